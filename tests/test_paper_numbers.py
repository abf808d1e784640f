"""The paper's numbers beside ours (mjx_curio/analysis/paper_numbers.py): every run's curve in
1,000-step bins against NumPy, and each reading measured on planted curves."""

import numpy as np
import pytest

from mjx_curio import analysis as an
from mjx_curio.analysis import paper_numbers as pn
from mjx_curio.analysis.significance import welch_t

from test_claims import POLICIES, fake_sweep


def test_run_curves_bin_the_windows_and_sum_the_contacts():
    s = fake_sweep("multi_agent", 2, POLICIES, 150, seeds=2)  # 3,000 steps: three bins of 50 windows
    rng = np.random.default_rng(0)
    s.metrics["curiosity"][:] = rng.random(s.metrics["curiosity"].shape)
    s.metrics["contact_object"][:, 60, 1, 2] = 3
    s.metrics["contact_agent"][:, 120, :] = 2  # both agents see the same contact: counted once
    cv = pn.run_curves(s)
    assert cv["steps"].tolist() == [1000, 2000, 3000]
    want = s.metrics["curiosity"].astype(float).mean(axis=2).reshape(6, 3, 50).mean(axis=2)
    np.testing.assert_allclose(cv["runs"], want, rtol=1e-6)
    assert cv["object_contacts"][0].tolist() == [0, 3, 3] and cv["agent_contacts"][0].tolist() == [0, 0, 2]


def _curves(levels, bins=80):
    """Planted curves of `bins` 1,000-step bins, one run a level function of the step (thousands)."""
    steps = np.arange(1, bins + 1) * 1000
    return {"steps": steps, "runs": np.array([[f(k) for k in steps / 1000] for f in levels])}


def test_each_measure_on_planted_curves():
    # Two runs of each policy; run r's curiosity is 0.5 + 0.1 r, except a dip to 0.2 in one bin.
    dips = [12, 20]
    cv = _curves([lambda k, r=r: 0.2 if k == dips[r % 2] else 0.5 + 0.1 * r for r in range(6)])
    object_totals = np.array([50, 50, 10, 20, 100, 100])  # ε-greedy, Boltzmann, UCB
    cv["object_contacts"] = np.outer(object_totals, cv["steps"] / 80_000)  # a steady rate
    cv["object_contacts"][3, 40:] = cv["object_contacts"][3, 39]  # one Boltzmann run stops at 40,000
    groups = {"eps": [0, 1], "boltzmann": [2, 3], "ucb": [4, 5]}

    def value(measure, policy, *args):
        return pn.reading_value(pn.Reading("fig. x", "multi_agent", policy, "", "", measure, args), cv, groups)

    assert value("level", "eps", 30_000, 40_000)[1] == pytest.approx(0.55)  # runs at 0.5 and 0.6
    assert value("end", "ucb")[1] == pytest.approx(0.95)
    assert value("lowest", "eps")[1] == pytest.approx(0.2)
    assert value("lowest_step", "eps")[1] == pytest.approx((11_500 + 19_500) / 2)  # the bins' middles
    assert value("share_of_ucb", "eps", "object_contacts")[1] == pytest.approx(50.0)
    assert value("share_of_ucb", "boltzmann", "object_contacts")[0] == "10 % [10, 10]"  # 10, and 20 stopped halfway
    assert value("share_by", "ucb", "object_contacts", 40_000)[1] == pytest.approx(50.0)
    assert value("touching_after", "boltzmann", "object_contacts", 30_000)[0] == "2 of 2"
    assert value("touching_after", "boltzmann", "object_contacts", 50_000)[0] == "1 of 2"
    # A run that diverged at once (every bin NaN) is left out of the lowest and its step.
    halted = {**cv, "runs": cv["runs"].copy()}
    halted["runs"][0] = np.nan
    assert pn.reading_value(pn.Reading("", "", "eps", "", "", "lowest_step"), halted, groups)[0].startswith(
        "19,500 [nan, nan] (runs: 19,500-19,500)")
    # Runs of 40,000 steps: nothing about later steps.
    short = {k: (v[:, :40] if k != "steps" else v[:40]) for k, v in cv.items()}
    assert pn.reading_value(pn.Reading("", "", "ucb", "", "", "level", (30_000, 80_000)), short, groups) is None
    assert pn.reading_value(pn.Reading("", "", "ucb", "", "", "share_by", ("object_contacts", 40_000)),
                            short, groups) is None
    assert pn.reading_value(pn.Reading("", "", "ucb", "", "", "level", (0, 1_000)), cv, {"ucb": [4]})[1] == 0.9


