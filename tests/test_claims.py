"""The claims table (mjx_curio/analysis/claims/): each claim's verdict on synthetic sweeps with
a planted effect (and without it), and the whole table on the session's tiny sweeps. The tests
the claims use are checked in test_significance.py."""

import dataclasses
import itertools
import math
import pathlib

import numpy as np
import pytest

from mjx_curio import analysis as an
from mjx_curio.analysis import claims as cl
from mjx_curio.analysis.self_model import STEP_METRICS, action_baseline_moments, step_tracking
from mjx_curio.arena import ACTIONS, AGENT_NAMES, OBJECTS
from mjx_curio.metrics import SCHEMA, VIEW_TARGETS

# ------------------------------------------------------------------------------ synthetic sweeps


def fake_sweep(name, n_agents, groups, n_windows, seeds=3, walls="same", preset="none", every=20, first_seed=0,
               z="sample"):
    """A `Sweep` built in memory: `groups` = [(policy, setting value)], `seeds` runs each (seeds
    `first_seed` on), latents `z`, every metric of the schema zero (floats: zero too) until a test
    sets it."""
    runs = []
    for policy, value in groups:
        for seed in range(first_seed, first_seed + seeds):
            setting = an.SETTINGS[policy][0]
            row = dict(index=len(runs), name=f"{policy}-{value:g}-s{seed}", policy=policy, seed=seed, eps=0.2,
                       temperature=1.5, ucb_c=1.0)
            row[setting] = value
            runs.append(row)
    manifest = {"format": an.FORMAT, "runs": runs, "n_agents": n_agents, "agent_names": list(AGENT_NAMES[:n_agents]),
                "actions": list(ACTIONS), "objects": list(OBJECTS), "view_targets": list(VIEW_TARGETS),
                "metrics": {"every": every, "windows": n_windows},
                "config": {"walls": walls, "preset": preset, "seeds": seeds, "first_seed": first_seed},
                "run_config": {"image": 16, "learner": {"z": z}}}
    metrics = {k: np.zeros((len(runs), n_windows) + m.shape(n_agents), m.dtype) for k, m in SCHEMA.items()}
    metrics["steps_taken"][:] = every
    metrics["action_counts"][..., 0] = every
    steps = (np.arange(n_windows) + 1) * every
    return an.Sweep(pathlib.Path(name), manifest, {"windows_done": n_windows}, steps, metrics)


POLICIES = [("eps", 0.2), ("boltzmann", 1.5), ("ucb", 1.0)]
# The claims, in the table's order.
KEYS = ["1", "2", "3", "4", "5", "6a", "6b", "6c", "7", "8", "9", "10", "11", "12", "13", "14", "15"]


def test_assign_presets_by_settings_name_and_manifest():
    multi = fake_sweep("multi", 2, POLICIES + [("boltzmann", 0.5)], 4)
    single = fake_sweep("single", 1, [("eps", 0.2), ("ucb", 1.0)], 4)
    walls = fake_sweep("whatever", 1, [("eps", 0.2)], 4, walls="different", preset="single_agent_walls_different")
    got = cl.assign_presets([multi, single, walls])
    assert got == {"single_agent": single, "single_agent_walls_different": walls, "multi_agent": multi,
                   "boltzmann_temperatures": multi}
    # A dict key naming a preset wins over the settings.
    assert cl.assign_presets({"multi_agent_walls_different": multi}) == {"multi_agent_walls_different": multi}
    # Temperatures below 0.5 stand for the low-temperature preset, not the paper's; a recorded preset
    # wins over a name that sorts first.
    low = fake_sweep("low", 2, [("boltzmann", t) for t in (0.005, 0.05)], 4)
    got = cl.assign_presets([low])
    assert got["boltzmann_low_temperatures"] is low and "boltzmann_temperatures" not in got
    paper = fake_sweep("b", 2, [("boltzmann", t) for t in (0.5, 2.5)], 4, preset="boltzmann_temperatures")
    low_named = fake_sweep("a", 2, [("boltzmann", t) for t in (0.005, 0.05)], 4, preset="boltzmann_low_temperatures")
    assert cl.assign_presets([low_named, paper]) == {"boltzmann_temperatures": paper,
                                                     "boltzmann_low_temperatures": low_named}


def test_one_experiments_seeds_from_several_sweeps_merge_into_one():
    a = fake_sweep("multi_agent", 2, POLICIES, 6, seeds=3, preset="multi_agent")
    b = fake_sweep("more", 2, POLICIES, 5, seeds=5, preset="multi_agent", first_seed=3)
    for s, offset in ((a, 0.0), (b, 100.0)):
        s.metrics["curiosity"][:] = offset + np.arange(s.n_runs)[:, None, None]
    b.progress["halted"] = {"4": 60}
    merged = an.merge_sweeps([b, a])  # parts in order of their first seed, whatever the order given
    assert merged.parts == (a, b) and merged.n_runs == 24 and merged.n_windows == 5
    assert [g.n for g in merged.groups()] == [8, 8, 8]
    assert [merged.runs[i].seed for i in merged.groups()[0].indices] == list(range(8))
    np.testing.assert_array_equal(merged.metrics["curiosity"][:, 0, 0], np.r_[np.arange(9), 100 + np.arange(15)])
    assert merged.progress["halted"] == {"13": 60} and merged.steps_done == 100
    assert merged.manifest["config"]["seeds"] == 8 and merged.manifest["config"]["first_seed"] == 0
    assert merged.name == "multi_agent.seeds-0-7"  # named by its seeds, not its parts' directories
    with pytest.raises(an.SweepError, match="each keeps its own checkpoints"):
        merged.checkpoints()
    # A preset recorded by several sweeps is served by them merged; one sweep alone is itself.
    got = cl.assign_presets([a, b])
    assert got["multi_agent"].n_runs == 24 and cl.assign_presets([a])["multi_agent"] is a
    assert "(n=8)" in cl.claim_contact_ranking(got).statistic and "(n=3)" not in cl.claim_contact_ranking(got).statistic
    # Not one experiment: a setting the results depend on differs, or a run is repeated.
    c = fake_sweep("other", 2, POLICIES, 5, seeds=2, preset="multi_agent", first_seed=8)
    c.manifest["run_config"]["image"] = 32
    with pytest.raises(an.SweepError, match=r"differ in image \(32 against 16\)"):
        an.merge_sweeps([a, c])
    # A metric's meaning reworded between the parts is the same array; another dtype is not.
    entry = {"dtype": "float32", "dims": ["runs", "windows"], "unit": "m", "meaning": "where"}
    a.manifest["metrics"]["schema"] = {"x": entry}
    b.manifest["metrics"]["schema"] = {"x": {**entry, "meaning": "where (frozen once halted)"}}
    assert an.merge_sweeps([a, b]).n_runs == 24
    b.manifest["metrics"]["schema"] = {"x": {**entry, "dtype": "float16"}}
    with pytest.raises(an.SweepError, match="record different metrics"):
        an.merge_sweeps([a, b])
    # A metric only one part records (added to the sweeps between them) is left out of the merge.
    b.manifest["metrics"]["schema"] = {"x": entry, "rotation_reversals": entry}
    del a.metrics["rotation_reversals"]
    merged = an.merge_sweeps([a, b])
    assert "rotation_reversals" not in merged.metrics and set(merged.manifest["metrics"]["schema"]) == {"x"}
    assert "curiosity" in merged.metrics
    for s in (a, b):
        del s.manifest["metrics"]["schema"]
    d = fake_sweep("again", 2, [("ucb", 1.0)], 5, seeds=1, preset="multi_agent", first_seed=2)
    with pytest.raises(an.SweepError, match="both ran UCB \\(c=1\\) with seed 2"):
        cl.assign_presets([a, d])


def test_join_seed_parts_merges_each_experiments_parts_and_keeps_the_rest_apart():
    a = fake_sweep("multi_agent", 2, POLICIES, 6, seeds=3, preset="multi_agent")
    single = fake_sweep("single_agent", 1, POLICIES, 6, seeds=3, preset="single_agent")
    b = fake_sweep("multi_agent.seeds-3-5", 2, POLICIES, 5, seeds=3, preset="multi_agent", first_seed=3)
    c = fake_sweep("multi_agent.seeds-6-7", 2, POLICIES, 6, seeds=2, preset="multi_agent", first_seed=6)
    rerun = fake_sweep("rerun", 2, [("ucb", 1.0)], 6, seeds=1, preset="multi_agent", first_seed=4)
    bigger = fake_sweep("bigger", 2, POLICIES, 6, seeds=3, preset="multi_agent", first_seed=8)
    bigger.manifest["run_config"]["image"] = 32
    for s in (a, b, c):
        s.metrics["curiosity"][:] = s.runs[0].seed + np.arange(s.n_runs)[:, None, None]
        s.manifest["config"]["steps"] = 120  # what the fakes lack for `describe`
    got = an.join_seed_parts([c, single, a, rerun, b, bigger])
    # One experiment's three parts stand where its first sweep stood, as one sweep of seeds 0-7.
    assert [s.name for s in got] == ["multi_agent.seeds-0-7", "single_agent", "rerun", "bigger"]
    merged = got[0]
    assert merged.parts == (a, b, c) and merged.n_runs == 24 and merged.n_windows == 5
    assert [g.n for g in merged.groups()] == [8, 8, 8]
    np.testing.assert_array_equal(merged.metrics["curiosity"][:9, 0, 0], np.arange(9))
    np.testing.assert_array_equal(merged.metrics["curiosity"][9:, 0, 0], np.r_[3 + np.arange(9), 6 + np.arange(6)])
    # A run repeated (UCB, seed 4) is a rerun, not more seeds; other settings are another experiment.
    assert got[1] is single and got[2] is rerun and got[3] is bigger
    lines = merged.describe().splitlines()
    assert lines[0].startswith("multi_agent.seeds-0-7, merged from 3 sweeps: 24 runs, 2 agents")
    assert "steps done 100 of 120" in lines[1] and "x 8" in lines[2]
    assert lines[3:] == [f"  part {s.path}: seeds {seeds}, steps done {steps}, checkpoints at steps: none"
                         for s, seeds, steps in ((a, "0, 1, 2", 120), (b, "3, 4, 5", 100), (c, "6, 7", 120))]
    # Parts named after seeds keep only the experiment's name; one sweep alone is itself.
    assert an.join_seed_parts([c, b])[0].name == "multi_agent.seeds-3-7"
    assert an.join_seed_parts([c, a])[0].name == "multi_agent.seeds-0-2+6-7"  # a gap is named, not bridged
    assert an.join_seed_parts([a, rerun])[0].name == "multi_agent.seeds-0-2+4"
    assert an.join_seed_parts([a]) == [a]
    assert an.experiment_name("multi_agent.order.seeds-3-5") == "multi_agent.order" == an.experiment_name(
        "multi_agent.order") and an.experiment_name("multi_agent.seeds-0-2+4") == "multi_agent"
    assert an.seeds_name("multi_agent.order.seeds-3-5", [5, 0, 1, 2, 4]) == "multi_agent.order.seeds-0-2+4-5"
    # A later part that records a metric added since joins the earlier ones, which lack it, and the
    # merge keeps what every part records; a metric recorded as another array keeps it apart.
    entry = {"dtype": "float32", "dims": ["runs", "windows"], "unit": "m"}
    a.manifest["metrics"]["schema"] = {"x": entry}
    b.manifest["metrics"]["schema"] = {"x": entry, "added": entry}
    c.manifest["metrics"]["schema"] = {"x": {**entry, "dtype": "float16"}}
    got = an.join_seed_parts([a, b, c])
    assert [s.name for s in got] == ["multi_agent.seeds-0-5", "multi_agent.seeds-6-7"] and got[1] is c
    assert got[0].parts == (a, b) and set(got[0].manifest["metrics"]["schema"]) == {"x"}