def test_the_table_on_planted_sweeps_and_full_length_curves():
    single = fake_sweep("single_agent", 1, POLICIES, 2000, seeds=3)
    multi = fake_sweep("multi_agent", 2, POLICIES, 2000, seeds=3)
    single.metrics["curiosity"][:] = 0.4
    multi.metrics["curiosity"][:] = 0.3
    t = an.paper_numbers_table({"single_agent": single, "multi_agent": multi})
    assert len(t.rows) == len(pn.READINGS) and len(t.columns) == 5
    rows = {(r[0], r[2]): r for r in t.rows}
    assert rows["fig. 8", "curiosity, steps 0-1,000"][4] == "0.4 [0.4, 0.4]"
    assert rows["fig. 18", "curiosity, steps 30,000-80,000"][4] == "—"  # 40,000-step runs
    assert rows["fig. 21", "object contacts, % of UCB's"][4] == "—"  # no UCB contacts to compare with
    cv = _curves([lambda k: 0.6] * 9)
    cv["object_contacts"] = cv["agent_contacts"] = np.outer(np.arange(1, 10), cv["steps"] / 1000)
    long = {"multi_agent": (cv, {"eps": [0, 1, 2], "boltzmann": [3, 4, 5], "ucb": [6, 7, 8]})}
    t = an.paper_numbers_table({"single_agent": single, "multi_agent": multi}, long, "80,000 steps, planted")
    assert t.columns[-1] == "here: 80,000 steps, planted"
    rows = {(r[0], r[2]): r for r in t.rows}
    assert rows["fig. 18", "curiosity, steps 30,000-80,000"][5] == "0.6 [0.6, 0.6]"
    assert rows["fig. 8", "curiosity, steps 0-1,000"][5] == "—"  # no one-agent run of that length
    assert rows["fig. 21", "% of the run's object contacts made by step 40,000"][5] == "50 % [50, 50]"
    assert t.values[0]["ours"] == pytest.approx(0.4) and t.values[0]["ours_long"] is None
    # Full-length runs of one policy (fig. 8's ε-greedy alone): its readings, but no share of UCB's.
    t = an.paper_numbers_table({"single_agent": single, "multi_agent": multi},
                               {"single_agent": (cv, {"eps": [0, 1, 2]}), "multi_agent": (cv, {"eps": [0, 1, 2]})})
    rows = {(r[0], r[2]): r for r in t.rows}
    assert rows["fig. 8", "curiosity, steps 0-1,000"][5] == "0.6 [0.6, 0.6]"
    assert rows["fig. 21", "object contacts, % of UCB's"][5] == "—"


def test_plot_paper_readings_draws_each_source_and_the_papers_boxes():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cv = _curves([lambda k: 0.4] * 3 + [lambda k: 0.5] * 3)
    fig, ax = plt.subplots()
    an.plot_paper_readings(ax, "fig. 8", [("ours", cv, [0, 1, 2]), ("longer", cv, [3, 4, 5])])
    lines = [ln for ln in ax.get_lines() if len(ln.get_xdata()) == 80]
    assert [ln.get_ydata().mean() for ln in lines] == pytest.approx([0.4, 0.5])
    boxes = [r.box for r in pn.READINGS if r.figure == "fig. 8" and r.box]
    outlines = [ln for ln in ax.get_lines() if len(ln.get_xdata()) == 5]
    assert len(boxes) == 4 and [(ln.get_xdata()[0], ln.get_ydata()[0]) for ln in outlines] == [
        (b[0], b[2]) for b in boxes]
    plt.close(fig)