def test_pieces_of_one_grid_merge_over_the_keys_they_may_differ_in():
    # The paper's temperatures and low ones, the same seeds: one sweep over every temperature.
    paper = fake_sweep("boltzmann_temperatures", 2, [("boltzmann", t) for t in (0.5, 2.5)], 6,
                       preset="boltzmann_temperatures")
    low = fake_sweep("boltzmann_low_temperatures", 2, [("boltzmann", t) for t in (0.005, 0.05)], 4,
                     preset="boltzmann_low_temperatures")
    paper.manifest["config"]["temperature"], low.manifest["config"]["temperature"] = [0.5, 2.5], [0.005, 0.05]
    with pytest.raises(an.SweepError, match="differ in preset .*; temperature"):
        an.merge_sweeps([paper, low])
    both = an.merge_sweeps([paper, low], differ=("temperature", "preset"))
    assert both.name == "boltzmann_temperatures + boltzmann_low_temperatures" and both.n_windows == 4
    assert [g.value for g in sorted(both.groups("boltzmann"), key=lambda g: g.value)] == [0.005, 0.05, 0.5, 2.5]
    assert both.manifest["config"]["temperature"] == [0.005, 0.05, 0.5, 2.5]
    assert both.manifest["config"]["preset"] == ["boltzmann_temperatures", "boltzmann_low_temperatures"]
    # Seeds are shared across the pieces, so the blocked test sees all four temperatures per seed.
    late = cl.late_curiosity(both)
    gs = sorted(both.groups("boltzmann"), key=lambda g: g.value)
    assert cl.seed_table(both, gs, late).shape == (4, 3)


def test_missing_presets_make_every_row_not_testable_with_the_name():
    table = cl.claims_table({})
    assert [v["key"] for v in table.values] == KEYS
    for v in table.values:
        assert v["verdict"].startswith("not testable: the ") and "missing" in v["verdict"]
    assert "boltzmann_temperatures sweep is missing" in table.values[KEYS.index("7")]["verdict"]


def test_contact_ranking_finds_a_planted_order_and_rejects_its_reverse():
    rng = np.random.default_rng(0)
    s = fake_sweep("multi_agent", 2, POLICIES, 2000, seeds=4)  # 40,000 steps
    planted_obj = {"eps": 500, "boltzmann": 100, "ucb": 1000}  # total contact steps per run
    planted_agt = {"eps": 30, "boltzmann": 150, "ucb": 300}
    totals = {}
    for g in s.groups():
        for i in g.indices:
            obj = planted_obj[g.policy] + int(rng.integers(-20, 21))
            agt = planted_agt[g.policy] + int(rng.integers(-10, 11))
            s.metrics["contact_object"][i, :obj, 0, 2] = 1  # one contact step per window, agent 0, sphere
            s.metrics["contact_agent"][i, :agt, :] = 1  # both agents see each agent-agent contact
            totals.setdefault(g.policy, []).append((obj, agt))
    r = cl.claim_contact_ranking({"multi_agent": s})
    assert r.verdict.startswith("holds"), r.verdict
    for p, rows in totals.items():
        assert r.values[f"objects {p}"] == pytest.approx(np.mean([o for o, _ in rows]))
        assert r.values[f"agent-agent {p}"] == pytest.approx(np.mean([a for _, a in rows]))
    # UCB and eps swapped: UCB is no longer the most in touch with objects.
    swap = {0: 2, 1: 1, 2: 0}
    order = np.concatenate([s.groups()[swap[k]].indices for k in range(3)])
    s.metrics["contact_object"][:] = s.metrics["contact_object"][order]
    r = cl.claim_contact_ranking({"multi_agent": s})
    assert r.verdict.startswith("does not hold") and "objects UCB > ε" in r.verdict, r.verdict


def test_temperatures_anova_on_planted_late_curiosity():
    s = fake_sweep("boltzmann_temperatures", 2, [("boltzmann", t) for t in (0.5, 1.5, 2.5)], 2000, seeds=3)
    late = np.array([1, 2, 3, 4, 5, 6, 7, 8, 9], float)  # the ANOVA of test_one_way_anova_by_hand
    s.metrics["curiosity"][:] = 5.0  # the first three quarters: anything
    s.metrics["curiosity"][:, 1500:, :] = late[:, None, None]
    r = cl.claim_temperatures_alike({"boltzmann_temperatures": s})
    assert r.values["F"] == pytest.approx(27.0) and r.values["p"] == pytest.approx(1e-3)
    assert r.verdict.startswith("does not hold"), r.verdict
    s.metrics["curiosity"][:, 1500:, :] = np.array([1, 2, 3, 2, 1, 3, 3, 2, 1], float)[:, None, None]
    r = cl.claim_temperatures_alike({"boltzmann_temperatures": s})
    assert r.values["F"] == pytest.approx(0.0) and r.verdict.startswith("holds"), r.verdict
    # Each seed at its own level, the temperatures 0.01 apart within every seed: the one-way test
    # sees no difference, the test blocked by seed does, and it sets the verdict.
    for t, g in enumerate(sorted(s.groups("boltzmann"), key=lambda g: g.value)):
        for i in g.indices:
            s.metrics["curiosity"][i, 1500:, :] = s.runs[i].seed + 0.01 * t + 0.001 * (s.runs[i].seed == t)
    r = cl.claim_temperatures_alike({"boltzmann_temperatures": s})
    assert r.values["p"] > 0.5 and r.values["p_blocked"] < 0.05, r.values
    assert r.verdict.startswith("does not hold") and "blocked by seed (3 seeds" in r.statistic, r.verdict
    # The equivalence bound beside it: temperatures 0.02 apart at most, a residual of 0.001 (I - 1/3)
    # (sum of squares 2e-6 on 4 degrees of freedom), so 0.02 + t(0.95, 4) sqrt(2 x 5e-7 / 3) (the
    # metrics are float32: to 1e-6).
    assert r.values["largest_difference"] == pytest.approx(0.02, abs=1e-6)
    assert r.values["equivalence_bound"] == pytest.approx(0.02 + 2.131847 * math.sqrt(2 * 5e-7 / 3), abs=1e-6)
    assert "rule out differences beyond ±0.0212" in r.statistic, r.statistic
    # Temperatures that ran different seeds form no block: the one-way test decides.
    s.metrics["curiosity"][:, 1500:, :] = late[:, None, None]
    hot = max(s.groups("boltzmann"), key=lambda g: g.value)
    for i in hot.indices:
        s.runs[i] = dataclasses.replace(s.runs[i], seed=s.runs[i].seed + 10)
    r = cl.claim_temperatures_alike({"boltzmann_temperatures": s})
    assert "blocked" not in r.statistic and r.values["p"] == pytest.approx(1e-3), r.statistic
    assert r.verdict == "does not hold: the temperatures differ (p=0.001)", r.verdict
    short = fake_sweep("boltzmann_temperatures", 2, [("boltzmann", t) for t in (0.5, 1.5)], 100, seeds=2)
    r = cl.claim_temperatures_alike({"boltzmann_temperatures": short})
    assert r.verdict.startswith("not testable at this scale (needs runs of >= 40,000 steps"), r.verdict


def test_temperature_table_on_planted_runs():
    # Three temperatures, 3 seeds, 10 windows of 14 steps, two agents. Actions: at T = 0.01 one
    # action only (entropy 0, top share 1), at T = 0.1 every action twice a window (entropy 1, top
    # share 1/7), at T = 1 two actions 7 times each (entropy ln 2 / ln 7, top share 1/2). Object
    # contacts: run i touches on i + 1 steps of its first window, per agent.
    s = fake_sweep("boltzmann_low_temperatures", 2, [("boltzmann", t) for t in (0.01, 0.1, 1.0)], 10, seeds=3,
                   every=14)
    ac = s.metrics["action_counts"]
    ac[:] = 0
    ac[0:3, ..., 0] = 14
    ac[3:6] = 2
    ac[6:9, ..., 0] = ac[6:9, ..., 1] = 7
    for i in range(9):
        s.metrics["contact_object"][i, 0, :, 0] = i + 1
    late = np.array([1.0, 2, 3, 2, 3, 4, 3, 4, 6])  # per run; seed s adds s, T adds its index
    # Floor: run i's first agent steps 0.3 m along x every window for its first i + 2 windows, then
    # stays (i + 2 squares of 0.25 m, the last position repeated); the second agent never moves (1).
    pose = s.metrics["agent_pose"]
    for i in range(9):
        pose[i, :, 0, 0] = 0.3 * np.minimum(np.arange(10), i + 1) + 0.01
    s.metrics["curiosity"][:] = 9.0
    s.metrics["curiosity"][:, -3:, :] = late[:, None, None]  # the last quarter of 10 windows: 3
    t = an.temperature_table(s)
    assert [r[0] for r in t.rows] == ["0.01", "0.1", "1", "across T, blocked by seed"]
    v = t.values
    assert [r["action_entropy"] for r in v[:3]] == pytest.approx([0.0, 1.0, math.log(2) / math.log(7)])
    assert [r["top_share"] for r in v[:3]] == pytest.approx([1.0, 1 / 7, 0.5])
    per_run = 1000 * 2 * (np.arange(9) + 1) / (10 * 14 * 2)  # both agents touch; 280 agent-steps a run
    assert [r["object_contacts"] for r in v[:3]] == pytest.approx(per_run.reshape(3, 3).mean(axis=1))
    assert [r["late_curiosity"] for r in v[:3]] == pytest.approx(late.reshape(3, 3).mean(axis=1))
    floor = ((np.arange(9) + 2 + 1) / 2).reshape(3, 3).mean(axis=1)  # mean of the agents' squares
    assert [r["floor_cells"] for r in v[:3]] == pytest.approx(floor)
    want = an.block_anova(late.reshape(3, 3))
    assert (v[3]["late_curiosity F"], v[3]["late_curiosity p"]) == (pytest.approx(want["F"]), pytest.approx(want["p"]))
    assert t.rows[3][2] == f"F(2, 4) = {want['F']:.3g}, p = {want['p']:.3g}" and t.rows[3][1] == "3 seeds"
    assert len({tuple(r) for r in v}) == 1  # every row has the same keys: the CSV can be written
    assert t.to_csv().count("\n") == 5
    with pytest.raises(an.SweepError, match="no Boltzmann runs"):
        an.temperature_table(fake_sweep("eps", 2, [("eps", 0.2)], 4))
    # The same measures per policy: one row a group, the temperature table's rows without the test.
    p = an.policy_measures_table(s)
    assert [r[0] for r in p.rows] == [g.label for g in s.groups()] and len(p.rows) == 3
    assert [r[1:] for r in p.rows] == [r[1:] for r in t.rows[:3]]
    for got, want in zip(p.values, v[:3]):
        assert {k: x for k, x in got.items() if k != "policy"} == pytest.approx(
            {k: x for k, x in want.items() if k != "T"}, nan_ok=True)
    eps = an.policy_measures_table(fake_sweep("eps", 2, [("eps", 0.2), ("ucb", 1.0)], 4))
    assert [r[0] for r in eps.rows] == ["ε-greedy (ε=0.2)", "UCB (c=1)"]