def test_the_readings_panels_follow_the_loaded_presets_and_draw_the_longer_runs():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    multi = fake_sweep("multi_agent", 2, POLICIES, 100, seeds=3)
    multi.metrics["curiosity"][:] = 0.3
    long = {"multi_agent": (_curves([lambda k: 0.6] * 9), {"eps": [0, 1, 2], "ucb": [6, 7, 8]})}
    fig = plt.figure()
    axes = an.plot_paper_readings_panels(fig, {"multi_agent": multi}, long)
    # figs. 17, 18 and 20 run two agents; fig. 8 (one agent) has no sweep here.
    assert [ax.get_title().split(":")[0] for ax in axes] == ["fig. 17", "fig. 18", "fig. 20"]
    means = [[round(float(ln.get_ydata().mean()), 6) for ln in ax.get_lines() if ln.get_label().endswith(" runs)")]
             for ax in axes]
    assert means == [[0.3, 0.6], [0.3, 0.6], [0.3]]  # no Boltzmann runs among the longer ones
    assert fig.get_size_inches()[1] == pytest.approx(9.0)
    plt.close(fig)
    empty = plt.figure()
    assert an.plot_paper_readings_panels(empty, {}) == [] and not empty.axes
    plt.close(empty)


def test_readings_side_by_side_compares_two_sweeps_in_the_figures_windows():
    """Two one-agent ε-greedy sweeps with planted levels: each level window of fig. 8 the shorter
    reaches, and the last 2,000 steps both ran, with b - a and Welch's test against NumPy."""
    a = fake_sweep("a", 1, [("eps", 0.2)], 600, seeds=4)  # 12,000 steps
    b = fake_sweep("b", 1, [("eps", 0.2)], 800, seeds=4)  # 16,000 steps: only a's are read
    rng = np.random.default_rng(1)
    for s, level in ((a, 0.5), (b, 0.8)):
        per_run = level + 0.05 * rng.standard_normal(4)
        s.metrics["curiosity"][:] = per_run[:, None, None]
        s.metrics["curiosity_spread"][:] = 0.4
    t = pn.readings_side_by_side(a, b, ("A", "B"))
    windows = list(dict.fromkeys(r[0] for r in t.rows))
    assert windows == ["steps 0-1,000", "steps 4,000-6,000", "steps 10,000-12,000 (the last both ran)"]
    xa = a.metrics["curiosity"][:, 0, 0].astype(float)
    xb = b.metrics["curiosity"][:, 0, 0].astype(float)
    want = welch_t(xb, xa)
    got = t.values[0]
    assert got["metric"] == "curiosity" and got["A"] == pytest.approx(xa.mean()) and got["B"] == pytest.approx(xb.mean())
    assert got["diff"] == pytest.approx(xb.mean() - xa.mean()) and got["p"] == pytest.approx(want["p"])
    assert t.values[1]["metric"] == "curiosity_spread" and t.values[1]["diff"] == pytest.approx(0.0, abs=1e-6)
    assert t.rows[0][2] == "close to 1" and t.rows[1][2] == "—"
    with pytest.raises(ValueError, match="no curiosity levels"):
        pn.readings_side_by_side(a, b, ("A", "B"), figure="fig. 21")


def test_side_by_side_reads_the_window_where_the_papers_curve_is_lowest():
    """Fig. 17 has one level (steps 0-1,000) and a lowest point (its box, steps 20,000-25,000):
    both are windows once the sweeps reach them, in order of their steps, the paper's number
    beside each."""
    a, b = (fake_sweep(name, 2, [("eps", 0.2)], 1_400, seeds=3) for name in "ab")  # 28,000 steps
    t = pn.readings_side_by_side(a, b, ("A", "B"), figure="fig. 17")
    curiosity = [r for r in t.rows if r[1] == "curiosity"]
    assert [r[0] for r in curiosity] == ["steps 0-1,000", "steps 20,000-25,000 (the paper's lowest)",
                                         "steps 26,000-28,000 (the last both ran)", "the lowest bin, steps 0-28,000"]
    assert [r[2] for r in curiosity] == ["0.7", "about 0.53", "—", "about 0.53"]
    short = fake_sweep("short", 2, [("eps", 0.2)], 1_200, seeds=3)  # 24,000 steps: short of the trough's end
    rows = pn.readings_side_by_side(a, short, ("A", "S"), figure="fig. 17").rows
    assert all("paper's lowest" not in r[0] for r in rows)