def test_seed_coupling_on_planted_actions_and_curiosity():
    # Two temperatures, 3 seeds, 8 windows. Each seed's action counts are its own (seed s takes
    # action 1 on s + 1 steps a window); at T = 2.5 the second half of the windows move one step to
    # action 2, so runs of one seed agree on exactly half the windows and runs of different seeds
    # on none. Curiosity: rows of a Hadamard matrix per seed (zero mean, mutually orthogonal),
    # scaled and shifted by temperature: r = 1 within a seed, 0 across seeds.
    s = fake_sweep("boltzmann_temperatures", 2, [("boltzmann", t) for t in (0.5, 2.5)], 8, seeds=3)
    hadamard = np.array([[1, -1, 1, -1, 1, -1, 1, -1], [1, 1, -1, -1, 1, 1, -1, -1], [1, -1, -1, 1, 1, -1, -1, 1]])
    lo, hi = sorted(s.groups("boltzmann"), key=lambda g: g.value)
    for g in (lo, hi):
        for i in g.indices:
            seed = s.runs[i].seed
            s.metrics["action_counts"][i, :, :, 0] = 20 - (seed + 1)
            s.metrics["action_counts"][i, :, :, 1] = seed + 1
            s.metrics["curiosity"][i] = (0.5 + g.value * hadamard[seed])[:, None]
    for i in hi.indices:
        s.metrics["action_counts"][i, 4:, :, 0] -= 1
        s.metrics["action_counts"][i, 4:, :, 2] += 1
    c = cl.seed_coupling(s, lo, hi)
    assert c["same"]["identical"] == [0.5, 0.5, 0.5]
    assert c["other"]["identical"] == [0.0] * 6
    assert c["same"]["r"] == pytest.approx([1.0] * 3)
    assert c["other"]["r"] == pytest.approx([0.0] * 6, abs=1e-12)
    # One agent of seed 1 acting differently in every window halves that pair's share.
    j = hi.indices[1]
    s.metrics["action_counts"][j, :, 1, 3] += 1
    s.metrics["action_counts"][j, :, 1, 0] -= 1
    assert cl.seed_coupling(s, lo, hi)["same"]["identical"] == [0.5, 0.25, 0.5]


def test_agents_move_together_against_other_runs():
    rng = np.random.default_rng(1)
    s = fake_sweep("multi_agent", 2, POLICIES, 600, seeds=3)  # 12,000 steps
    walks = np.cumsum(rng.normal(size=(s.n_runs, 600)), axis=1)  # each run its own course of events
    s.metrics["curiosity"][:] = (walks[:, :, None] + 0.1 * rng.normal(size=(s.n_runs, 600, 2))).astype(np.float32)
    d = cl.agent_curiosity_coupling(s)
    assert np.all(np.tanh(d["within"]) > 0.99)
    r = cl.claim_agents_move_together({"multi_agent": s})
    assert r.verdict.startswith("holds"), r.verdict
    assert "Context" not in r.statistic
    # A z=mean side experiment is read as context, with its own numbers, and leaves the verdict be.
    side = fake_sweep("multi_agent.z_mean", 2, [("eps", 0.2)], 600, seeds=3, z="mean")
    side.metrics["curiosity"][:, :, 0] = np.cumsum(rng.normal(size=(3, 600)), axis=1)
    side.metrics["curiosity"][:, :, 1] = np.cumsum(rng.normal(size=(3, 600)), axis=1)
    both = cl.claim_agents_move_together({"multi_agent": s, "multi_agent.z_mean": side})
    assert both.verdict == r.verdict and "Context, not the verdict: multi_agent.z_mean" in both.statistic
    assert both.values["multi_agent.z_mean diff"] == pytest.approx(
        float(np.mean(cl.agent_curiosity_coupling(side)["diff"])))
    # Agent 1 of each run on a course of its own: no closer to agent 0 than agents of other runs are.
    s.metrics["curiosity"][:, :, 1] = np.cumsum(rng.normal(size=(s.n_runs, 600)), axis=1)
    r = cl.claim_agents_move_together({"multi_agent": s})
    assert r.verdict.startswith("does not hold"), r.verdict


def test_dip_and_rise_found_when_planted_not_in_noise():
    rng = np.random.default_rng(2)
    s = fake_sweep("multi_agent", 2, POLICIES, 4000, seeds=4)  # 80,000 steps
    steps = s.steps - 10
    shape = np.where(steps < 5_000, 1.0, np.where(steps < 30_000, 0.55, 0.55 + 0.1 * (steps - 30_000) / 50_000))
    noise = lambda: 0.05 * rng.normal(size=s.metrics["curiosity"].shape)  # noqa: E731
    s.metrics["curiosity"][:] = shape[None, :, None] + noise()
    d = cl.curiosity_fall_rise(s, s.groups("eps")[0])
    assert d["fall"] == pytest.approx(np.full(4, 0.45), abs=0.01)
    assert d["rise"] == pytest.approx(np.full(4, 0.1 * 0.9), abs=0.01)  # late block: steps 70k-80k
    r = cl.claim_curiosity_dip_and_rise({"multi_agent": s})
    assert r.verdict.startswith("holds"), r.verdict
    s.metrics["curiosity"][:] = 0.6 + noise()  # flat
    r = cl.claim_curiosity_dip_and_rise({"multi_agent": s})
    assert r.verdict.startswith("does not hold"), r.verdict


def test_curiosity_parts_put_a_planted_rise_in_the_spread_not_the_error():
    """Curiosity = error + spread with the error falling and flat after the trough and the
    spread rising late: the parts' table gives the rise to the spread (share ~100 %, its CI above
    0) and none to the error (its CI around 0), the fall to the error, and the curiosity's own
    fall and rise as `curiosity_fall_rise` has them. A z=mean sweep's curiosity is one part, the
    error. A sweep made before sweeps recorded the spread has no rows and no parts."""
    rng = np.random.default_rng(3)
    s = fake_sweep("single_agent.spread", 1, [("eps", 0.2)], 2000, seeds=6)  # 40,000 steps
    steps = s.steps - 10
    error = np.where(steps < 5_000, 0.6, 0.2)
    spread = np.where(steps < 30_000, 0.3, 0.4)
    noise = lambda: 0.02 * rng.normal(size=s.metrics["curiosity"].shape)  # noqa: E731
    s.metrics["curiosity_spread"][:] = spread[None, :, None] + noise()
    s.metrics["curiosity"][:] = s.metrics["curiosity_spread"] + error[None, :, None] + noise()
    g = s.groups("eps")[0]
    d = an.parts_fall_rise(s, g)
    np.testing.assert_array_equal(d["curiosity"]["rise"], cl.curiosity_fall_rise(s, g)["rise"])
    np.testing.assert_allclose(d["error"]["rise"], d["curiosity"]["rise"] - d["spread"]["rise"], atol=1e-12)
    table = an.curiosity_parts_table({"single_agent.spread": s})
    rows = {v["part"]: v for v in table.values}
    assert list(rows) == list(an.PARTS) and [r[0] for r in table.rows] == ["`single_agent.spread`"] * 3
    assert rows["curiosity"]["rise"] == pytest.approx(0.1, abs=0.01) and rows["spread"]["rise_low"] > 0.09
    assert rows["spread"]["rise_share"] == pytest.approx(1.0, abs=0.1)
    assert rows["error"]["rise_low"] < 0 < rows["error"]["rise_high"]
    assert rows["error"]["fall"] == pytest.approx(0.4, abs=0.01) and rows["spread"]["fall_share"] == pytest.approx(0, abs=0.05)
    assert rows["spread"]["early"] == pytest.approx(0.3, abs=0.01) and rows["spread"]["late"] == pytest.approx(0.4, abs=0.01)
    # Under z=mean the latent is the posterior mean: the spread recorded is 0 and the curiosity is
    # all error, one row a group, named so.
    m = fake_sweep("single_agent.z_mean", 1, [("eps", 0.2)], 2000, seeds=6, z="mean")
    m.metrics["curiosity"][:] = error[None, :, None] + noise()
    both = an.curiosity_parts_table({"single_agent.spread": s, "single_agent.z_mean": m})
    assert an.samples_latent(s) and not an.samples_latent(m)
    assert [(r[0], r[3]) for r in both.rows[3:]] == [("`single_agent.z_mean`", an.MEAN_LATENT_PART["curiosity"])]
    assert both.values[3]["fall"] == pytest.approx(0.4, abs=0.01) and both.values[3]["fall_share"] == 1.0
    assert "z=mean" in both.note and "z=mean" not in table.note
    del s.metrics["curiosity_spread"]
    assert not an.records_spread(s) and an.curiosity_parts_table({"single_agent": s}).rows == []
    with pytest.raises(ValueError, match="curiosity_spread"):
        an.curiosity_parts(s, g)


def test_agents_parts_compare_each_part_over_claim_3s_window_policy_by_policy():
    # One agent ran 40,000 steps of eps and UCB, two agents 30,000 of eps: only eps pairs, over
    # steps 15,000-30,000. Planted: a second agent doubles the error and lowers the spread, so the
    # curiosity as a whole hardly moves; outside the window the spread is far off, to show it is
    # not read. A z=mean sweep (no spread in its curiosity) is left out.
    rng = np.random.default_rng(11)
    one = fake_sweep("single_agent.spread", 1, [("eps", 0.2), ("ucb", 1.0)], 2000, seeds=4)
    two = fake_sweep("multi_agent.spread", 2, [("eps", 0.2)], 1500, seeds=5)
    mean_latent = fake_sweep("multi_agent.z_mean", 2, [("eps", 0.2)], 1500, seeds=5, z="mean")
    truth = {}
    for s, error, spread in ((one, 0.05, 0.40), (two, 0.10, 0.35)):
        shape = s.metrics["curiosity"].shape
        inside = (s.steps > 15_000) & (s.steps <= 30_000)
        s.metrics["curiosity_spread"][:] = np.where(inside, spread, 9.0)[None, :, None] + 0.01 * rng.normal(size=shape)
        run_error = error + 0.01 * rng.normal(size=(shape[0], 1, 1))
        s.metrics["curiosity"][:] = s.metrics["curiosity_spread"] + run_error + 0.01 * rng.normal(size=shape)
        g = s.groups("eps")[0]
        c = s.metrics["curiosity"][g.indices][:, inside].astype(float).mean(axis=2)  # the metrics are float32
        v = s.metrics["curiosity_spread"][g.indices][:, inside].astype(float).mean(axis=2)
        truth[s.n_agents] = {"curiosity": c.mean(1), "spread": v.mean(1), "error": (c - v).mean(1)}
    t = an.agents_parts_table({"single_agent.spread": one, "multi_agent.spread": two, "multi_agent.z_mean": mean_latent})
    assert [(v["group"], v["part"]) for v in t.values] == [("ε-greedy (ε=0.2)", p) for p in an.PARTS]
    assert {(v["from"], v["to"]) for v in t.values} == {(15_000, 30_000)} and "steps 15,000-30,000" in t.note
    for v in t.values:
        a, b = truth[1][v["part"]], truth[2][v["part"]]
        assert v["one_mean"] == pytest.approx(a.mean(), abs=1e-9) and v["two_mean"] == pytest.approx(b.mean(), abs=1e-9)
        assert v["diff"] == pytest.approx(b.mean() - a.mean(), abs=1e-9)
        se = math.sqrt(a.var(ddof=1) / len(a) + b.var(ddof=1) / len(b))
        assert v["t"] == pytest.approx((b.mean() - a.mean()) / se, rel=1e-9)
    rows = {v["part"]: v for v in t.values}
    assert rows["error"]["diff"] == pytest.approx(0.05, abs=0.02) and rows["error"]["p"] < 0.001
    assert rows["spread"]["diff"] == pytest.approx(-0.05, abs=0.01) and rows["spread"]["p"] < 0.001
    assert abs(rows["curiosity"]["diff"]) < 0.03
    assert t.rows[0][:2] == ["`single_agent.spread` / `multi_agent.spread`", "ε-greedy (ε=0.2)"]
    # Without a two-agent sweep that samples its latents and records the spread: no rows.
    assert an.agents_parts_table({"single_agent.spread": one, "multi_agent.z_mean": mean_latent}).rows == []


def test_two_agents_higher_compares_the_same_steps_when_one_sweep_is_longer():
    # Curiosity and loss drift upward with training alike for one and two agents; the two-agent
    # sweep ran 20,000 steps, the one-agent sweep 15,000. Only the common steps are comparable.
    rng = np.random.default_rng(5)
    single = fake_sweep("single_agent", 1, POLICIES, 750, seeds=4)
    multi = fake_sweep("multi_agent", 2, POLICIES, 1000, seeds=4)
    for s in (single, multi):
        drift = s.steps / 10_000
        s.metrics["curiosity"][:] = drift[None, :, None] + 0.01 * rng.normal(size=s.metrics["curiosity"].shape)
        s.metrics["vae_loss"][:] = s.n_agents * 100 * drift[None, :] + rng.normal(size=s.metrics["vae_loss"].shape)
    r = cl.claim_two_agents_higher({"single_agent": single, "multi_agent": multi})
    assert "steps 7,500-15,000" in r.statistic
    assert r.values["curiosity multi"] == pytest.approx(r.values["curiosity single"], abs=0.01)
    assert r.verdict.startswith("does not hold"), r.verdict
    multi.metrics["curiosity"][:] += 0.2  # a real two-agent excess, in loss too
    multi.metrics["vae_loss"][:] += 2 * 20
    r = cl.claim_two_agents_higher({"single_agent": single, "multi_agent": multi})
    assert r.verdict.startswith("holds"), r.verdict


def test_two_agent_vae_unsettled_on_planted_volatility():
    # The loss per image is a flat 100 plus noise of sd 4 a window with one agent. With two agents
    # the recorded loss sums both views (eq. 5), and its per-image mean over twice the views is
    # steadier by sqrt(2) when the views vary independently: the same volatility once scaled.
    rng = np.random.default_rng(11)
    single = fake_sweep("single_agent", 1, POLICIES, 1000, seeds=6)
    multi = fake_sweep("multi_agent", 2, POLICIES, 1000, seeds=6)
    single.metrics["vae_loss"][:] = 100 + 4 * rng.normal(size=single.metrics["vae_loss"].shape)
    per_image = 100 + 4 / math.sqrt(2) * rng.normal(size=multi.metrics["vae_loss"].shape)
    multi.metrics["vae_loss"][:] = 2 * per_image
    g = cl.paper_group(multi, "ucb")
    d = cl.vae_volatility(multi, g, 10_000, 20_000)
    x = per_image[g.indices].astype(np.float32).astype(float)
    resid = x - an.moving_average(x, 50, axis=1)
    np.testing.assert_allclose(d["per_image"], resid[:, 500:].std(axis=1, ddof=1), rtol=1e-4)
    np.testing.assert_allclose(d["scaled"], d["per_image"] * math.sqrt(2))
    halves = x[:, 500:750].mean(axis=1), x[:, 750:].mean(axis=1)
    np.testing.assert_allclose(d["late_change"], (halves[1] - halves[0]) / halves[0], rtol=1e-4)
    # The residual around a 50-window trailing mean of white noise has sd ~ 4 * sqrt(1 - 1/50).
    assert np.mean(d["scaled"]) == pytest.approx(4 * math.sqrt(1 - 1 / 50), rel=0.05)
    presets = {"single_agent": single, "multi_agent": multi}
    r = cl.claim_two_agent_vae_unsettled(presets)
    assert r.key == "14" and "steps 10,000-20,000" in r.statistic
    assert r.values["per_image multi"] < r.values["per_image single"] and r.values["per_image p"] < 0.001
    assert r.verdict.startswith("does not hold: the two-agent loss is not significantly more volatile"), r.verdict
    # Fluctuation beyond the batch size: the two-agent loss per image as noisy as one agent's.
    multi.metrics["vae_loss"][:] = 2 * (100 + 4 * rng.normal(size=multi.metrics["vae_loss"].shape))
    r = cl.claim_two_agent_vae_unsettled(presets)
    assert r.verdict == "holds (Welch p < 0.05, multi > single)", r.verdict
    assert r.values["scaled multi"] == pytest.approx(math.sqrt(2) * r.values["scaled single"], rel=0.05)
    # Short runs, different image sizes, or no UCB runs: not testable.
    short = fake_sweep("multi_agent", 2, POLICIES, 400)
    assert cl.claim_two_agent_vae_unsettled({"single_agent": single, "multi_agent": short}).verdict.startswith(
        "not testable at this scale")
    big = fake_sweep("multi_agent", 2, POLICIES, 1000, seeds=6)
    big.manifest["run_config"]["image"] = 32
    assert "differ in image size" in cl.claim_two_agent_vae_unsettled({"single_agent": single,
                                                                        "multi_agent": big}).verdict
    no_ucb = fake_sweep("multi_agent", 2, POLICIES[:2], 1000)
    assert "multi_agent has no UCB runs" in cl.claim_two_agent_vae_unsettled(
        {"single_agent": single, "multi_agent": no_ucb}).verdict


def test_running_action_baseline_recovers_per_action_means():
    rng = np.random.default_rng(3)
    counts = rng.multinomial(20, np.full(7, 1 / 7), size=(2, 300, 2)).astype(np.int32)  # [R, W, A, actions]
    m_true = np.linspace(0.2, 0.8, 7)
    cur = (counts / 20.0) @ m_true  # every window's curiosity is its action mix times the per-action means
    base = cl.running_action_baseline(cur, counts, history=50, ridge=1e-9)
    assert np.all(np.isnan(base[:, 0]))
    np.testing.assert_allclose(base[:, 20:], cur[:, 20:], rtol=1e-5)


def test_self_model_claim_on_planted_predictions():
    rng = np.random.default_rng(4)
    s = fake_sweep("multi_agent", 2, POLICIES, 1200, seeds=1)  # 24,000 steps, 3 runs
    shape = s.metrics["curiosity"].shape
    cur = 0.6 + 0.1 * rng.normal(size=shape)
    s.metrics["curiosity"][:] = cur
    s.metrics["action_counts"][:] = rng.multinomial(20, np.full(7, 1 / 7), size=shape)  # unrelated to curiosity
    pred = 0.6 + 0.1 * rng.normal(size=shape)  # early: knows nothing
    pred[:, 400:] = cur[:, 400:] + 0.02 * rng.normal(size=(3, 800, 2))  # later: knows the outcome
    s.metrics["predicted"][:] = pred
    for name in STEP_METRICS:  # a sweep made before the window moments: window means only
        del s.metrics[name]
    d = cl.self_model_tracking(s)
    assert np.all(np.abs(np.tanh(d["self_early"])) < 0.2) and np.all(np.tanh(d["self_late"]) > 0.95)
    assert np.all(np.abs(np.tanh(d["base_late"])) < 0.2)
    r = cl.claim_self_model_predicts({"multi_agent": s})
    assert r.verdict.startswith("holds"), r.verdict
    assert "window means detrended" in r.statistic and "only window means are compared" in r.statistic