def test_side_by_side_finds_each_runs_lowest_bin_over_the_steps_both_ran():
    """Planted dips: a's runs lowest in the bin of steps 10,000-11,000, b's in 20,000-21,000 at
    other depths; a dip of b's beyond a's last step is not read."""
    a = fake_sweep("a", 2, [("eps", 0.2)], 1_400, seeds=3)  # 28,000 steps
    b = fake_sweep("b", 2, [("eps", 0.2)], 1_600, seeds=3)  # 32,000 steps
    for s in (a, b):
        s.metrics["curiosity"][:] = 0.6
    a.metrics["curiosity"][:, 500:550] = np.array([0.2, 0.3, 0.4])[:, None, None]
    b.metrics["curiosity"][:, 1000:1050] = np.array([0.4, 0.45, 0.5])[:, None, None]
    b.metrics["curiosity"][:, 1450:1500] = 0.0  # steps 29,000-30,000: after a's end
    t = pn.readings_side_by_side(a, b, ("A", "B"), figure="fig. 17")
    level, step = [(r, v) for r, v in zip(t.rows, t.values) if r[0] == "the lowest bin, steps 0-28,000"]
    assert level[0][1:3] == ["curiosity", "about 0.53"]
    assert step[0][1:3] == ["its step (the bin's middle)", "20,000-25,000"]
    assert level[1]["A"] == pytest.approx(0.3) and level[1]["B"] == pytest.approx(0.45)
    assert level[1]["p"] == pytest.approx(welch_t([0.4, 0.45, 0.5], [0.2, 0.3, 0.4])["p"])
    assert step[1]["A"] == 10_500 and step[1]["B"] == 20_500 and step[1]["diff"] == 10_000
    assert step[0][3] == "10,500 [10,500, 10,500] (runs: 10,500-10,500)" and step[0][5].startswith("+10,000")
    assert not any("lowest bin" in r[0] for r in pn.readings_side_by_side(a, b, ("A", "B")).rows)  # fig. 8: none


def test_side_by_side_shows_the_training_batches_curiosity_where_a_sweep_records_it():
    a = fake_sweep("a", 1, [("eps", 0.2)], 300, seeds=2)
    b = fake_sweep("b", 1, [("eps", 0.2)], 300, seeds=2)
    del a.metrics["batch_curiosity"]  # made before the metric existed
    b.metrics["batch_curiosity"][:] = 0.9
    t = pn.readings_side_by_side(a, b, ("A", "B"))
    rows = [r for r in t.rows if r[1] == "training batches' curiosity"]
    assert len(rows) == 3 and all(r[3] == "—" and r[4].startswith("0.9 ") and r[5] == "—" for r in rows)
    assert "a sweep made before it was recorded" in t.note
    both = pn.readings_side_by_side(b, b, ("B", "B again"))
    assert "a sweep made before it was recorded" not in both.note
    assert all(r[5] != "—" for r in both.rows if r[1] == "training batches' curiosity")
    del b.metrics["batch_curiosity"]
    assert all(r[1] != "training batches' curiosity" for r in pn.readings_side_by_side(a, b, ("A", "B")).rows)


def test_side_by_side_shared_only_keeps_the_measures_both_sweeps_record():
    """Against a sweep that records the curiosity alone, `shared_only` drops the other's posterior
    spread and training batches' curiosity (and the note on the spread); the curiosity rows, their
    numbers included, are those of the full table."""
    a = fake_sweep("a", 1, [("eps", 0.2)], 300, seeds=3)
    b = fake_sweep("b", 1, [("eps", 0.2)], 300, seeds=3)
    for name in ("curiosity_spread", "batch_curiosity"):
        del a.metrics[name]  # made before either was recorded
    rng = np.random.default_rng(2)
    for s in (a, b):
        s.metrics["curiosity"][:] = (0.5 + 0.05 * rng.standard_normal(3))[:, None, None]
    full = pn.readings_side_by_side(a, b, ("A", "B"))
    shared = pn.readings_side_by_side(a, b, ("A", "B"), shared_only=True)
    assert {r[1] for r in full.rows} == {"curiosity", "posterior spread", "training batches' curiosity"}
    assert {r[1] for r in shared.rows} == {"curiosity"}
    assert shared.rows == [r for r in full.rows if r[1] == "curiosity"]
    assert "posterior spread is" in full.note and "posterior spread is" not in shared.note
    both = pn.readings_side_by_side(b, b, ("B", "B again"), shared_only=True)
    assert {r[1] for r in both.rows} == {"curiosity", "posterior spread", "training batches' curiosity"}