def _step_windows(s, every, c, q, a):
    """Fill a fake sweep's window metrics from per-step values [runs, steps, agents] as a sweep
    records them (every step taken)."""
    r, t, n_agents = c.shape
    win = lambda x: x.reshape(r, t // every, every, *x.shape[2:])  # noqa: E731
    cw, qw, aw = win(c), win(q), win(a)
    took = aw[..., None] == np.arange(7)  # [R, W, w, agents, 7]
    counts = took.sum(axis=2)
    s.metrics["curiosity"][:] = cw.mean(axis=2)
    s.metrics["predicted"][:] = qw.mean(axis=2)
    s.metrics["predicted_var"][:] = qw.var(axis=2)
    s.metrics["curiosity_var"][:] = cw.var(axis=2)
    s.metrics["predicted_curiosity_cov"][:] = ((qw - qw.mean(axis=2, keepdims=True))
                                               * (cw - cw.mean(axis=2, keepdims=True))).mean(axis=2)
    with np.errstate(invalid="ignore"):
        s.metrics["curiosity_by_action"][:] = (cw[..., None] * took).sum(axis=2) / counts
    s.metrics["action_counts"][:] = counts


def _pooled_within(x, y, every):
    """The Pearson correlation of per-step values [steps] after each window's mean is taken out."""
    x, y = x.reshape(-1, every), y.reshape(-1, every)
    x, y = x - x.mean(axis=1, keepdims=True), y - y.mean(axis=1, keepdims=True)
    return (x * y).sum() / np.sqrt((x * x).sum() * (y * y).sum())


def test_per_step_tracking_is_the_within_window_correlation_of_the_steps():
    rng = np.random.default_rng(6)
    every, n_w, history = 10, 30, 4
    s = fake_sweep("multi_agent", 2, POLICIES, n_w, seeds=1, every=every)
    shape = (3, n_w * every, 2)
    a = rng.integers(0, 7, shape)
    trend = np.linspace(0.8, 0.4, n_w * every)[None, :, None]  # shared by every curve: windows take it out
    c = trend + 0.05 * a + 0.1 * rng.normal(size=shape)  # curiosity depends on the action, and on chance
    q = trend + 0.5 * (c - trend) + 0.1 * rng.normal(size=shape)  # the self-model sees some of it
    _step_windows(s, every, c, q, a)
    d = step_tracking(s, history=history)
    third = n_w // 3
    first, last = slice(0, third * every), slice((n_w - third) * every, n_w * every)
    z = lambda f: np.mean([np.arctanh(f(i, j)) for j in range(2)])  # noqa: E731
    for i in range(3):
        assert d["self_early"][i] == pytest.approx(z(lambda i, j: _pooled_within(q[i, first, j], c[i, first, j], every)))
        assert d["self_late"][i] == pytest.approx(z(lambda i, j: _pooled_within(q[i, last, j], c[i, last, j], every)))

        def baseline_r(i, j):  # each step predicted by its action's running mean, step by step
            b = np.empty(n_w * every)
            for w in range(n_w):
                seen = slice(max(w - history, 0) * every, w * every)
                ca, aa = c[i, seen, j], a[i, seen, j]
                prior = ca.mean() if ca.size else 0.0
                for t in range(w * every, (w + 1) * every):
                    mine = ca[aa == a[i, t, j]]
                    b[t] = (mine.sum() + prior) / (mine.size + 1)
            return _pooled_within(b[last], c[i, last, j], every)

        assert d["base_late"][i] == pytest.approx(z(baseline_r))
    assert np.all(d["edge"] == d["self_late"] - d["base_late"])
    # The first window has seen nothing: no baseline there, and the early third's windows still count.
    n_var_b, _ = action_baseline_moments(s.metrics["action_counts"], s.metrics["curiosity_by_action"], history)
    assert np.isnan(n_var_b[:, 0]).all() and np.isfinite(n_var_b[:, 1:]).all()


def test_tracking_over_time_pools_each_bin_of_steps():
    rng = np.random.default_rng(8)
    every, n_w = 10, 30
    s = fake_sweep("multi_agent", 2, POLICIES, n_w, seeds=2, every=every)
    shape = (6, n_w * every, 2)
    a = rng.integers(0, 7, shape)
    c = 0.5 + 0.1 * rng.normal(size=shape)
    q = c * np.linspace(0, 1, n_w * every)[None, :, None] + 0.1 * rng.normal(size=shape)  # learns as it goes
    _step_windows(s, every, c, q, a)
    steps, r_self, r_base = an.tracking_over_time(s, "ucb", every=100)
    assert steps.tolist() == [100, 200, 300] and r_self.shape == r_base.shape == (2, 3)
    for k, i in enumerate(s.group("ucb").indices):
        for b in range(3):
            part = slice(b * 100, (b + 1) * 100)
            want = np.tanh(np.mean([np.arctanh(_pooled_within(q[i, part, j], c[i, part, j], every)) for j in range(2)]))
            assert r_self[k, b] == pytest.approx(want)
    assert r_self[:, 0].mean() < 0.3 < 0.6 < r_self[:, 2].mean()
    assert np.all(np.abs(r_base[:, 1:]) < 0.3)  # the action tells nothing of the curiosity here


def _knows_late(name):
    """Three runs of 24,000 steps whose self-models know nothing for the first third, then each
    step's outcome, while every window's mean prediction stays the same."""
    rng = np.random.default_rng(7)
    s = fake_sweep(name, 2, POLICIES, 1200, seeds=1, preset="multi_agent")
    shape = (3, 1200 * 20, 2)
    a = rng.integers(0, 7, shape)
    c = 0.6 + 0.1 * rng.normal(size=shape)
    q = 0.6 + 0.1 * rng.normal(size=shape)  # early: knows nothing
    q[:, 8000:] = c[:, 8000:] + 0.05 * rng.normal(size=(3, 16000, 2))  # later: knows each step's outcome
    _step_windows(s, 20, c, q, a)
    s.metrics["predicted"][:] = 0.6  # the window means alone hide it
    return s


def test_the_self_model_claim_reads_per_step_pairs_where_the_sweep_records_them():
    r = cl.claim_self_model_predicts({"multi_agent": _knows_late("multi_agent")})
    assert r.statistic.startswith("multi_agent, runs: 3, per-step pairs, correlated within 20-step windows"), r.statistic
    assert r.verdict.startswith("holds"), r.verdict
    # late: corr = sd(c) / sd(q) = 0.1 / sqrt(0.1^2 + 0.05^2) per step
    assert r.values["z self late"] == pytest.approx(np.arctanh(0.1 / np.sqrt(0.0125)), abs=0.02)
    assert abs(r.values["z self early"]) < 0.05 and abs(r.values["z baseline late"]) < 0.05
    # A preset sweep made before the window moments gives way to a side experiment that has them.
    main = fake_sweep("multi_agent", 2, POLICIES, 1200, seeds=1)
    for name in STEP_METRICS:
        del main.metrics[name]
    assert "20-step window means" in cl.claim_self_model_predicts({"multi_agent": main}).statistic
    side = cl.claim_self_model_predicts({"multi_agent": main, "multi_agent.steps": _knows_late("multi_agent.steps")})
    assert side.statistic.startswith("multi_agent.steps, runs: 3, per-step pairs"), side.statistic
    assert side.values == r.values


def test_observational_curiosity_on_planted_windows():
    rng = np.random.default_rng(5)
    s = fake_sweep("multi_agent", 2, POLICIES, 600, seeds=1)
    shape = s.metrics["curiosity"].shape  # [R, W, 2]
    sees_other = rng.random(shape) < 0.3
    s.metrics["view_fraction"][..., -1] = np.where(sees_other, 0.2, 0.0)
    s.metrics["curiosity"][:] = 0.5 + 0.01 * rng.normal(size=shape) + 0.05 * sees_other
    d = cl.watching_excess(s)
    assert d["diff"] == pytest.approx(np.full(3, 0.05), abs=0.01)
    assert cl.claim_observational_curiosity({"multi_agent": s}).verdict.startswith("holds")
    # A static object filling the view adds to the curiosity too. Where it fills more of it while
    # watching, the raw difference takes that for watching; with the view's fill held fixed it does not.
    fill = 0.4 * rng.random(shape) + 0.3 * sees_other
    s.metrics["view_fraction"][..., 0] = fill  # the pyramid: never moves
    s.metrics["view_fraction"][..., -1] = np.where(sees_other, 0.001, 0.0)  # the other agent, a speck
    s.metrics["curiosity"] += 0.1 * fill
    d = cl.watching_excess(s)
    assert d["diff"] == pytest.approx(np.full(3, 0.05 + 0.1 * 0.3), abs=0.01)
    assert d["beyond_view"] == pytest.approx(np.full(3, 0.05), abs=0.005)
    s.metrics["view_fraction"][..., 0] = 0.0
    s.metrics["curiosity"] -= 0.1 * fill
    # A moving object in view counts as watching too; one the agent touched itself does not.
    s.metrics["view_fraction"][..., -1] = 0.0
    s.metrics["view_fraction"][..., 2] = 0.1  # the sphere always in view ...
    s.metrics["object_pos"][:, :, 2, 0] = np.cumsum(np.where(sees_other[:, :, 0], 0.05, 0.0), axis=1)  # ... moving
    s.metrics["curiosity"][:, :, 1] = 0.5 + 0.01 * rng.normal(size=shape[:2])  # agent 1 is not watched by design
    s.metrics["contact_object"][:, :, 1, 2] = 1  # agent 1 touches the sphere: its windows are excluded
    d = cl.watching_excess(s)
    assert d["n_watching"] == int(sees_other[:, 1:, 0].sum())
    assert d["diff"] == pytest.approx(np.full(3, 0.05), abs=0.01)


def test_stop_least_and_trembling_stand_in():
    s = fake_sweep("multi_agent", 2, POLICIES, 1000, seeds=3)  # 20,000 steps
    a = s.metrics["action_counts"]
    a[:] = 0
    a[..., :6] = 3  # six moves three times a window each ...
    a[..., 6] = 2  # ... stop twice
    b = s.groups("boltzmann")[0].indices
    a[b, :, :, 4:6] = 5  # Boltzmann: rotate left and right five times each a window
    a[b, :, :, :4] = 2
    a[b, :, :, 6] = 2
    r = cl.claim_stop_least({"multi_agent": s})
    assert r.values[next(k for k in r.values if k.endswith("stop share"))] == pytest.approx(2 / 20)
    # eps runs are identical across seeds: the CI is the point 1/20, above 0.
    assert r.verdict.startswith("holds"), r.verdict
    bal = cl.balanced_rotation_share(s)
    assert bal[b] == pytest.approx(np.full(3, 10 / 20)) and bal[s.groups("eps")[0].indices] == pytest.approx(6 / 20)
    # Rotating often, the claim's other reading: 10 of 20 steps for Boltzmann, 6 of 20 for the others.
    rot = cl.rotation_share(s)
    assert rot[b] == pytest.approx(10 / 20) and rot[s.groups("ucb")[0].indices] == pytest.approx(6 / 20)
    # Identical seeds have no spread: Welch's t is undefined, so not significant; a little spread fixes that.
    a[b[0], :, 0, 4] += 1
    a[b[1], :, 1, 5] += 1
    # A sweep that records the order: Boltzmann turns back 4 times a window (of 19 pairs of steps),
    # the others once; then the other way round.
    rev = s.metrics["rotation_reversals"]
    rev[:] = 1
    rev[b] = 4
    rev[b[0], :, 0] = 5  # a little spread
    rate = cl.reversal_rate(s)
    assert rate[b[1]] == pytest.approx(4 / 19) and rate[s.groups("eps")[0].indices] == pytest.approx(1 / 19)
    r = cl.claim_boltzmann_trembles({"multi_agent": s})
    assert r.verdict.startswith("holds"), r.verdict
    assert set(r.tests) == {"reversal rate Boltzmann > ε-greedy", "reversal rate Boltzmann > UCB"}
    # The context beside it: reversals against a random order of each window's own turns. Boltzmann
    # (5 and 5 turns in 20 steps: 2.5 reversals expected; 6 and 5 in 21 for one agent of the first
    # two seeds: 60 / 21) turns back 4 times (5 for the first seed's first agent), the others (3
    # and 3: 0.9 expected) once.
    odd = 60 / 21
    assert r.values["boltzmann reversals / shuffled"] == pytest.approx(
        np.mean([9 / (odd + 2.5), 8 / (odd + 2.5), 8 / 5]))
    assert r.values["eps reversals / shuffled"] == pytest.approx(1 / 0.9)
    assert "random order of each window's own actions" in r.statistic
    # Boltzmann rotates on 10 or 11 of 20-21 steps a window, the others on 6 of 20.
    assert r.values["eps rotation share"] == pytest.approx(6 / 20)
    assert r.values["rotation share Boltzmann > ucb p"] < 0.05 and "rotating often" in r.statistic
    rev[b] = 0
    rev[b[0], :, 0] = 1
    r = cl.claim_boltzmann_trembles({"multi_agent": s})
    assert r.verdict.startswith("does not hold: Boltzmann not significantly above"), r.verdict
    # Without the order (sweeps made before it was recorded) only an upper bound on alternation is
    # known, and bounds do not order the policies, whichever way they compare: not testable.
    del s.metrics["rotation_reversals"]
    for boltzmann_turns in (5, 1):
        a[b, :, :, 4:6] = boltzmann_turns
        a[b[0], :, 0, 4] += 1
        r = cl.claim_boltzmann_trembles({"multi_agent": s})
        assert r.verdict.startswith("not testable: the sweep does not record the order"), r.verdict
        assert "upper bound" in r.statistic and not r.tests


def test_a_side_experiment_keeps_its_own_key_and_claim_6b_reads_it_for_the_order():
    # The preset's 8-seed sweep, made before the order of actions was recorded, and a shorter side
    # experiment of the same preset that records it, with seeds the main sweep also ran: merged,
    # they would repeat runs (SweepError); as a side experiment it stands apart.
    main = fake_sweep("multi_agent", 2, POLICIES, 1000, preset="multi_agent")
    del main.metrics["rotation_reversals"]
    side = fake_sweep("multi_agent.order", 2, POLICIES, 1000, preset="multi_agent")
    more = fake_sweep("multi_agent.order.seeds-3-5", 2, POLICIES, 1000, preset="multi_agent", first_seed=3)
    assert an.side_experiment("multi_agent.order.seeds-3-5") == "multi_agent.order"
    assert an.side_experiment("multi_agent.seeds-3-5") is None and an.side_experiment("multi_agent") is None
    assert an.side_experiment("nothing.order") is None
    got = cl.assign_presets([side, main])
    assert list(got) == ["multi_agent", "multi_agent.order"]
    # Each beside its preset, whatever the order given; one without its preset loaded at the end.
    single = fake_sweep("single_agent", 1, POLICIES, 4, preset="single_agent")
    single_side = fake_sweep("single_agent.order", 1, POLICIES, 4, preset="single_agent")
    got = cl.assign_presets([main, single, single_side, side])
    assert list(got) == ["multi_agent", "multi_agent.order", "single_agent", "single_agent.order"]
    assert list(cl.assign_presets([single_side, main])) == ["multi_agent", "single_agent.order"]
    assert got["multi_agent"] is main and got["multi_agent.order"] is side
    # Its seed parts merge among themselves, not into the preset.
    got = cl.assign_presets([main, side, more])
    assert got["multi_agent"] is main and got["multi_agent.order"].n_runs == 18
    assert cl.preset_and_sides(got, "multi_agent") == [main, got["multi_agent.order"]]
    # Read as a directory (sorted by name) the side experiment's seeds 3-5 come before the preset's:
    # each joins its own experiment, whatever the order.
    main_more = fake_sweep("multi_agent.seeds-3-5", 2, POLICIES, 1000, preset="multi_agent", first_seed=3)
    for listed in ([main, side, more, main_more], [main_more, more, side, main]):
        joined = an.join_seed_parts(listed)
        assert [s.name for s in joined] == ["multi_agent.seeds-0-5", "multi_agent.order.seeds-0-5"]
        assert joined[0].parts == (main, main_more) and joined[1].parts == (side, more)
    # Claim 6b: the preset's sweep lacks the order, so the side experiment's reversals decide.
    b = side.groups("boltzmann")[0].indices
    side.metrics["rotation_reversals"][:] = 1
    side.metrics["rotation_reversals"][b] = 4
    side.metrics["rotation_reversals"][b[0], :, 0] = 5
    r = cl.claim_boltzmann_trembles(cl.assign_presets([main, side]))
    assert r.statistic.startswith("multi_agent.order: reversal rate"), r.statistic
    assert r.verdict.startswith("holds"), r.verdict
    r = cl.claim_boltzmann_trembles(cl.assign_presets([main]))
    assert r.verdict.startswith("not testable: the sweep does not record the order"), r.verdict
    # A side experiment of another algorithm (here z=mean; likewise the authors' VAE layers) is
    # set beside the preset, never in its place, though its name comes first and it records the order.
    other = fake_sweep("multi_agent.a_z_mean", 2, POLICIES, 1000, preset="multi_agent", z="mean")
    got = cl.assign_presets([other, main, side])
    assert list(got) == ["multi_agent", "multi_agent.a_z_mean", "multi_agent.order"]
    assert cl.preset_and_sides(got, "multi_agent") == [main, side]
    assert cl.claim_boltzmann_trembles(got).statistic.startswith("multi_agent.order: reversal rate")
    # A side experiment named after a preset whose settings it does not have is refused by name.
    single = fake_sweep("multi_agent.order", 1, POLICIES, 4)
    with pytest.raises(an.SweepError, match="multi_agent.order: named as a side experiment of multi_agent"):
        cl.assign_presets([main, single])


def _reversals(seq, left, right) -> int:
    return sum({a, b} == {left, right} for a, b in zip(seq[:-1], seq[1:]))


def test_reversals_against_shuffled_is_the_mean_over_every_order_of_the_window():
    # Windows of 6 steps taken (as in a run halted early), so that every order of a window's
    # actions can be enumerated: the expectation comes from counting, not from the formula.
    s = fake_sweep("multi_agent", 2, POLICIES, 3, seeds=3)
    left, right = ACTIONS.index("rotate_left"), ACTIONS.index("rotate_right")
    rng = np.random.default_rng(3)
    expected = np.zeros(len(s.runs))
    for r in range(len(s.runs)):
        for w in range(3):
            for agent in range(2):
                seq = rng.choice(len(ACTIONS), size=6, p=[0.1, 0.1, 0.1, 0.1, 0.25, 0.25, 0.1])
                s.metrics["action_counts"][r, w, agent] = np.bincount(seq, minlength=len(ACTIONS))
                s.metrics["rotation_reversals"][r, w, agent] = _reversals(seq, left, right)
                orders = list(itertools.permutations(seq))
                expected[r] += np.mean([_reversals(o, left, right) for o in orders])
    observed = s.metrics["rotation_reversals"].sum(axis=(1, 2))
    np.testing.assert_allclose(cl.reversals_against_shuffled(s), observed / expected, rtol=1e-12)
    # The same over time, in one bin of the 3 windows, group by group (the figure's numbers).
    for g in s.groups():
        steps, rate, ratio = an.reversal_rates(s, g, every=60)
        assert steps.tolist() == [60]
        np.testing.assert_allclose(ratio[:, 0], observed[g.indices] / expected[g.indices], rtol=1e-12)
        np.testing.assert_allclose(rate[:, 0], observed[g.indices] / (3 * 2 * 19))  # 19 pairs a window and agent
    # Strict alternation (left, right, left, ...) against turns in runs (left, left, left, right, ...).
    s.metrics["action_counts"][:] = 0
    s.metrics["action_counts"][..., left] = 3
    s.metrics["action_counts"][..., right] = 3
    s.metrics["rotation_reversals"][:] = 5
    assert cl.reversals_against_shuffled(s) == pytest.approx(5 / 3)  # 2 * 3 * 3 / 6 = 3 expected
    s.metrics["rotation_reversals"][:] = 1
    assert cl.reversals_against_shuffled(s) == pytest.approx(1 / 3)
    s.metrics["action_counts"][..., right] = 0  # no turn back is possible: undefined
    assert np.isnan(cl.reversals_against_shuffled(s)).all()
    del s.metrics["rotation_reversals"]  # a sweep made before the metric: said so, by name
    with pytest.raises(an.SweepError, match="rotation_reversals"):
        an.reversal_rates(s, "eps")


def test_prefers_moving_objects_share():
    s = fake_sweep("single_agent", 1, [("eps", 0.2)], 2000, seeds=3)
    c = s.metrics["contact_object"]
    c[:, :300, 0, OBJECTS.index("sphere")] = 1
    c[:, :100, 0, OBJECTS.index("cylinder")] = 1
    c[:, :100, 0, OBJECTS.index("disc")] = 1
    r = cl.claim_prefers_moving_objects({"single_agent": s})
    assert r.values["contact share"] == pytest.approx(400 / 500)
    assert r.verdict.startswith("holds"), r.verdict


def test_policies_parts_compare_each_part_over_the_whole_run():
    # One agent: ε-greedy and UCB in one sweep of 40,000 steps, Boltzmann in another of 30,000, so
    # Boltzmann is compared over steps 0-30,000 and UCB with ε-greedy over all 40,000. Planted:
    # Boltzmann's spread 0.1 above the others', its error the same; after step 30,000 the ε and UCB
    # spread is far off, to show it is not read against Boltzmann.
    # A Boltzmann group at another temperature, and a z=mean sweep, are left out.
    rng = np.random.default_rng(12)
    greedy = fake_sweep("single_agent.spread", 1, [("eps", 0.2), ("ucb", 1.0)], 2000, seeds=4)
    boltz = fake_sweep("single_agent.spread_boltzmann", 1, [("boltzmann", 1.5), ("boltzmann", 0.5)], 1500, seeds=5)
    mean_latent = fake_sweep("single_agent.z_mean", 1, [("boltzmann", 1.5)], 2000, z="mean")
    for s, spread in ((greedy, 0.3), (boltz, 0.4)):
        shape = s.metrics["curiosity"].shape
        s.metrics["curiosity_spread"][:] = np.where(s.steps <= 30_000, spread, 9.0)[None, :, None]
        s.metrics["curiosity_spread"][:] += 0.01 * rng.normal(size=shape)
        s.metrics["curiosity"][:] = s.metrics["curiosity_spread"] + 0.05 + 0.01 * rng.normal(size=shape)
    boltz.metrics["curiosity"][boltz.groups("boltzmann")[1].indices] += 5.0  # T = 0.5: not the paper's setting
    t = an.policies_parts_table({"single_agent.spread": greedy, "single_agent.spread_boltzmann": boltz,
                                 "single_agent.z_mean": mean_latent})
    assert [(v["policy"], v["against"]) for v in t.values[::3]] == [("boltzmann", "eps"), ("boltzmann", "ucb"),
                                                                    ("ucb", "eps")]
    assert [v["to"] for v in t.values[::3]] == [30_000, 30_000, 40_000] and {v["agents"] for v in t.values} == {1}
    def run_means(s, policy, part, to):
        g = s.groups(policy)[0]  # the paper's setting comes first here
        c, v = (s.metrics[k][g.indices][:, s.steps <= to].astype(float) for k in ("curiosity", "curiosity_spread"))
        return {"curiosity": c, "spread": v, "error": c - v}[part].mean(axis=(1, 2))

    for v in t.values:
        x1 = run_means(boltz if v["policy"] == "boltzmann" else greedy, v["policy"], v["part"], v["to"])
        x2 = run_means(greedy, v["against"], v["part"], v["to"])
        assert v["mean"] == pytest.approx(x1.mean(), abs=1e-6)
        assert v["against_mean"] == pytest.approx(x2.mean(), abs=1e-6)
        assert v["p"] == pytest.approx(an.welch_t(x1, x2)["p"], rel=1e-4)
    rows = {(v["policy"], v["against"], v["part"]): v for v in t.values}
    assert rows["boltzmann", "eps", "spread"]["diff"] == pytest.approx(0.1, abs=0.01)
    assert rows["boltzmann", "eps", "spread"]["p"] < 0.001
    assert abs(rows["boltzmann", "eps", "error"]["diff"]) < 0.01 and abs(rows["ucb", "eps", "spread"]["diff"]) < 0.01
    # With one policy alone there is nothing to set against it.
    assert an.policies_parts_table({"single_agent.spread_boltzmann": boltz}).rows == []
    # A later rerun of a policy's sweep, listed first, does not take its place.
    rerun = fake_sweep("single_agent.batch_curiosity", 1, [("eps", 0.2)], 2000, seeds=4)
    greedy.manifest["created"], rerun.manifest["created"] = "2026-01-01T00:00:00", "2026-02-01T00:00:00"
    t = an.policies_parts_table({"single_agent.batch_curiosity": rerun, "single_agent.spread": greedy,
                                 "single_agent.spread_boltzmann": boltz})
    assert {v["against_sweep"] for v in t.values if v["against"] == "eps"} == {"single_agent.spread"}


def test_rotations_less_on_planted_action_counts():
    # Every wall different, 3 seeds of 15,000 steps. In every 20-step window each move is chosen 3
    # times, each rotation twice and stop 4 times, so a move's share is 3/20 and a rotation's 2/20,
    # but in the last run the rotations take one step each from stop: margins 0.05, 0.05 and 0.
    walls = fake_sweep("single_agent_walls_different", 1, [("eps", 0.2)], 750, walls="different")
    ac = walls.metrics["action_counts"]
    ac[:] = 0
    ac[..., :4], ac[..., 4:6], ac[..., 6] = 3, 2, 4
    ac[2, ..., 4:6], ac[2, ..., 6] = 3, 2
    r = cl.claim_rotations_less({"single_agent_walls_different": walls})
    label = "single_agent_walls_different ε-greedy (ε=0.2) (fig. 12)"
    assert r.values[f"{label} margin"] == pytest.approx(0.1 / 3)
    m = an.mean_ci(np.array([0.05, 0.05, 0.0]))
    assert r.values[f"{label} margin high"] == pytest.approx(m[2])
    assert r.verdict.startswith("does not hold: the margin's CI does not lie above 0") and "other way" not in r.verdict
    # Every run a margin of 0.05 (no spread): holds; the context sweep (identical walls) is named
    # but does not decide, though its rotations are chosen more.
    ac[2, ..., 4:6], ac[2, ..., 6] = 2, 4
    single = fake_sweep("single_agent", 1, [("eps", 0.2)], 2000)
    single.metrics["action_counts"][:] = 0
    single.metrics["action_counts"][..., 4:6] = 10
    r = cl.claim_rotations_less({"single_agent_walls_different": walls, "single_agent": single})
    assert r.verdict.startswith("holds"), r.verdict
    assert r.values["single_agent ε-greedy (ε=0.2) (fig. 10, identical walls; context) margin"] == pytest.approx(-0.5)
    # The rotations chosen more: the other way; too short or missing: says so.
    ac[..., :4], ac[..., 4:6], ac[..., 6] = 2, 5, 2
    ac[1, ..., 6] = 4
    assert cl.claim_rotations_less({"single_agent_walls_different": walls}).verdict == (
        "does not hold: the margin's CI does not lie above 0 (it lies below: the other way)")
    short = fake_sweep("single_agent_walls_different", 1, [("eps", 0.2)], 100, walls="different")
    assert cl.claim_rotations_less({"single_agent_walls_different": short}).verdict.startswith(
        "not testable at this scale (needs runs of >= 10,000 steps")
    assert "single_agent_walls_different sweep is missing" in cl.claim_rotations_less({"single_agent": single}).verdict


def _plant_run_curiosity(s, levels):
    """Each run's curiosity: 0 over the first half of the windows, twice its level over the second
    (so only the mean over the whole run is the level), the agents alike."""
    half = s.n_windows // 2
    s.metrics["curiosity"][:] = 0.0
    s.metrics["curiosity"][:, half:, :] = 2 * np.asarray(levels, float)[:, None, None]


def test_policy_curiosity_claims_on_planted_runs():
    single = fake_sweep("single_agent", 1, POLICIES, 2000, seeds=3)  # 40,000 steps
    multi = fake_sweep("multi_agent", 2, POLICIES, 2000, seeds=3)
    # Claim 10, one agent: Boltzmann 0.4 below both others (sd 0.1, p ~ 0.008), ε-greedy 0.05 below UCB.
    _plant_run_curiosity(single, [0.5, 0.6, 0.7, 0.1, 0.2, 0.3, 0.55, 0.65, 0.75])
    r = cl.claim_boltzmann_least_curious({"single_agent": single})
    assert r.verdict.startswith("holds"), r.verdict
    v = r.values
    assert (v["single_agent eps"], v["single_agent boltzmann"], v["single_agent ucb"]) == (
        pytest.approx(0.6), pytest.approx(0.2), pytest.approx(0.65))
    assert v["single_agent ε-greedy > Boltzmann p"] == pytest.approx(
        an.welch_t([0.5, 0.6, 0.7], [0.1, 0.2, 0.3])["p"]) and v["single_agent ε-greedy > Boltzmann p"] < 0.05
    w = an.welch_t([0.5, 0.6, 0.7], [0.55, 0.65, 0.75])
    assert v["single_agent eps - ucb"] == pytest.approx(-0.05)
    assert v["single_agent eps - ucb bound"] == pytest.approx(an.tost_bound(-0.05, w["se"], w["df"]))
    assert set(r.tests) == {"ε-greedy > Boltzmann", "UCB > Boltzmann"} and "Context" not in r.statistic
    # Boltzmann the most curious: significantly the other way, both tests named.
    _plant_run_curiosity(single, [0.5, 0.6, 0.7, 0.9, 1.0, 1.1, 0.55, 0.65, 0.75])
    r = cl.claim_boltzmann_least_curious({"single_agent": single, "multi_agent": multi})
    assert r.verdict == ("does not hold: ε-greedy > Boltzmann significantly the other way; UCB > Boltzmann "
                         "significantly the other way"), r.verdict
    assert "Context, not the verdict: multi_agent (2 agents)" in r.statistic and r.values["multi_agent eps"] == 0.0
    # Claim 11, two agents: UCB 0.4 above ε-greedy holds; the same level does not.
    _plant_run_curiosity(multi, [0.5, 0.6, 0.7, 0.0, 0.0, 0.0, 0.9, 1.0, 1.1])
    r = cl.claim_ucb_more_curious({"multi_agent": multi, "single_agent": single})
    assert r.verdict.startswith("holds") and "(1 agent)" in r.statistic, (r.verdict, r.statistic)
    assert r.values["multi_agent UCB > ε-greedy p"] == pytest.approx(an.welch_t([0.9, 1.0, 1.1], [0.5, 0.6, 0.7])["p"])
    _plant_run_curiosity(multi, [0.5, 0.6, 0.7, 0.0, 0.0, 0.0, 0.5, 0.6, 0.7])
    assert cl.claim_ucb_more_curious({"multi_agent": multi}).verdict == "does not hold: UCB > ε-greedy not significant"
    # What cannot be tested says why: no sweep, no Boltzmann runs, runs too short.
    assert "single_agent sweep is missing" in cl.claim_boltzmann_least_curious({}).verdict
    two = fake_sweep("single_agent", 1, [("eps", 0.2), ("ucb", 1.0)], 2000)
    assert cl.claim_boltzmann_least_curious({"single_agent": two}).verdict == (
        "not testable: single_agent has no runs of boltzmann")
    short = fake_sweep("multi_agent", 2, POLICIES, 100)
    assert cl.claim_ucb_more_curious({"multi_agent": short}).verdict.startswith(
        "not testable at this scale (needs runs of >= 40,000 steps (multi_agent has 2,000)")


def test_contacts_raise_curiosity_on_planted_windows():
    rng = np.random.default_rng(12)
    single = fake_sweep("single_agent", 1, POLICIES, 600, seeds=3)  # 12,000 steps
    multi = fake_sweep("multi_agent", 2, POLICIES, 600, seeds=3)
    for s in (single, multi):
        shape = s.metrics["curiosity"].shape  # [R, W, A]
        touching = rng.random(shape) < 0.1
        s.metrics["contact_object"][..., 1] = np.where(touching, 3, 0)  # the cylinder, 3 steps of the window
        s.metrics["curiosity"][:] = 0.5 + 0.01 * rng.normal(size=shape) + 0.04 * touching
    g = cl.paper_group(single, "eps")
    d = cl.contact_excess(single, g)
    assert d["diff"] == pytest.approx(np.full(3, 0.04), abs=0.01)
    assert d["n_touching"] + d["n_apart"] == 3 * 599  # window 0 left out
    r = cl.claim_contacts_raise_curiosity({"single_agent": single, "multi_agent": multi})
    assert r.verdict == "holds (every CI above 0)", r.verdict
    assert set(r.tests) == {"single_agent ε-greedy (ε=0.2) (fig. 9) excess touching - apart",
                            "multi_agent UCB (c=1) (section 4.1.2) excess touching - apart"}
    assert "Context, not the verdict: single_agent Boltzmann (T=1.5) (one agent)" in r.statistic
    # A view full of objects that surprises by itself: the raw difference takes it for touching,
    # the fit with the view's fill held fixed does not.
    fill = np.where(single.metrics["contact_object"][..., 1] > 0, 0.3, 0.0) + 0.6 * rng.random(shape[:2] + (1,))
    single.metrics["view_fraction"][..., 1] = fill
    single.metrics["curiosity"][:] = 0.5 + 0.001 * rng.normal(size=single.metrics["curiosity"].shape) + 0.1 * fill
    d = cl.contact_excess(single, g)
    assert d["diff"] == pytest.approx(np.full(3, 0.03), abs=0.005)
    assert d["beyond_view"] == pytest.approx(np.zeros(3), abs=0.002)
    single.metrics["curiosity"] += 0.03 * (single.metrics["contact_object"][..., 1] > 0)
    assert cl.contact_excess(single, g)["beyond_view"] == pytest.approx(np.full(3, 0.03), abs=0.002)
    # Windows where the agent touched only the other agent are neither touching nor apart.
    ucb = cl.paper_group(multi, "ucb")
    before = cl.contact_excess(multi, ucb)
    multi.metrics["contact_agent"][:, 1] = 1
    after = cl.contact_excess(multi, ucb)
    only_agent = int((multi.metrics["contact_object"][ucb.indices, 1].sum(axis=-1) == 0).sum())
    assert after["n_touching"] == before["n_touching"] and after["n_apart"] == before["n_apart"] - only_agent > 0
    # Without the planted rise in the UCB runs, the claim fails there, and says so.
    multi.metrics["curiosity"][:] = 0.5 + 0.01 * rng.normal(size=multi.metrics["curiosity"].shape)
    r = cl.claim_contacts_raise_curiosity({"single_agent": single, "multi_agent": multi})
    assert r.verdict == "does not hold: multi_agent UCB (c=1) (section 4.1.2): the CI does not lie above 0", r.verdict
    # Too few touching windows: the run drops out, and too few runs make it untestable.
    single.metrics["contact_object"][:] = 0
    single.metrics["contact_object"][:, 5, 0, 1] = 1
    assert np.isnan(cl.contact_excess(single, g)["diff"]).all()
    assert cl.claim_contacts_raise_curiosity({"single_agent": single}).verdict.startswith("not testable at this scale")


def test_situation_parts_split_claims_9_and_12_into_error_and_spread():
    # Planted: touching raises the world model's error by 0.03 and the spread by 0.02; a full view
    # (half the touching windows' fill is the object) raises the error by 0.1 per unit of fill more.
    # Raw, the error's part takes the fill's share; held fixed, it is the touch's own 0.03.
    rng = np.random.default_rng(13)
    s = fake_sweep("single_agent.spread", 1, [("eps", 0.2)], 600, seeds=4)
    mean_latent = fake_sweep("single_agent.z_mean", 1, [("eps", 0.2)], 600, seeds=4, z="mean")
    shape = s.metrics["curiosity"].shape
    touching = rng.random(shape) < 0.1
    s.metrics["contact_object"][..., 3] = np.where(touching, 2, 0)  # the disc
    fill = 0.5 * rng.random(shape) + 0.3 * touching
    s.metrics["view_fraction"][..., 3] = fill
    spread = 0.4 + 0.02 * touching + 0.002 * rng.normal(size=shape)
    error = 0.1 + 0.03 * touching + 0.1 * fill + 0.002 * rng.normal(size=shape)
    s.metrics["curiosity_spread"][:] = spread
    s.metrics["curiosity"][:] = spread + error
    t = an.situation_parts_table({"single_agent.spread": s, "single_agent.z_mean": mean_latent})
    rows = {v["part"]: v for v in t.values}
    assert list(rows) == list(an.PARTS)
    assert {(v["sweep"], v["claim"]) for v in t.values} == {("single_agent.spread", "12")}
    assert rows["spread"]["diff"] == pytest.approx(0.02, abs=0.003)
    assert rows["error"]["diff"] == pytest.approx(0.03 + 0.1 * 0.3, abs=0.005)
    assert rows["curiosity"]["diff"] == pytest.approx(rows["spread"]["diff"] + rows["error"]["diff"], abs=1e-6)
    assert rows["error"]["beyond_view"] == pytest.approx(0.03, abs=0.003)
    assert rows["spread"]["beyond_view"] == pytest.approx(0.02, abs=0.003)
    assert t.rows[0][:5] == ["`single_agent.spread`", "ε-greedy (ε=0.2)", "12: touching an object", "4",
                             "curiosity obtained"]
    # Two agents: claim 9 too, per group. Planted: watching the other agent raises the spread alone.
    two = fake_sweep("multi_agent.spread", 2, [("eps", 0.2), ("ucb", 1.0)], 600, seeds=3)
    shape = two.metrics["curiosity"].shape
    sees = rng.random(shape) < 0.3
    two.metrics["view_fraction"][..., -1] = np.where(sees, 0.1, 0.0)
    two.metrics["curiosity_spread"][:] = 0.4 + 0.03 * sees + 0.002 * rng.normal(size=shape)
    two.metrics["curiosity"][:] = two.metrics["curiosity_spread"] + 0.1 + 0.002 * rng.normal(size=shape)
    t = an.situation_parts_table({"multi_agent.spread": two})
    watched = {(v["group"], v["part"]): v for v in t.values if v["claim"] == "9"}
    assert len(watched) == 6 and {v["claim"] for v in t.values} == {"9", "12"}
    for group in ("ε-greedy (ε=0.2)", "UCB (c=1)"):
        assert watched[group, "spread"]["diff"] == pytest.approx(0.03, abs=0.003)
        assert watched[group, "error"]["diff"] == pytest.approx(0.0, abs=0.003)
    # No sweep that records the spread with sampled latents: no rows.
    assert an.situation_parts_table({"single_agent.z_mean": mean_latent}).rows == []


def test_contacts_begin_late_on_planted_rates():
    single = fake_sweep("single_agent", 1, POLICIES, 2000, seeds=3)  # 40,000 steps
    g = cl.paper_group(single, "eps")
    # 1 contact step a window (50 per 1,000 steps) before step 25,000, 4 or 5 from then on.
    onset = 25_000 // 20
    for k, r in enumerate(g.indices):
        single.metrics["contact_object"][r, :onset, 0, 2] = 1
        single.metrics["contact_object"][r, onset:, 0, 2] = 4 + k % 2
    d = cl.contact_onset(single, g)
    assert d["before"] == pytest.approx(np.full(3, 50.0))
    assert d["after"] == pytest.approx([200.0, 250.0, 200.0])
    r = cl.claim_contacts_begin_late({"single_agent": single})
    assert r.verdict == "holds (the rise's CI above 0)", r.verdict
    assert r.values["single_agent ε-greedy (ε=0.2) (fig. 9) rise"] == pytest.approx(500 / 3)
    # The same rate throughout does not hold; a sweep of half the length cannot test it.
    single.metrics["contact_object"][g.indices, onset:, 0, 2] = 1
    assert cl.claim_contacts_begin_late({"single_agent": single}).verdict == (
        "does not hold: the rise's CI does not lie above 0")
    short = fake_sweep("single_agent", 1, POLICIES, 1000)
    assert cl.claim_contacts_begin_late({"single_agent": short}).verdict.startswith(
        "not testable at this scale (needs runs of >= 40,000 steps (single_agent has 20,000)")
    assert "single_agent sweep is missing" in cl.claim_contacts_begin_late({}).verdict

def test_boltzmann_agents_meet_on_planted_contacts():
    # 80,000 steps: the ε-greedy agents touch each other on 3-5 steps a run, the Boltzmann agents on
    # 40-60 (in their last quarter, as the paper's run does), UCB's on 100.
    multi = fake_sweep("multi_agent", 2, POLICIES, 4000, seeds=4)
    totals = {"eps": [3, 4, 5, 4], "boltzmann": [40, 60, 50, 55], "ucb": [100] * 4}
    for p, n in totals.items():
        for r, k in zip(cl.paper_group(multi, p).indices, n):
            multi.metrics["contact_agent"][r, 3000:3000 + k, :] = 1  # one step a window, both agents see it
    r = cl.claim_boltzmann_agents_meet({"multi_agent": multi})
    assert r.key == "15" and r.verdict == "holds (Welch p < 0.05, Boltzmann > ε-greedy)", r.verdict
    assert r.values["agent-agent boltzmann"] == pytest.approx(51.25)
    assert r.values["agent-agent eps share of UCB"] == pytest.approx(4.0)
    assert "Boltzmann 51 [" in r.statistic and "(51 % of UCB's)" in r.statistic
    assert list(r.tests) == ["agent-agent Boltzmann > ε"]
    # The other way round: does not hold, and says so.
    for p in ("eps", "boltzmann"):
        multi.metrics["contact_agent"][cl.paper_group(multi, p).indices] = 0
    for r_, k in zip(cl.paper_group(multi, "eps").indices, totals["boltzmann"]):
        multi.metrics["contact_agent"][r_, :k, :] = 1
    r = cl.claim_boltzmann_agents_meet({"multi_agent": multi})
    assert r.verdict == ("does not hold: Boltzmann agents do not touch each other significantly more than "
                         "ε-greedy ones (fewer)"), r.verdict
    # Half the paper's length: not testable, the statistic shown, no test for the power table.
    short = fake_sweep("multi_agent", 2, POLICIES, 2000)
    r = cl.claim_boltzmann_agents_meet({"multi_agent": short})
    assert r.verdict.startswith("not testable at this scale (needs runs of >= 80,000 steps") and r.tests == {}
    assert "agent-agent contact steps per run" in r.statistic


# ------------------------------------------------------------------------------ the tiny sweeps


def test_claims_table_on_the_tiny_sweeps(tiny_sweeps_dir):
    table = an.claims_table(tiny_sweeps_dir)
    md = table.to_markdown()
    assert [v["key"] for v in table.values] == KEYS
    assert len(table.rows) == len(cl.CLAIMS) and all(len(r) == len(table.columns) for r in table.rows)
    for v in table.values:
        assert v["verdict"].startswith(cl.VERDICTS), v["verdict"]
        if v["key"] == "10":  # the tiny one-agent sweep runs ε-greedy and UCB only
            assert v["verdict"] == "not testable: single has no runs of boltzmann", v["verdict"]
            continue
        if v["key"] == "6c":  # no tiny sweep has different walls
            assert v["verdict"] == "not testable: the single_agent_walls_different sweep is missing", v["verdict"]
            continue
        # 200 steps and 1-2 seeds: too small for any claim, and the table must say so.
        assert v["verdict"].startswith("not testable at this scale (needs runs of >= "), v["verdict"]
        assert "multi has 200)" in v["verdict"] or "single has 200)" in v["verdict"], v["verdict"]
        for k, x in v.items():
            if k not in ("key", "claim", "verdict") and x is not None:
                assert math.isfinite(x), (v["key"], k, x)
    assert "Sweeps as presets: single_agent = single, multi_agent = multi, boltzmann_temperatures = multi" in md
    # The statistics that 200 steps allow are computed.
    by_key = {v["key"]: v for v in table.values}
    assert by_key["3"]["curiosity single"] is not None and by_key["3"]["curiosity multi"] is not None
    assert by_key["4"]["within z"] is not None and by_key["7"]["F"] is not None
    print(md)


def test_walls_table_on_planted_runs():
    # One agent, ε-greedy, 3 seeds a side. The walls runs ran 15 windows of 20 steps (300 steps),
    # the identical-walls runs 25: only their first 15 windows count, the last 100 steps (5 windows)
    # for curiosity and the VAE loss. The windows outside are planted far off, so using them shows.
    d = fake_sweep("walls", 1, [("eps", 0.2)], 15, walls="different")
    s = fake_sweep("same", 1, [("eps", 0.2), ("ucb", 1.0)], 25)
    for sweep, level in ((d, [1.0, 2.0, 4.0]), (s, [0.5, 1.0, 1.5, 9.0, 9.0, 9.0])):
        sweep.metrics["curiosity"][:] = 100.0
        sweep.metrics["curiosity"][:, 10:15, 0] = np.array(level)[:, None]
        sweep.metrics["vae_loss"][:] = 1e4
        sweep.metrics["vae_loss"][:, 10:15] = 10 * np.array(level)[:, None]
        sweep.metrics["recon"][:] = 1e4
        sweep.metrics["recon"][:, 10:15] = 7 * np.array(level)[:, None]
    s.metrics["curiosity"][:, 15:] = s.metrics["vae_loss"][:, 15:] = s.metrics["recon"][:, 15:] = -1e6
    # Contacts over all 300 steps: walls run i touches on i + 1 steps; identical-walls runs on 3,
    # and on every step after step 300.
    for i in range(3):
        d.metrics["contact_object"][i, 0, 0, 0] = i + 1
    s.metrics["contact_object"][:, 1, 0, 1] = 3
    s.metrics["contact_object"][:, 15:, 0, 0] = 20
    # The third walls run diverged: no late windows (its contacts still count over its steps).
    d.metrics["curiosity"][2, 5:] = d.metrics["vae_loss"][2, 5:] = d.metrics["recon"][2, 5:] = np.nan
    d.metrics["steps_taken"][2, 5:] = 0
    t = an.walls_table({"single_agent_walls_different": d, "single_agent": s}, late_steps=100)
    assert t.columns[3:] == ["curiosity, steps 200-300", "VAE loss per image, steps 200-300",
                             "of which reconstruction, steps 200-300",
                             "object contacts per 1,000 agent-steps, steps 0-300"]
    assert len(t.rows) == 1 and t.rows[0][:3] == ["1", "ε-greedy (ε=0.2)", "2 / 3"]  # UCB: no walls runs
    v = t.values[0]
    assert v["steps"] == 300 and (v["runs different"], v["runs same"]) == (2, 3)
    assert (v["curiosity different"], v["curiosity same"]) == (pytest.approx(1.5), pytest.approx(1.0))
    assert v["curiosity p"] == pytest.approx(an.welch_t([1.0, 2.0], [0.5, 1.0, 1.5])["p"])
    assert (v["vae_loss different"], v["vae_loss same"]) == (pytest.approx(15.0), pytest.approx(10.0))
    assert (v["recon different"], v["recon same"]) == (pytest.approx(10.5), pytest.approx(7.0))
    walls_rate = 1000 * np.array([1, 2, 3]) / np.array([300, 300, 100])
    assert v["object_contacts different"] == pytest.approx(walls_rate.mean())
    assert v["object_contacts same"] == pytest.approx(10.0)  # 3 contact steps in 300
    assert v["object_contacts p"] == pytest.approx(an.welch_t(walls_rate, [10.0, 10.0, 10.0])["p"])
    # Not significant (p ~ 0.4): the seeds a side for 80 % power at the difference seen, in the cell.
    need = an.seeds_needed(cl.Tested(np.array([1.0, 2.0]), np.array([0.5, 1.0, 1.5])))
    assert v["curiosity p"] > 0.05 and v["curiosity seeds for 80 % power"] == need and 8 < need < 10_000
    # And the bound two one-sided tests put on it: 0.5 + t(0.95, df) sqrt(1/4 + 1/12), with Welch's
    # df = (1/3)^2 / ((1/4)^2 / 1 + (1/12)^2 / 2); ten times that for the VAE loss.
    bound = 0.5 + an.t_critical((1 / 3) ** 2 / (1 / 16 + 1 / 288), 0.1) * math.sqrt(1 / 3)
    assert v["curiosity equivalence bound"] == pytest.approx(bound) and 1.0 < bound < 5.0
    assert v["vae_loss equivalence bound"] == pytest.approx(10 * bound)
    assert t.rows[0][3] == f"1.5 vs 1 (p = {v['curiosity p']:.2g}; Δ within ±{bound:.3g}; {int(need)} seeds)"
    # The identical-walls side the larger: the same count (a two-sided test); a significant
    # difference, or none at all, has no count.
    from mjx_curio.analysis import walls
    x, y = [0.5, 1.0, 1.5], [1.0, 2.0]
    assert walls._seeds_for_power(x, y, an.welch_t(x, y)) == need
    assert v["vae_loss seeds for 80 % power"] == need  # ten times the curiosity's values: the same test
    assert math.isnan(walls._seeds_for_power([1.0, 1.1, 0.9], [5.0, 5.1, 4.9], an.welch_t([1.0, 1.1, 0.9], [5.0, 5.1, 4.9])))
    same = an.walls_table({"single_agent_walls_different": s, "single_agent": s}, late_steps=100)
    assert all(math.isnan(x) for k, x in same.values[0].items() if k.endswith("power"))
    # Two agents: the VAE loss is per image, the curiosity the mean of the agents.
    d2 = fake_sweep("walls2", 2, [("eps", 0.2)], 15, walls="different")
    s2 = fake_sweep("same2", 2, [("eps", 0.2)], 15)
    d2.metrics["vae_loss"][:] = 40.0
    d2.metrics["recon"][:] = 30.0
    d2.metrics["curiosity"][..., 0], d2.metrics["curiosity"][..., 1] = 1.0, 3.0
    t2 = an.walls_table({"multi_agent_walls_different": d2, "multi_agent": s2}, late_steps=100)
    assert (t2.values[0]["vae_loss different"], t2.values[0]["recon different"]) == (20.0, 15.0)
    assert t2.values[0]["curiosity different"] == 2.0
    # Identical-walls runs shorter than the wall runs cannot be cut to their length: no row.
    assert an.walls_table({"multi_agent_walls_different": s, "multi_agent": d}).rows == []
    for bad in (0, -100, 2.5):
        with pytest.raises(ValueError, match="late_steps"):
            an.walls_table({}, late_steps=bad)
