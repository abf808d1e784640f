"""Claims: the paper's findings (sections 4 and 5) tested on the preset sweeps, as one table.

    from mjx_curio import analysis as an
    table = an.claims_table("runs/paper")      # or a list of Sweeps, or {preset name: Sweep}
    print(table.to_markdown())

The paper shows one run per experiment; the presets (presets.toml) run several seeds of each, so
each claim here becomes a statistic across seeds: a mean with its 95% confidence interval
(`stats.mean_ci`, Student t across runs) or a named test with its p-value. Every claim has its own
function below (`claim_*`), whose docstring says exactly what is measured and how the verdict is
decided; `claims_table` runs them all.

Verdicts, and the rules every claim shares:
  holds            the statistic shows the paper's effect at the 5% level in the paper's direction
                   (the 95% CI excludes the null on the paper's side, or p < 0.05 with the sign the
                   paper reports; a claim of *no* difference holds when p >= 0.05).
  does not hold    the sweeps are at the scale the claim needs, and the statistic does not show
                   the effect (no significant effect, or a significant one the other way; the
                   reason follows the colon). Not significant is not the same as refuted: with
                   8 seeds a small effect can go undetected (`power` says how small, from the
                   values each claim's tests compared, `ClaimResult.tests`).
  not testable ... a preset sweep the claim needs is not loaded ("not testable: ..."), the metrics
                   cannot show it, or the sweeps are smaller than the claim needs: "not testable at
                   this scale (needs ...)", naming the run length and seeds that would test it.
                   The statistic is still computed where the data allow, for inspection.

Scale: every comparison needs at least `MIN_SEEDS` runs in each compared group (a 95% t interval
over 2 runs spans +-12.7 sd, which decides nothing), and each claim names the run length its
phenomenon needs, from where the paper sees it (e.g. the curiosity minimum between 10,000 and
30,000 steps).

Sweeps are matched to presets (`assign_presets`) by the `preset` their manifest records, else by
their directory or dict name, else by their settings (agents, walls, policies, temperatures), so a
sweep run by hand with a preset's settings stands in for it. A sweep named `<preset>.<label>`
(e.g. `multi_agent.order`) is a side experiment of that preset: its own seeds and length, kept
apart from the preset's sweep, read by the claims that name it (claim 6b reads `multi_agent.*`
where the `multi_agent` sweep does not record the order of actions).

Tests with p-values use only NumPy and the standard library (`significance`). Imports `significance`,
`sweeps`, `stats` and `tables`.
"""

from __future__ import annotations

import dataclasses
import math
import pathlib
import warnings
from typing import Callable, Mapping, Sequence

import numpy as np

from mjx_curio.analysis.stats import (
    agent_contacts,
    mean_ci,
    moving_average,
    nan_ratio,
    object_contacts,
    per_agent_vae_loss,
    turn_reversals,
)
from mjx_curio.analysis.significance import (
    block_anova,
    equivalence_bound,
    fisher_z,
    one_way_anova,
    pearson_r,
    tost_bound,
    welch_t,
)
from mjx_curio.analysis.self_model import records_steps, step_tracking, trailing_sum
from mjx_curio.analysis.sweeps import Group, Sweep, SweepError, load_sweeps, merge_sweeps, side_experiment
from mjx_curio.analysis.tables import Table

ALPHA = 0.05
MIN_SEEDS = 3
SMOOTH = 50  # windows of the paper's moving average (50 points of 20 steps)

# What each preset is, as the settings a sweep must have to stand in for it (presets.toml).
PRESET_SETTINGS = {
    "single_agent": dict(agents=1, walls="same", policies=("eps", "boltzmann", "ucb")),
    "single_agent_walls_different": dict(agents=1, walls="different", policies=("eps",)),
    "multi_agent": dict(agents=2, walls="same", policies=("eps", "boltzmann", "ucb")),
    "multi_agent_walls_different": dict(agents=2, walls="different", policies=("eps", "boltzmann", "ucb")),
    "boltzmann_temperatures": dict(agents=2, walls="same", policies=("boltzmann",), temperatures=2,
                                   temperature_range=(0.5, math.inf)),
    # Not the paper's: the temperatures where the policy's softmax starts to favour actions.
    "boltzmann_low_temperatures": dict(agents=2, walls="same", policies=("boltzmann",), temperatures=2,
                                       temperature_range=(0.0, 0.5)),
}
# The paper's setting of each policy, used where a sweep holds several (the sweep's defaults).
PAPER_SETTING = {"eps": 0.2, "boltzmann": 1.5, "ucb": 1.0}


# ---------------------------------------------------------------------------- seeds as blocks


def seed_table(sweep: Sweep, groups: Sequence[Group], x) -> np.ndarray:
    """[groups, seeds]: `x` (one value a run) arranged by group and seed, over the seeds that every
    group ran (in seed order): the table `block_anova` takes, a seed being a block."""
    seeds = sorted(set.intersection(*({sweep.runs[i].seed for i in g.indices} for g in groups))) if groups else []
    by_seed = [{sweep.runs[i].seed: x[i] for i in g.indices} for g in groups]
    return np.array([[row[seed] for seed in seeds] for row in by_seed], float).reshape(len(groups), len(seeds))


# ------------------------------------------------------------------------------- sweeps to presets


def assign_presets(sweeps) -> dict[str, Sweep]:
    """{preset name: Sweep} from `sweeps`: a directory (as `load_sweeps` reads it), a list of
    Sweeps, or a dict {name: Sweep}. A sweep serves a preset when, in this order: its manifest
    records that `preset`; its name (dict key, else directory name) is the preset's; or its settings
    fit the preset (same number of agents and walls, at least one of its policies, and for
    `boltzmann_temperatures` at least 2 temperatures, all >= 0.5; for `boltzmann_low_temperatures`
    all below 0.5). A sweep named after or made by one preset
    serves only that one; the first fitting sweep wins. Several sweeps made by one preset are its
    seeds run in parts (`first_seed=3 seeds=5` after `seeds=3`) and serve it as one
    (`merge_sweeps`; SweepError, naming what differs, where they are not one experiment).

    A sweep named `<preset>.<label>` (`side_experiment`; its seed parts `<preset>.<label>.seeds-3-5`)
    is another experiment with that preset's settings, e.g. a shorter sweep that records a metric
    the preset's sweep lacks: it serves the key `<preset>.<label>`, right after its preset, and never
    the preset itself (SweepError where its settings do not fit the preset's)."""
    if isinstance(sweeps, (str, pathlib.Path)):
        sweeps = load_sweeps(sweeps)
    named = list(sweeps.items()) if isinstance(sweeps, Mapping) else [(s.name, s) for s in sweeps]
    claimed: dict[str, list[Sweep]] = {}
    sides: dict[str, list[Sweep]] = {}
    fixed = set()
    for name, s in named:
        side = side_experiment(name)
        if side is not None:
            of = side.partition(".")[0]
            if of in PRESET_SETTINGS and not _fits(s, PRESET_SETTINGS[of]):
                raise SweepError(f"{name}: named as a side experiment of {of}, but its settings (agents, walls, "
                                 "policies) are not that preset's")
            sides.setdefault(side, []).append(s)
            fixed.add(id(s))
            continue
        recorded = s.manifest.get("config", {}).get("preset", "none")
        for key in (recorded, name):
            if key in PRESET_SETTINGS:
                claimed.setdefault(key, []).append(s)
                fixed.add(id(s))
                break
    out: dict[str, Sweep] = {key: merge_sweeps(parts) for key, parts in claimed.items()}
    for preset, want in PRESET_SETTINGS.items():
        if preset in out:
            continue
        for _, s in named:
            if id(s) not in fixed and _fits(s, want):
                out[preset] = s
                break
    # Each side experiment right after its preset (at the end where its preset is not loaded).
    ordered: dict[str, Sweep] = {}
    for key, s in out.items():
        ordered[key] = s
        ordered.update({side: merge_sweeps(parts) for side, parts in sides.items() if side.partition(".")[0] == key})
    ordered.update({side: merge_sweeps(parts) for side, parts in sides.items() if side not in ordered})
    return ordered


def preset_and_sides(presets: Mapping[str, Sweep], preset: str) -> list[Sweep]:
    """The sweep serving `preset`, then its side experiments (`<preset>.<label>`), those given."""
    return [s for key, s in presets.items() if key == preset or key.startswith(preset + ".")]


def _fits(s: Sweep, want: dict) -> bool:
    if s.n_agents != want["agents"] or s.manifest.get("config", {}).get("walls", "same") != want["walls"]:
        return False
    policies = {r.policy for r in s.runs}
    if not policies & set(want["policies"]):
        return False
    temperatures = [g.value for g in s.groups("boltzmann")]
    lo, hi = want.get("temperature_range", (-math.inf, math.inf))
    return len(temperatures) >= want.get("temperatures", 0) and all(lo <= t < hi for t in temperatures)


# ------------------------------------------------------------------------------------ the claims


@dataclasses.dataclass(frozen=True)
class Tested:
    """The values, one a run, behind one of a claim's tests, oriented so that the paper's effect
    is positive; what `power` needs to say how many seeds the test wants.

    One sample (`y` None): the effect is mean(x) - `null`, tested by its 95% t interval. Two
    samples: mean(x) - mean(y), Welch's t. `blocked`: `x` is a [treatments, seeds] table of a claim
    of *no* difference, tested by `block_anova`. `runs_per_seed`: the runs one seed adds to `x`
    (the claims that pool every policy of a sweep add one run per policy)."""

    x: np.ndarray
    y: np.ndarray | None = None
    null: float = 0.0
    runs_per_seed: int = 1
    blocked: bool = False


@dataclasses.dataclass
class ClaimResult:
    """One row of the claims table. `values`: the numbers behind `statistic` (None where the data
    cannot give them). `tests`: {label: `Tested`} for each test the verdict rests on."""

    key: str
    claim: str
    evidence: str
    statistic: str
    verdict: str
    values: dict = dataclasses.field(default_factory=dict)
    tests: dict = dataclasses.field(default_factory=dict)


VERDICTS = ("holds", "does not hold", "not testable")


def claim_curiosity_dip_and_rise(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 1: curiosity falls in the first few thousand steps, then rises again (figs. 8, 17, 18).

    Measured per run on the curiosity (window means, averaged over the agents), as means over
    fixed blocks of steps placed where the paper's figures put them: early = steps 0-2,000 (the
    initial high level), trough = steps 10,000-30,000 (the paper's minima: ~5,000-15,000 in fig. 8,
    20,000-25,000 in fig. 17, 10,000-30,000 in fig. 18), late = the last 10,000 steps.
    fall = early - trough, rise = late - trough. Fixed blocks, not each run's own minimum: a
    minimum picked out of noise lies below the curve's level, so `late - minimum` is positive even
    for a flat curve. Groups: single_agent eps (fig. 8), multi_agent eps (fig. 17) and ucb (fig. 18),
    those loaded. (Fig. 15, walls different, shows a fall and then a plateau, not a rise; left out.)
    Verdict: holds if in every group the 95% CIs of both fall and rise lie above 0. Scale: runs of
    >= 40,000 steps (the late block must start after the trough block), >= MIN_SEEDS seeds a group.
    """
    key, claim = "1", "Curiosity falls in the first few thousand steps, then rises again"
    evidence = "figs. 8 (single agent, ε-greedy), 17 (two agents, ε-greedy), 18 (two agents, UCB); one run each"
    sources = [("single_agent", "eps", "fig. 8"), ("multi_agent", "eps", "fig. 17"), ("multi_agent", "ucb", "fig. 18")]
    groups = _source_groups(presets, sources)
    if not groups:
        return ClaimResult(key, claim, evidence, "n/a", _missing(("single_agent", "multi_agent"), presets))
    parts, values, fails, tests = [], {}, [], {}
    for label, s, g in groups:
        d = curiosity_fall_rise(s, g)
        fall, rise = mean_ci(d["fall"]), mean_ci(d["rise"])
        tests.update({f"{label} fall": Tested(d["fall"]), f"{label} rise": Tested(d["rise"])})
        parts.append(f"{label}: fall {_ci(fall)}, rise {_ci(rise)}")
        values.update({f"{label} fall": _num(fall[0]), f"{label} fall low": _num(fall[1]),
                       f"{label} rise": _num(rise[0]), f"{label} rise low": _num(rise[1])})
        if not (fall[1] > 0 and rise[1] > 0):
            fails.append(f"{label}: {'fall' if not fall[1] > 0 else 'rise'} CI does not lie above 0")
    gap = _scale_gaps([(s, 40_000, {label: g.n}) for label, s, g in groups])
    gaps = [gap] if gap else []
    stat = ("mean over runs [95% CI] of fall = curiosity(steps 0-2k) - curiosity(10k-30k) and "
            "rise = curiosity(last 10k steps) - curiosity(10k-30k); " + "; ".join(parts))
    return ClaimResult(key, claim, evidence, stat, _decide(gaps, fails, "every fall and rise CI above 0"), values,
                       tests)


def curiosity_fall_rise(sweep: Sweep, group: Group) -> dict:
    """Per run of `group`: {"early", "trough", "late", "fall", "rise"} (arrays [runs]); the blocks
    of `claim_curiosity_dip_and_rise`, NaN where a block holds no window."""
    return fall_rise(sweep, _nanmean(sweep.metrics["curiosity"][group.indices].astype(float), axis=2))


def fall_rise(sweep: Sweep, c: np.ndarray) -> dict:
    """`curiosity_fall_rise` of any per-run series c [runs, windows] of `sweep`."""
    t = sweep.steps_done
    early = block_mean(sweep, c, 0, 2_000)
    trough = block_mean(sweep, c, 10_000, 30_000)
    late = block_mean(sweep, c, max(t - 10_000, 30_000), t)
    return {"early": early, "trough": trough, "late": late, "fall": early - trough, "rise": late - trough}


def claim_contact_ranking(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 2: UCB gives the most agent-object and agent-agent contacts, Boltzmann the fewest
    agent-object contacts (figs. 21, 22, section 4.1.5).

    Measured on multi_agent, per run: agent-object contact steps over the whole run (summed over
    both agents and the four objects, `stats.object_contacts`), and steps with the agents touching
    (`stats.agent_contacts`). One group per policy (the paper's setting where a sweep has several).
    Five Welch t-tests across runs: objects UCB > ε-greedy, UCB > Boltzmann, Boltzmann < ε-greedy;
    agent-agent UCB > ε-greedy, UCB > Boltzmann. Verdict: holds if all five have p < 0.05 with the
    paper's sign (requiring every one to pass needs no multiple-test correction). Scale: runs of
    >= 40,000 steps (fig. 21: Boltzmann's contacts stop at ~30,000, UCB has 60% of its total by
    40,000), >= MIN_SEEDS seeds a policy.
    """
    key, claim = "2", "UCB gives the most agent-object and agent-agent contacts; Boltzmann the fewest object contacts"
    evidence = "figs. 21, 22 and section 4.1.5 (two agents; one run per policy)"
    s = presets.get("multi_agent")
    if s is None:
        return ClaimResult(key, claim, evidence, "n/a", _missing(("multi_agent",), presets))
    gs = {p: _paper_group(s, p) for p in ("eps", "boltzmann", "ucb")}
    if any(g is None for g in gs.values()):
        lacking = [p for p, g in gs.items() if g is None]
        return ClaimResult(key, claim, evidence, "n/a", f"not testable: {s.name} (multi_agent) has no runs of "
                                                        f"{', '.join(lacking)}")
    obj = object_contacts(s).sum(axis=1).astype(float)
    agt = agent_contacts(s).sum(axis=1).astype(float)
    tests = {  # (label, values of the higher side, values of the lower side)
        "objects UCB > ε": (obj[gs["ucb"].indices], obj[gs["eps"].indices]),
        "objects UCB > Boltzmann": (obj[gs["ucb"].indices], obj[gs["boltzmann"].indices]),
        "objects ε > Boltzmann": (obj[gs["eps"].indices], obj[gs["boltzmann"].indices]),
        "agent-agent UCB > ε": (agt[gs["ucb"].indices], agt[gs["eps"].indices]),
        "agent-agent UCB > Boltzmann": (agt[gs["ucb"].indices], agt[gs["boltzmann"].indices]),
    }
    values, parts = {}, []
    for what, arr in (("objects", obj), ("agent-agent", agt)):
        cells = []
        for p, g in gs.items():
            m = mean_ci(arr[g.indices])
            values[f"{what} {p}"] = _num(m[0])
            cells.append(f"{_short(p)} {_ci(m, 0)}")
        parts.append(f"{what} contact steps per run: " + ", ".join(cells))
    fails, tparts = [], []
    for label, (hi, lo) in tests.items():
        w = welch_t(hi, lo)
        values[f"{label} t"], values[f"{label} p"] = _num(w["t"]), _num(w["p"])
        tparts.append(f"{label}: t={_f(w['t'])}, p={_p(w['p'])}")
        if not (w["p"] < ALPHA and w["diff"] > 0):
            fails.append(label)
    gap = _scale_gap(s, 40_000, {g.label: g.n for g in gs.values()})
    stat = f"{s.name}: " + "; ".join(parts) + ". Welch t: " + "; ".join(tparts)
    return ClaimResult(key, claim, evidence, stat,
                       _decide([gap] if gap else [], [f"not significant: {', '.join(fails)}"] if fails else [],
                               "all five Welch tests p < 0.05 in the paper's direction"), values,
                       {label: Tested(hi, lo) for label, (hi, lo) in tests.items()})


def claim_two_agents_higher(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 3: two agents have higher curiosity and a higher VAE loss than one (figs. 23, 24).

    Measured on the UCB runs (the paper's choice) of single_agent and multi_agent, per run, as
    means over the second half of the steps both sweeps have run (after the initial fall; the same
    steps on both sides when one sweep is longer): curiosity (averaged over the
    agents) and the VAE loss per image (`stats.per_agent_vae_loss`: the two-agent loss of eq. 5
    sums both views, so it is halved; the summed loss is ~2x a single agent's by construction).
    Welch t multi - single for each. Verdict: holds if both differences are positive with p < 0.05.
    Scale: runs of >= 10,000 steps (the second half then starts after the fall, ~5,000 steps in
    fig. 8), >= MIN_SEEDS seeds a side; the two sweeps must have the same image size.
    """
    key, claim = "3", "Two agents have higher curiosity and a higher VAE loss than one"
    evidence = "figs. 23, 24, section 4.2 (UCB; one single-agent and one two-agent run)"
    single, multi = presets.get("single_agent"), presets.get("multi_agent")
    if single is None or multi is None:
        return ClaimResult(key, claim, evidence, "n/a", _missing(("single_agent", "multi_agent"), presets))
    gs, gm = _paper_group(single, "ucb"), _paper_group(multi, "ucb")
    if gs is None or gm is None:
        return ClaimResult(key, claim, evidence, "n/a", "not testable: " + " and ".join(
            f"{s.name} has no UCB runs" for s, g in ((single, gs), (multi, gm)) if g is None))
    # The same steps on both sides: curiosity and loss drift over training, so a longer sweep's
    # later half would not be comparable with a shorter one's.
    common = min(single.steps_done, multi.steps_done)
    lo, hi = common // 2, common
    cur = {w: block_mean(s, _nanmean(s.metrics["curiosity"][g.indices].astype(float), axis=2), lo, hi)
           for w, s, g in (("single", single, gs), ("multi", multi, gm))}
    vae = {w: block_mean(s, per_agent_vae_loss(s)[g.indices].astype(float), lo, hi)
           for w, s, g in (("single", single, gs), ("multi", multi, gm))}
    values, parts, fails, tests = {}, [], [], {}
    for what, d in (("curiosity", cur), ("VAE loss per image", vae)):
        ms, mm = mean_ci(d["single"]), mean_ci(d["multi"])
        tests[f"{what}: two agents > one"] = Tested(d["multi"], d["single"])
        w = welch_t(d["multi"], d["single"])
        values.update({f"{what} single": _num(ms[0]), f"{what} multi": _num(mm[0]), f"{what} t": _num(w["t"]),
                       f"{what} p": _num(w["p"])})
        parts.append(f"{what}: one agent {_ci(ms)}, two agents {_ci(mm)}, Welch t={_f(w['t'])}, p={_p(w['p'])}")
        if not (w["p"] < ALPHA and w["diff"] > 0):
            fails.append(f"{what} not significantly higher with two agents")
    gap = _scale_gaps([(single, 10_000, {f"{single.name} UCB": gs.n}), (multi, 10_000, {f"{multi.name} UCB": gm.n})])
    gaps = [gap] if gap else []
    if single.image != multi.image:
        return ClaimResult(key, claim, evidence, "; ".join(parts),
                           f"not testable: {single.name} ({single.image} px) and {multi.name} ({multi.image} px) "
                           "differ in image size", values)
    stat = (f"mean over steps {lo:,}-{hi:,} of each run (the second half of the steps both sweeps ran), "
            f"{single.name} vs {multi.name}: " + "; ".join(parts))
    return ClaimResult(key, claim, evidence, stat, _decide(gaps, fails, "both Welch tests p < 0.05, multi > single"),
                       values, tests)


def claim_agents_move_together(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 4: the two agents' curiosity curves move together ("remarkably similar", 4.1.2, 5).

    Measured on every run of multi_agent: the Pearson correlation of the two agents' smoothed
    curiosity (trailing moving average of 50 windows, the curve of fig. 17), on Fisher's z scale,
    minus a baseline: the mean z of the correlation between an agent of this run and the other
    agent of each other run of the same group (same policy and setting, other seed), in both
    pairings. The baseline has the same learning trend and the same policy but no shared events,
    so the difference is what the shared run adds. Verdict: holds if the 95% CI of the mean
    difference across runs lies above 0. Scale: runs of >= 10,000 steps (>= 10 stretches of 1,000
    steps, the smoothing span), >= MIN_SEEDS runs with a baseline (2+ seeds in their group).
    """
    key, claim = "4", "The two agents' curiosity curves move together"
    evidence = "section 4.1.2 (fig. 17: 'remarkably similar'), section 5; one run"
    s = presets.get("multi_agent")
    if s is None:
        return ClaimResult(key, claim, evidence, "n/a", _missing(("multi_agent",), presets))
    d = agent_curiosity_coupling(s)
    within, cross, diff = mean_ci(d["within"]), mean_ci(d["cross"]), mean_ci(d["diff"])
    n = int(np.isfinite(d["diff"]).sum())
    values = {"within z": _num(within[0]), "cross-run z": _num(cross[0]), "diff": _num(diff[0]),
              "diff low": _num(diff[1]), "diff high": _num(diff[2]), "runs": n}
    stat = (f"{s.name}, runs: {n}: Fisher z of the agents' correlation (smoothed curiosity) within a run "
            f"{_ci(within)} (r={_f(np.tanh(within[0]))}), agents of different runs of the same group {_ci(cross)} "
            f"(r={_f(np.tanh(cross[0]))}); within - baseline {_ci(diff)}")
    gap = _scale_gap(s, 10_000, {"runs with a baseline": n})
    fails = [] if diff[1] > 0 else ["the within-run correlation is not above the cross-run baseline"]
    tests = {"within-run z - cross-run z": Tested(d["diff"], runs_per_seed=len(s.groups()))}
    return ClaimResult(key, claim, evidence, stat, _decide([gap] if gap else [], fails, "the CI above 0"), values,
                       tests)


def agent_curiosity_coupling(sweep: Sweep, window: int = SMOOTH) -> dict:
    """Per run: {"within" z of corr(agent 0, agent 1), "cross" the baseline z, "diff" within -
    cross} (arrays [runs], NaN where a run's group has no other run); see
    `claim_agents_move_together`."""
    c = moving_average(sweep.metrics["curiosity"].astype(float), window, axis=1)  # [R, W, 2]
    n = sweep.n_runs
    within, cross = np.full(n, np.nan), np.full(n, np.nan)
    for g in sweep.groups():
        for i in g.indices:
            within[i] = fisher_z(pearson_r(c[i, :, 0], c[i, :, 1]))
            others = [j for j in g.indices if j != i]
            if others:
                cross[i] = np.mean([(fisher_z(pearson_r(c[i, :, 0], c[j, :, 1]))
                                     + fisher_z(pearson_r(c[j, :, 0], c[i, :, 1]))) / 2 for j in others])
    return {"within": within, "cross": cross, "diff": within - cross}


MOVING_OBJECTS = ("sphere", "cylinder")


def claim_prefers_moving_objects(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 5: the agent prefers objects that move (the sphere, the toppled rolling cylinder) to
    the static ones (pyramid, disc) (section 4.1, fig. 9).

    Measured on the ε-greedy runs of single_agent (fig. 9's run), per run over the whole run: the
    share of agent-object contact steps that are with the sphere or the cylinder (runs with fewer
    than 20 contact steps in all are left out: no preference to measure), and, reported alongside,
    the same share of the view (object pixels only). Null: 0.5, no preference between the pairs.
    The pairs differ in size and starting place, so 0.5 is only a first-order null. Verdict: holds
    if the 95% CI of the contact share lies above 0.5. Scale: runs of >= 40,000 steps (the agent
    first interacts often with objects at ~25,000 steps in fig. 9), >= MIN_SEEDS runs with contacts.
    """
    key, claim = "5", "The agent prefers objects that move (sphere, toppled cylinder) to static ones"
    evidence = "section 4.1, fig. 9 (one agent, ε-greedy; one run)"
    s = presets.get("single_agent")
    if s is None:
        return ClaimResult(key, claim, evidence, "n/a", _missing(("single_agent",), presets))
    g = _paper_group(s, "eps")
    if g is None:
        return ClaimResult(key, claim, evidence, "n/a", f"not testable: {s.name} has no ε-greedy runs")
    d = moving_object_shares(s, g)
    c, v = mean_ci(d["contact_share"]), mean_ci(d["view_share"])
    n = int(np.isfinite(d["contact_share"]).sum())
    values = {"contact share": _num(c[0]), "contact share low": _num(c[1]), "view share": _num(v[0]), "runs": n}
    stat = (f"{s.name} {g.label}: share of contact steps with sphere+cylinder {_ci(c)} ({n} runs with >= 20 contact "
            f"steps); share of object pixels in view {_ci(v)}; null 0.5")
    gap = _scale_gap(s, 40_000, {"runs with contacts": n})
    fails = [] if c[1] > 0.5 else ["the contact share's CI does not lie above 0.5"]
    tests = {"sphere+cylinder share of contacts > 0.5": Tested(d["contact_share"], null=0.5)}
    return ClaimResult(key, claim, evidence, stat, _decide([gap] if gap else [], fails, "the CI above 0.5"), values,
                       tests)


def moving_object_shares(sweep: Sweep, group: Group, min_contacts: int = 20) -> dict:
    """Per run of `group`: {"contact_share", "view_share"} of the sphere and cylinder among the
    four objects, over the whole run and all agents (contact share NaN below `min_contacts`)."""
    mov = [sweep.objects.index(o) for o in MOVING_OBJECTS]
    k = len(sweep.objects)
    contacts = sweep.metrics["contact_object"][group.indices].astype(float).sum(axis=(1, 2))  # [n, K]
    total = contacts.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        contact_share = np.where(total >= min_contacts, contacts[:, mov].sum(axis=1) / total, np.nan)
        view = _nanmean(sweep.metrics["view_fraction"][group.indices][..., :k].astype(float), axis=(1, 2))  # [n, K]
        view_share = view[:, mov].sum(axis=1) / view.sum(axis=1)
    return {"contact_share": contact_share, "view_share": view_share}


def claim_stop_least(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 6a: `stop` is the action chosen least (figs. 10, 12).

    Measured on the ε-greedy runs (the policy of figs. 10 and 12) of single_agent,
    single_agent_walls_different and multi_agent, those loaded, per run over the whole run and all
    agents: the margin = (share of the least chosen other action) - (share of stop); positive when
    stop is the least chosen. Verdict: holds if in every group the 95% CI of the margin lies above 0.
    Scale: runs of >= 10,000 steps (the self-model must first learn that stop is dull),
    >= MIN_SEEDS seeds a group.
    """
    key, claim = "6a", "'stop' is the action chosen least"
    evidence = "figs. 10, 12, section 4.1.1 (one agent, ε-greedy; one run each)"
    sources = [("single_agent", "eps", "fig. 10"), ("single_agent_walls_different", "eps", "fig. 12"),
               ("multi_agent", "eps", "two agents")]
    groups = _source_groups(presets, sources)
    if not groups:
        return ClaimResult(key, claim, evidence, "n/a", _missing(("single_agent", "multi_agent"), presets))
    parts, values, fails, tests = [], {}, [], {}
    for label, s, g in groups:
        if "stop" not in s.actions:
            return ClaimResult(key, claim, evidence, "n/a", f"not testable: {s.name} has no 'stop' action")
        shares = action_shares(s, g)
        stop = s.actions.index("stop")
        margin = np.delete(shares, stop, axis=1).min(axis=1) - shares[:, stop]
        m, st = mean_ci(margin), mean_ci(shares[:, stop])
        tests[f"{label} margin"] = Tested(margin)
        values.update({f"{label} margin": _num(m[0]), f"{label} margin low": _num(m[1]),
                       f"{label} stop share": _num(st[0])})
        parts.append(f"{label}: stop share {_ci(st)}, margin {_ci(m)}")
        if not m[1] > 0:
            fails.append(f"{label}: the margin's CI does not lie above 0")
    gap = _scale_gaps([(s, 10_000, {label: g.n}) for label, s, g in groups])
    gaps = [gap] if gap else []
    stat = ("margin = share of the least chosen other action - share of stop, mean over runs [95% CI]; "
            + "; ".join(parts))
    return ClaimResult(key, claim, evidence, stat, _decide(gaps, fails, "every margin CI above 0"), values, tests)


def claim_rotations_less(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 6c: with a different texture on every wall, the rotations are chosen somewhat less
    often than the four moves, which are chosen about equally (fig. 12, section 4.1.1).

    Measured on the ε-greedy runs of single_agent_walls_different (fig. 12's run), per run over
    the whole run: the margin = (mean share of forward, backward, left, right) - (mean share of
    rotate_left, rotate_right); positive when the rotations are chosen less. Verdict: holds if
    its 95% CI lies above 0. Context, not the verdict: the same margin on single_agent's
    ε-greedy runs (identical walls, fig. 10), where loaded. Scale: runs of >= 10,000 steps (as
    claim 6a), >= MIN_SEEDS seeds.
    """
    key, claim = "6c", "Rotations are chosen less often than the four moves"
    evidence = "fig. 12, section 4.1.1 (one agent, ε-greedy, every wall different; one run)"
    groups = _source_groups(presets, [("single_agent_walls_different", "eps", "fig. 12")])
    if not groups:
        return ClaimResult(key, claim, evidence, "n/a", _missing(("single_agent_walls_different",), presets))
    groups += _source_groups(presets, [("single_agent", "eps", "fig. 10, identical walls; context")])
    parts, values, margins = [], {}, []
    for label, s, g in groups:
        margin = move_rotation_margin(s, g)
        if margin is None:
            return ClaimResult(key, claim, evidence, "n/a", f"not testable: {s.name} lacks the moves or rotations")
        m = mean_ci(margin)
        values.update({f"{label} margin": _num(m[0]), f"{label} margin high": _num(m[2])})
        parts.append(f"{label}: margin {_ci(m)}")
        margins.append(margin)
    (label, s, g), margin = groups[0], margins[0]  # fig. 12's runs decide; the rest is context
    low, high = mean_ci(margin)[1:3]
    other_way = " (it lies below: the other way)" if high < 0 else ""
    fails = [] if low > 0 else [f"the margin's CI does not lie above 0{other_way}"]
    gap = _scale_gap(s, 10_000, {label: g.n})
    stat = ("margin = a move's mean share - a rotation's mean share (per run, the four moves and the two rotations), "
            "mean over runs [95% CI]; " + "; ".join(parts))
    return ClaimResult(key, claim, evidence, stat, _decide([gap] if gap else [], fails, "the margin's CI above 0"),
                       values, {f"{label} margin": Tested(margin)})


def move_rotation_margin(sweep: Sweep, group: Group) -> np.ndarray | None:
    """[runs of the group]: the mean share of the four moves minus that of the two rotations
    (`action_shares`); None where the sweep's actions lack one of them."""
    moves, turns = ("forward", "backward", "left", "right"), ("rotate_left", "rotate_right")
    if not set(moves + turns) <= set(sweep.actions):
        return None
    shares = action_shares(sweep, group)
    return (shares[:, [sweep.actions.index(a) for a in moves]].mean(axis=1)
            - shares[:, [sweep.actions.index(a) for a in turns]].mean(axis=1))


def action_shares(sweep: Sweep, group: Group) -> np.ndarray:
    """[runs of the group, actions]: each action's share of all steps of the run (agents pooled)."""
    counts = sweep.metrics["action_counts"][group.indices].astype(float).sum(axis=(1, 2))
    return counts / np.maximum(counts.sum(axis=1, keepdims=True), 1)


def claim_boltzmann_trembles(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 6b: Boltzmann agents "tremble" (rapid alternating rotations; section 5), where tuned
    ε-greedy and UCB do not.

    Measured where a sweep records it (`rotation_reversals`): on multi_agent, or where that sweep
    does not, on the first of its side experiments that does (`multi_agent.<label>`, e.g.
    `multi_agent.order`: the same settings, its own seeds and length; `assign_presets`). Per run,
    over the whole run and both agents: the reversal rate = steps at which an agent turned the other way
    than at the step before, over the pairs of consecutive steps inside the 20-step windows (a
    uniformly random choice of the 7 actions: 2/49 = 0.041). Welch t: Boltzmann > ε-greedy and
    Boltzmann > UCB; holds if both are significant in that direction. Beside it, as context: the
    reversals against a random order of each window's own actions (`reversals_against_shuffled`),
    which tells a policy that alternates apart from one that merely turns often; and the paper's
    words read the other way, rotating often (`rotation_share`, on the preset's own sweep).

    Sweeps made before that metric record how often each action was taken per window, not the
    order. Their balanced-rotation share, 2 * min(rotate_left, rotate_right) / steps summed over
    windows, is the most steps alternating turns could fill: an upper bound on each policy's
    alternation, and a comparison of upper bounds cannot order the alternation itself (a policy
    with the higher bound may alternate less). It is shown, and the verdict is "not testable".
    Scale: runs of >= 20,000 steps, >= MIN_SEEDS seeds a policy.
    """
    key, claim = "6b", "Boltzmann agents 'tremble' (rapid alternating rotations)"
    evidence = "section 5 (qualitative, from videos)"
    candidates = preset_and_sides(presets, "multi_agent")
    if not candidates:
        return ClaimResult(key, claim, evidence, "n/a", _missing(("multi_agent",), presets))
    s = next((c for c in candidates if "rotation_reversals" in c.metrics), candidates[0])
    gs = {p: _paper_group(s, p) for p in ("boltzmann", "eps", "ucb")}
    if gs["boltzmann"] is None or (gs["eps"] is None and gs["ucb"] is None):
        return ClaimResult(key, claim, evidence, "n/a", f"not testable: {s.name} lacks Boltzmann or comparison runs")
    if not {"rotate_left", "rotate_right"} <= set(s.actions):
        return ClaimResult(key, claim, evidence, "n/a", f"not testable: {s.name} has no rotate actions")
    direct = "rotation_reversals" in s.metrics
    measure, name = (reversal_rate(s), "reversal rate") if direct else (balanced_rotation_share(s), "balanced rotation")
    values, parts, fails = {}, [], []
    for p, g in gs.items():
        if g is not None:
            m = mean_ci(measure[g.indices])
            values[f"{p} {name}"] = _num(m[0])
            parts.append(f"{_short(p)} {_ci(m)}")
    tparts, tests = [], {}
    for p in ("eps", "ucb"):
        if gs[p] is None:
            continue
        w = welch_t(measure[gs["boltzmann"].indices], measure[gs[p].indices])
        values[f"Boltzmann > {p} p"] = _num(w["p"])
        tparts.append(f"Boltzmann > {_short(p)}: t={_f(w['t'])}, p={_p(w['p'])}")
        if direct:  # a test of the claim itself; the bound's comparison is not one
            tests[f"reversal rate Boltzmann > {_short(p)}"] = Tested(measure[gs["boltzmann"].indices],
                                                                     measure[gs[p].indices])
        if not (w["p"] < ALPHA and w["diff"] > 0):
            fails.append(f"Boltzmann not significantly above {_short(p)}")
    if direct:
        stat = (f"{s.name}: reversal rate, steps turning the other way than the step before per pair of consecutive "
                f"steps in a 20-step window (a uniformly random policy: 2/49 = 0.041): {', '.join(parts)}; "
                + "; ".join(tparts))
        stat += "; " + _order_beyond_counts(s, gs, values)
    else:
        stat = (f"{s.name}: balanced-rotation share 2*min(rotate_left, rotate_right)/steps per 20-step window "
                f"(an upper bound on alternating turns; this sweep does not record their order): {', '.join(parts)}; "
                + "; ".join(tparts))
    stat += "; " + _rotating_often(candidates[0], values)
    gap = _scale_gap(s, 20_000, {g.label: g.n for g in gs.values() if g is not None})
    if gap:
        verdict = f"not testable at this scale (needs {gap})"
    elif not direct:
        verdict = ("not testable: the sweep does not record the order of actions (rotation_reversals), and upper "
                   "bounds on alternation cannot order the policies' alternation")
    elif fails:
        verdict = "does not hold: " + "; ".join(fails)
    else:
        verdict = "holds (Boltzmann's reversal rate significantly above the other policies')"
    return ClaimResult(key, claim, evidence, stat, verdict, values, tests)


def _order_beyond_counts(s: Sweep, gs: dict, values: dict) -> str:
    """Claim 6b's context, not its verdict: whether each policy turns back more than the order of
    its own turns would by chance (`reversals_against_shuffled`), which separates alternating
    from merely turning often. Adds its figures to `values`; returns its text."""
    parts, tests = _boltzmann_against_others(reversals_against_shuffled(s), gs, "reversals / shuffled", values)
    return ("reversals over those a random order of each window's own actions would give (1: turns in no "
            f"particular order; context, not the verdict): {parts}; {tests}")


def _rotating_often(s: Sweep, values: dict) -> str:
    """Claim 6b's other reading, context only: the paper's words ("exploit rapid rotations") may
    mean rotating often rather than turning back. Each policy's share of steps rotating either way
    on `s` (the preset's own sweep, with the most seeds), Welch tests of Boltzmann against the
    others. Adds its figures to `values`; returns its text."""
    gs = {p: _paper_group(s, p) for p in ("boltzmann", "eps", "ucb")}
    parts, tests = _boltzmann_against_others(rotation_share(s), gs, "rotation share", values)
    n = len(s.actions)
    return (f"read as rotating often (context, not the verdict), {s.name}'s share of steps rotating either way (a "
            f"uniformly random policy: 2/{n} = {2 / n:.3f}): {parts}; {tests}")


def _boltzmann_against_others(x: np.ndarray, gs: dict, name: str, values: dict) -> tuple[str, str]:
    """Claim 6b's context measures: `x` (one value a run) per policy group of `gs` as mean [95% CI],
    and Welch tests of Boltzmann against ε-greedy and UCB; into `values` as "<policy> <name>" and
    "<name> Boltzmann > <policy> p". Returns the two texts."""
    parts, tests = [], []
    for p, g in gs.items():
        if g is not None:
            m = mean_ci(x[g.indices])
            values[f"{p} {name}"] = _num(m[0])
            parts.append(f"{_short(p)} {_ci(m)}")
    for p in ("eps", "ucb"):
        if gs[p] is not None and gs["boltzmann"] is not None:
            w = welch_t(x[gs["boltzmann"].indices], x[gs[p].indices])
            values[f"{name} Boltzmann > {p} p"] = _num(w["p"])
            tests.append(f"Boltzmann > {_short(p)}: t={_f(w['t'])}, p={_p(w['p'])}")
    return ", ".join(parts), "; ".join(tests)


def rotation_share(sweep: Sweep) -> np.ndarray:
    """[runs]: the share of steps on which an agent rotated, either way (agents pooled)."""
    rl, rr, total = _turn_counts(sweep)
    return (rl + rr).sum(axis=(1, 2)) / np.maximum(total, 1)


def _turn_counts(sweep: Sweep) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """rotate_left and rotate_right counts [runs, windows, agents], and each run's steps taken."""
    a = sweep.metrics["action_counts"].astype(float)  # [R, W, agents, actions]
    rl, rr = a[..., sweep.actions.index("rotate_left")], a[..., sweep.actions.index("rotate_right")]
    return rl, rr, a.sum(axis=(1, 2, 3))


def reversal_rate(sweep: Sweep) -> np.ndarray:
    """[runs]: steps at which an agent turned the other way than at the step before, over the
    pairs of consecutive steps taken inside the windows (agents pooled)."""
    t = turn_reversals(sweep)
    return t["observed"].sum(axis=1) / np.maximum(t["pairs"].sum(axis=1), 1)


def reversals_against_shuffled(sweep: Sweep) -> np.ndarray:
    """[runs]: the reversals an agent made over those a random order of each window's own actions
    would make on average (agents pooled, windows summed; `stats.turn_reversals`): 1 where the
    turns come in no particular order, above 1 where an agent turns back more often than its turn
    counts alone explain, below 1 where its turns come in runs of one direction; NaN for a run
    that never turned both ways in a window."""
    t = turn_reversals(sweep)
    return nan_ratio(t["observed"].sum(axis=1), t["shuffled"].sum(axis=1))


def balanced_rotation_share(sweep: Sweep) -> np.ndarray:
    """[runs]: sum over windows and agents of 2 * min(rotate_left, rotate_right), over the steps
    taken (agents pooled): the share of steps alternating turns could at most account for."""
    rl, rr, total = _turn_counts(sweep)
    return 2 * np.minimum(rl, rr).sum(axis=(1, 2)) / np.maximum(total, 1)


def claim_temperatures_alike(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 7: Boltzmann temperatures 0.5-2.5 make no significant difference (fig. 19, 4.1.4).

    Measured on boltzmann_temperatures, per run: the late curiosity = mean over the last quarter
    of the run (after the initial drop, where fig. 19's curves converge), averaged over the agents.
    One-way ANOVA across the temperature groups (F test; p from the F distribution), with eta^2,
    and the same test blocked by seed (`block_anova` on the seeds every temperature ran): runs of
    one seed draw the same random numbers and, with a near-uniform policy, share much of their
    course (`seed_coupling`), so they are not independent samples and the one-way test's error term
    holds the seeds' variance. Verdict, from the blocked test where it is defined (else the
    one-way): holds if p >= 0.05 (no significant difference, the paper's claim; with few seeds a
    temperature, only a sizeable effect would be detected), does not hold if p < 0.05. Scale: >= 2
    temperatures, runs of >= 40,000 steps, >= MIN_SEEDS seeds a temperature.
    """
    key, claim = "7", "Boltzmann temperatures 0.5-2.5 make no significant difference"
    evidence = "fig. 19, section 4.1.4 (one run per temperature)"
    s = presets.get("boltzmann_temperatures")
    if s is None:
        return ClaimResult(key, claim, evidence, "n/a", _missing(("boltzmann_temperatures",), presets))
    gs = sorted(s.groups("boltzmann"), key=lambda g: g.value)
    late = late_curiosity(s)
    a = one_way_anova([late[g.indices] for g in gs])
    table = seed_table(s, gs, late)
    blocked = block_anova(table)
    cells = [f"T={g.value:g} {_ci(mean_ci(late[g.indices]))}" for g in gs]
    values = {"F": _num(a["F"]), "p": _num(a["p"]), "eta2": _num(a["eta2"]), "df1": a["df1"], "df2": a["df2"],
              "F_blocked": _num(blocked["F"]), "p_blocked": _num(blocked["p"]), "df2_blocked": blocked["df2"],
              "seed_share": _num(blocked["block_share"])}
    values.update({f"T={g.value:g}": _num(np.nanmean(late[g.indices])) for g in gs})
    stat = (f"{s.name}: late curiosity (last quarter of the run) per temperature: {', '.join(cells)}; one-way ANOVA "
            f"F({a['df1']}, {a['df2']})={_f(a['F'])}, p={_p(a['p'])}, eta²={_f(a['eta2'])}")
    use_blocked = math.isfinite(blocked["p"])
    if use_blocked:
        stat += (f"; blocked by seed ({blocked['b']} seeds, {_f(100 * blocked['block_share'], 2)} % of the variance) "
                 f"F({blocked['df1']}, {blocked['df2']})={_f(blocked['F'])}, p={_p(blocked['p'])}")
        eq = equivalence_bound(table, ALPHA)
        values.update(equivalence_bound=_num(eq["bound"]), largest_difference=_num(eq["largest"]))
        if math.isfinite(eq["bound"]):
            stat += (f"; equivalence (context, not the verdict: two one-sided tests at 5 % for every two "
                     f"temperatures, blocked by seed): the data rule out differences beyond ±{_f(eq['bound'])} "
                     f"(largest observed {_f(eq['largest'])})")
    p = blocked["p"] if use_blocked else a["p"]
    gaps = []
    if len(gs) < 2:
        gaps.append(f">= 2 temperatures; {s.name} has {len(gs)}")
    gap = _scale_gap(s, 40_000, {g.label: g.n for g in gs})
    if gap:
        gaps.append(gap)
    if gaps:
        return ClaimResult(key, claim, evidence, stat, f"not testable at this scale (needs {'; '.join(gaps)})", values)
    if not np.isfinite(p):
        return ClaimResult(key, claim, evidence, stat, "not testable: the ANOVA is undefined (no spread)", values)
    verdict = "holds" if p >= ALPHA else f"does not hold: the temperatures differ (p={_p(p)})"
    tests = {"late curiosity, two temperatures apart": Tested(table, blocked=True)} if use_blocked else {}
    return ClaimResult(key, claim, evidence, stat, verdict, values, tests)


def late_curiosity(sweep: Sweep, fraction: float = 0.25) -> np.ndarray:
    """[runs]: mean curiosity over the last `fraction` of the windows, averaged over agents."""
    k = max(1, int(math.ceil(fraction * sweep.n_windows)))
    return _nanmean(sweep.metrics["curiosity"][:, -k:].astype(float), axis=(1, 2))


def seed_coupling(sweep: Sweep, a: Group, b: Group) -> dict:
    """How alike two groups' runs are when they share a seed, against when they do not.

    Runs of one seed draw the same random numbers, so where a policy barely depends on its setting
    (a near-uniform Boltzmann policy at any T) they repeat much of each other's actions. For each
    pair of runs, one from `a` and one from `b`: `identical`, the share of metrics windows in which
    an agent's action counts are identical (mean over agents), and `r`, the Pearson correlation
    of the two runs' curiosity curves (window means, mean over agents). Returns {"same": ...,
    "other": ...}, each {"identical": [...], "r": [...]}, one value per pair: pairs of the same
    seed, in seed order, and pairs of different seeds."""
    counts = sweep.metrics["action_counts"]
    curiosity = _nanmean(sweep.metrics["curiosity"].astype(float), axis=2)
    out = {kind: {"identical": [], "r": []} for kind in ("same", "other")}
    pairs = sorted(((sweep.runs[i].seed, i, j) for i in a.indices for j in b.indices),
                   key=lambda p: (sweep.runs[p[1]].seed != sweep.runs[p[2]].seed, p))
    for seed, i, j in pairs:
        kind = out["same" if seed == sweep.runs[j].seed else "other"]
        kind["identical"].append(float((counts[i] == counts[j]).all(axis=-1).mean()))
        kind["r"].append(pearson_r(curiosity[i], curiosity[j]))
    return out


def claim_self_model_predicts(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 8: the self-model knows what will surprise it (its role, sections 3.2, 5): its
    predicted curiosity of the chosen action tracks the curiosity obtained, better as it trains
    and better than a baseline that predicts each action's running mean.

    Where the sweep records each window's variances and covariance of the per-step predicted and
    obtained curiosity, and each action's mean curiosity (sweeps made since those metrics were
    added), the correlations are of per-step pairs, pooled within windows
    (`self_model.step_tracking`); the rest of the test is the same. Read from multi_agent, or,
    where that sweep lacks them, from the first side experiment of multi_agent that has them.
    Older sweeps hold, per 20-step window and agent, only the mean predicted curiosity of the
    actions taken (`predicted`), the mean obtained (`curiosity`) and the action counts. Measured
    on them per run of multi_agent and agent, the window means each detrended by its own trailing
    moving average of 50 windows (the slow fall and rise would otherwise make any two smooth
    curves correlate): r_self = corr(predicted, obtained) and
    r_base = corr(baseline, obtained), where the baseline predicts a window's curiosity as its
    action shares times each action's running mean curiosity, estimated from the previous 50
    windows alone (ridge regression of window curiosity on action shares, shrunk towards their
    overall mean). On Fisher's z scale, averaged over agents: rise = z(r_self, last third of the
    windows) - z(r_self, first third); edge = z(r_self, last third) - z(r_base, last third).
    Verdict: holds if the 95% CIs across runs of both lie above 0. Scale: runs of >= 20,000 steps
    (a third then holds >= 333 windows), >= MIN_SEEDS runs.
    """
    key, claim = "8", "The self-model knows what will surprise it (predicted vs obtained curiosity)"
    evidence = "sections 3.2, 5 (the self-model's role; no figure)"
    s = presets.get("multi_agent")
    if s is None:
        return ClaimResult(key, claim, evidence, "n/a", _missing(("multi_agent",), presets))
    s = next((c for c in preset_and_sides(presets, "multi_agent") if records_steps(c)), s)
    per_step = records_steps(s)
    d = step_tracking(s) if per_step else self_model_tracking(s)
    early, late, base = mean_ci(d["self_early"]), mean_ci(d["self_late"]), mean_ci(d["base_late"])
    rise, edge = mean_ci(d["rise"]), mean_ci(d["edge"])
    n = int(np.isfinite(d["rise"] + d["edge"]).sum())
    values = {"z self early": _num(early[0]), "z self late": _num(late[0]), "z baseline late": _num(base[0]),
              "rise": _num(rise[0]), "rise low": _num(rise[1]), "edge": _num(edge[0]), "edge low": _num(edge[1]),
              "runs": n}
    how = ("per-step pairs, correlated within 20-step windows (the window moments the sweep records)" if per_step
           else "20-step window means detrended")
    stat = (f"{s.name}, runs: {n}, {how}: Fisher z of corr(predicted, obtained) first third "
            f"{_ci(early)}, last third {_ci(late)}; action-running-mean baseline, last third {_ci(base)}; rise "
            f"{_ci(rise)}, edge over baseline {_ci(edge)}")
    if not per_step:
        stat += (". Per-step pairs: this sweep ran before sweeps recorded each window's variances and covariance of "
                 "predicted and obtained curiosity, so only window means are compared")
    gap = _scale_gap(s, 20_000, {"runs": n})
    fails = [] if rise[1] > 0 else ["the correlation does not rise significantly"]
    fails += [] if edge[1] > 0 else ["the self-model does not beat the baseline significantly"]
    k = len(s.groups())
    tests = {"rise of z, first to last third": Tested(d["rise"], runs_per_seed=k),
             "edge of z over the baseline": Tested(d["edge"], runs_per_seed=k)}
    return ClaimResult(key, claim, evidence, stat, _decide([gap] if gap else [], fails, "both CIs above 0"), values,
                       tests)


def self_model_tracking(sweep: Sweep, window: int = SMOOTH, history: int = SMOOTH, ridge: float = 1.0) -> dict:
    """Per run (agents averaged on Fisher's z scale): {"self_early", "self_late", "base_late",
    "rise", "edge"} (arrays [runs]), as `claim_self_model_predicts` defines them."""
    cur = sweep.metrics["curiosity"].astype(float)  # [R, W, A]
    pred = sweep.metrics["predicted"].astype(float)
    counts = sweep.metrics["action_counts"].astype(float)  # [R, W, A, actions]
    base = running_action_baseline(cur, counts, history, ridge)
    detrend = lambda x: x - moving_average(x, window, axis=1)  # noqa: E731
    cur_d, pred_d, base_d = detrend(cur), detrend(pred), detrend(base)
    n_w = cur.shape[1]
    third = n_w // 3
    first, last = slice(0, third), slice(n_w - third, n_w)
    r, a = cur.shape[0], cur.shape[2]
    z = {k: np.full((r, a), np.nan) for k in ("self_early", "self_late", "base_late")}
    if third >= 3:
        for i in range(r):
            for j in range(a):
                z["self_early"][i, j] = fisher_z(pearson_r(pred_d[i, first, j], cur_d[i, first, j]))
                z["self_late"][i, j] = fisher_z(pearson_r(pred_d[i, last, j], cur_d[i, last, j]))
                z["base_late"][i, j] = fisher_z(pearson_r(base_d[i, last, j], cur_d[i, last, j]))
    out = {k: _nanmean(v, axis=1) for k, v in z.items()}
    out["rise"] = out["self_late"] - out["self_early"]
    out["edge"] = out["self_late"] - out["base_late"]
    return out


def running_action_baseline(curiosity, action_counts, history: int = SMOOTH, ridge: float = 1.0) -> np.ndarray:
    """The per-action running-mean predictor, from window data: [runs, windows, agents] prediction
    of each window's mean curiosity = its action shares . m, where m (one value per action) solves
    the ridge regression of the previous `history` windows' curiosity on their action shares,
    shrunk (weight `ridge`, in windows) towards those windows' mean curiosity. NaN in window 0.
    curiosity: [runs, windows, agents]; action_counts: [runs, windows, agents, actions]."""
    y = np.asarray(curiosity, float)
    c = np.asarray(action_counts, float)
    x = c / np.maximum(c.sum(axis=-1, keepdims=True), 1)  # shares [R, W, A, K]
    ok = np.isfinite(y) & (c.sum(axis=-1) > 0)
    x0, y0 = np.where(ok[..., None], x, 0.0), np.where(ok, y, 0.0)
    k = x.shape[-1]

    trailing = lambda v: trailing_sum(v, history)  # noqa: E731
    xx = trailing(x0[..., :, None] * x0[..., None, :])  # [R, W, A, K, K]
    xy = trailing(x0 * y0[..., None])  # [R, W, A, K]
    ny = trailing(ok.astype(float))
    sy = trailing(y0)
    with np.errstate(invalid="ignore", divide="ignore"):
        prior = np.where(ny > 0, sy / np.maximum(ny, 1), np.nan)  # [R, W, A]
    m = np.linalg.solve(xx + ridge * np.eye(k), (xy + ridge * np.nan_to_num(prior)[..., None])[..., None])[..., 0]
    pred = (x * m).sum(axis=-1)
    return np.where((ny > 0) & ok, pred, np.nan)


def claim_observational_curiosity(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 9: observational learning: an agent's curiosity rises while the other agent, or an
    object moving without its touch, is in its view (sections 4.1.2, 5).

    Measured on every run of multi_agent, per agent and 20-step window, when the agent itself
    touched nothing: "watching" = the other agent or a moving object in view (view fraction > 0);
    "quiet" = neither in view. An object moves in a window when its position at the window's end
    is > 1 cm from the end of the window before (the window-end positions are all the metrics
    hold; window 0 is left out). Curiosity is taken relative to the agent's trailing moving average
    of 50 windows (as in `stats.observation_classes`), which removes the slow learning trend.
    Per run: mean excess while watching - mean excess while quiet (windows of both agents pooled).
    Reported alongside, not the verdict: the same with the share of the view that the objects and
    the other agent fill held fixed (`beyond_view`), since something in view also fills the view.
    Verdict: holds if the 95% CI across runs lies above 0. Scale: runs of >= 10,000 steps (past the
    initial fall), >= MIN_SEEDS runs with windows of both kinds.
    """
    key, claim = "9", "Observational learning: curiosity rises while the other agent or what it moves is in view"
    evidence = "sections 4.1.2 (fig. 16, 45,000-47,000 steps of one run), 5 (videos)"
    s = presets.get("multi_agent")
    if s is None:
        return ClaimResult(key, claim, evidence, "n/a", _missing(("multi_agent",), presets))
    d = watching_excess(s)
    w, q, diff, b = mean_ci(d["watching"]), mean_ci(d["quiet"]), mean_ci(d["diff"]), mean_ci(d["beyond_view"])
    n = int(np.isfinite(d["diff"]).sum())
    values = {"watching": _num(w[0]), "quiet": _num(q[0]), "diff": _num(diff[0]), "diff low": _num(diff[1]),
              "runs": n, "watching windows": int(d["n_watching"]), "quiet windows": int(d["n_quiet"]),
              "beyond view": _num(b[0]), "beyond view low": _num(b[1])}
    stat = (f"{s.name}, runs: {n}: curiosity above the agent's moving average, own contact excluded, while the other "
            f"agent or a moving object is in view {_ci(w)} ({d['n_watching']:,} windows), while neither is "
            f"{_ci(q)} ({d['n_quiet']:,} windows); difference {_ci(diff)}; with the view's fill held fixed "
            f"(context, not the verdict) {_ci(b)}")
    gap = _scale_gap(s, 10_000, {"runs with both kinds of window": n})
    fails = [] if diff[1] > 0 else ["watching does not raise curiosity significantly"]
    tests = {"excess watching - quiet": Tested(d["diff"], runs_per_seed=len(s.groups()))}
    return ClaimResult(key, claim, evidence, stat, _decide([gap] if gap else [], fails, "the CI above 0"), values,
                       tests)


def watching_excess(sweep: Sweep, window: int = SMOOTH, moved_m: float = 0.01) -> dict:
    """Per run: {"watching", "quiet", "diff"} mean excess curiosity, "beyond_view" the watching
    coefficient with the view's fill held fixed (`beyond_view`) (arrays [runs]), and the window
    counts {"n_watching", "n_quiet"}, as `claim_observational_curiosity` defines them."""
    if sweep.n_agents != 2:
        raise ValueError(f"{sweep.path} has {sweep.n_agents} agent(s): watching another agent needs two")
    k = len(sweep.objects)
    pos = sweep.metrics["object_pos"].astype(float)  # [R, W, K, 3]
    moved = np.zeros(pos.shape[:3], bool)
    moved[:, 1:] = np.linalg.norm(np.diff(pos, axis=1), axis=-1) > moved_m  # NaN compares False
    view = sweep.metrics["view_fraction"].astype(float)  # [R, W, 2, K + 1]
    own = (sweep.metrics["contact_object"].sum(axis=3) > 0) | (sweep.metrics["contact_agent"] > 0)  # [R, W, 2]
    moving_in_view = np.any(moved[:, :, None, :] & (view[..., :k] > 0), axis=3) | (view[..., k] > 0)
    valid = np.zeros(own.shape, bool)
    valid[:, 1:] = True
    watching = valid & ~own & moving_in_view
    quiet = valid & ~own & ~moving_in_view
    cur = sweep.metrics["curiosity"].astype(float)
    excess = cur - moving_average(cur, window, axis=1)
    w = _nanmean(np.where(watching, excess, np.nan), axis=(1, 2))
    q = _nanmean(np.where(quiet, excess, np.nan), axis=(1, 2))
    return {"watching": w, "quiet": q, "diff": w - q, "beyond_view": beyond_view(excess, watching, quiet, view),
            "n_watching": int(watching.sum()), "n_quiet": int(quiet.sum())}


def claim_contacts_raise_curiosity(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 12: an agent's own contacts with objects raise its curiosity (fig. 9 and section 4.1:
    the agent starts to interact with objects "coinciding with the steepest ascent in curiosity";
    section 4.1.2: UCB's many object interactions are "one reason why the curiosity reward is
    comparatively high").

    Measured per agent and 20-step window, as claim 9 measures watching: curiosity relative to the
    agent's trailing moving average of 50 windows (the slow learning trend removed), "touching" =
    the agent touched an object during the window, "apart" = it touched nothing (no object, not
    the other agent); window 0 is left out. Per run: mean excess while touching - mean excess
    while apart (the agents' windows pooled), NaN for a run with fewer than 5 touching windows.
    Reported alongside, not the verdict: the same difference with the share of the view that the
    objects and the other agent fill held fixed (`beyond_view`: per run, the touching coefficient of
    a least-squares fit of the excess on touching, that share and its square), since a touching
    agent faces an object close up and a view full of objects may surprise by itself. Groups: single_agent ε-greedy (fig. 9's run) and multi_agent UCB (section 4.1.2's), those
    loaded. Verdict: holds if in every group the 95% CI across runs lies above 0. Context, not the
    verdict: the other policies of both sweeps. Scale: runs of >= 10,000 steps (past the initial
    fall), >= MIN_SEEDS runs with touching windows a group.
    """
    key, claim = "12", "An agent's own contacts with objects raise its curiosity"
    evidence = "fig. 9, sections 4.1 (one agent, ε-greedy) and 4.1.2 (two agents, UCB); one run each"
    deciding = {("single_agent", "eps"): "fig. 9", ("multi_agent", "ucb"): "section 4.1.2"}
    groups = _source_groups(presets, [(preset, p, fig) for (preset, p), fig in deciding.items()])
    if not groups:
        return ClaimResult(key, claim, evidence, "n/a", _missing(("single_agent", "multi_agent"), presets))
    decide = {label for label, _, _ in groups}
    agents = {"single_agent": "one agent", "multi_agent": "two agents"}
    groups += _source_groups(presets, [(preset, p, agents[preset]) for preset in agents
                                       for p in ("eps", "boltzmann", "ucb") if (preset, p) not in deciding])
    parts, context_parts, values, fails, tests, sizes = [], [], {}, [], {}, []
    for label, s, g in groups:
        d = contact_excess(s, g)
        m, b = mean_ci(d["diff"]), mean_ci(d["beyond_view"])
        n = int(np.isfinite(d["diff"]).sum())
        values.update({f"{label} diff": _num(m[0]), f"{label} diff low": _num(m[1]), f"{label} runs": n,
                       f"{label} beyond view": _num(b[0]), f"{label} beyond view low": _num(b[1])})
        cell = (f"{label}: {_ci(m)}, {d['n_touching']:,} touching and {d['n_apart']:,} apart windows; the view's "
                f"fill held fixed {_ci(b)}")
        if label not in decide:
            context_parts.append(cell)
            continue
        parts.append(cell)
        tests[f"{label} excess touching - apart"] = Tested(d["diff"])
        sizes.append((s, 10_000, {f"{label} runs with contacts": n}))
        if not m[1] > 0:
            fails.append(f"{label}: the CI does not lie above 0")
    stat = ("curiosity above the agent's moving average while it touches an object - while it touches nothing, "
            "mean over runs [95% CI]; " + "; ".join(parts))
    if context_parts:
        stat += ". Context, not the verdict: " + "; ".join(context_parts)
    gap = _scale_gaps(sizes)
    return ClaimResult(key, claim, evidence, stat, _decide([gap] if gap else [], fails, "every CI above 0"), values,
                       tests)


def contact_excess(sweep: Sweep, group: Group, window: int = SMOOTH, min_windows: int = 5) -> dict:
    """Per run of `group`: {"touching", "apart", "diff"} mean excess curiosity, "beyond_view" the
    touching coefficient with the view's fill held fixed (arrays [runs]), and the window counts
    {"n_touching", "n_apart"}, as `claim_contacts_raise_curiosity` defines them."""
    m = sweep.metrics
    touching = m["contact_object"][group.indices].sum(axis=3) > 0  # [n, W, A]
    other = m["contact_agent"][group.indices] > 0
    valid = np.zeros(touching.shape, bool)
    valid[:, 1:] = True
    touching, apart = valid & touching, valid & ~touching & ~other
    cur = m["curiosity"][group.indices].astype(float)
    excess = cur - moving_average(cur, window, axis=1)
    t = _nanmean(np.where(touching, excess, np.nan), axis=(1, 2))
    a = _nanmean(np.where(apart, excess, np.nan), axis=(1, 2))
    enough = touching.sum(axis=(1, 2)) >= min_windows
    t = np.where(enough, t, np.nan)
    beyond = np.where(enough, beyond_view(excess, touching, apart, m["view_fraction"][group.indices]), np.nan)
    return {"touching": t, "apart": a, "diff": t - a, "beyond_view": beyond, "n_touching": int(touching.sum()),
            "n_apart": int(apart.sum())}


def beyond_view(excess, marked, rest, view_fraction) -> np.ndarray:
    """[runs]: per run, the coefficient of `marked` in a least-squares fit of `excess` on marked,
    the view's fill (the share of the view the objects and the other agent fill, summed from
    `view_fraction` [runs, windows, agents, targets]) and its square, over the windows `marked` or
    `rest` (the agents' windows pooled): `marked` windows' excess over `rest`'s with the fill held
    fixed. NaN for a run without windows of both kinds."""
    fill = np.nan_to_num(np.asarray(view_fraction, float)).sum(axis=3)
    out = np.full(excess.shape[0], np.nan)
    for r in range(excess.shape[0]):  # one small fit a run
        ok = (marked[r] | rest[r]) & np.isfinite(excess[r])
        if not (marked[r] & ok).any() or not (rest[r] & ok).any():
            continue
        v = fill[r][ok]
        x = np.stack([np.ones_like(v), marked[r][ok].astype(float), v, v * v], axis=1)
        out[r] = np.linalg.lstsq(x, excess[r][ok], rcond=None)[0][1]
    return out


CONTACT_ONSET = 25_000  # fig. 9: "around 25 000 training steps ... the agent begins to interact frequently"


def claim_contacts_begin_late(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 13: the agent begins to interact frequently with objects only around 25,000 steps
    (fig. 9, section 4.1: "for the first time").

    Measured on the ε-greedy runs of single_agent (fig. 9's run), per run: the agent-object contact
    steps per 1,000 steps after step 25,000 minus those before it (`contact_onset`). Verdict: holds
    if the 95% CI across runs lies above 0 (contacts more frequent after 25,000 steps than
    before). Context, not the verdict: the same for multi_agent's ε-greedy and UCB runs (fig. 21's
    curves: "UCB achieves 60% of its total interactions by 40,000 steps"). Scale: runs of >= 40,000
    steps (15,000 steps after the onset), >= MIN_SEEDS seeds.
    """
    key, claim = "13", "Frequent contacts with objects begin only around 25,000 steps"
    evidence = "fig. 9, section 4.1 (one agent, ε-greedy; one run)"
    groups = _source_groups(presets, [("single_agent", "eps", "fig. 9")])
    if not groups:
        return ClaimResult(key, claim, evidence, "n/a", _missing(("single_agent",), presets))
    groups += _source_groups(presets, [("multi_agent", "eps", "two agents"), ("multi_agent", "ucb", "two agents")])
    parts, values = [], {}
    for label, s, g in groups:
        d = contact_onset(s, g)
        b, a, m = mean_ci(d["before"]), mean_ci(d["after"]), mean_ci(d["rise"])
        values.update({f"{label} before": _num(b[0]), f"{label} after": _num(a[0]), f"{label} rise": _num(m[0]),
                       f"{label} rise low": _num(m[1])})
        parts.append(f"{label}: before {_ci(b)}, after {_ci(a)}, rise {_ci(m)}")
    (label, s, g), rise = groups[0], contact_onset(groups[0][1], groups[0][2])["rise"]
    low = mean_ci(rise)[1]
    fails = [] if low > 0 else ["the rise's CI does not lie above 0"]
    gap = _scale_gap(s, 40_000, {label: g.n})
    stat = (f"object contact steps per 1,000 steps before and after step {CONTACT_ONSET:,}, and rise = after - "
            "before, mean over runs [95% CI]; " + "; ".join(parts[:1]))
    if parts[1:]:
        stat += ". Context, not the verdict: " + "; ".join(parts[1:])
    return ClaimResult(key, claim, evidence, stat, _decide([gap] if gap else [], fails, "the rise's CI above 0"),
                       values, {f"{label} rise": Tested(rise)})


def contact_onset(sweep: Sweep, group: Group, at: int = CONTACT_ONSET) -> dict:
    """Per run of `group`: {"before", "after", "rise"}: agent-object contact steps (all agents) per
    1,000 steps over the windows wholly before step `at`, wholly after it, and after - before."""
    per_1000 = object_contacts(sweep)[group.indices].astype(float) * (1000 / sweep.metrics_every)
    before = block_mean(sweep, per_1000, 0, at)
    after = block_mean(sweep, per_1000, at, sweep.steps_done)
    return {"before": before, "after": after, "rise": after - before}

def claim_boltzmann_least_curious(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 10: Boltzmann records the lowest curiosity of the three policies, throughout the run;
    ε-greedy and UCB follow similar curves (fig. 11, section 4.1).

    Measured on single_agent (the paper's section 4.1, one agent), per run: the mean curiosity
    over the whole run (`run_curiosity`). Two Welch t-tests across runs: ε-greedy > Boltzmann and
    UCB > Boltzmann. Verdict: holds if both have p < 0.05 in the paper's direction. Context, not
    the verdict: ε-greedy against UCB (Welch, with the bound two one-sided tests put on their
    difference: the paper's "very similar"), and the same three policies with two agents
    (multi_agent), where loaded. Scale: runs of >= 40,000 steps (the paper's "throughout" is an
    80,000-step run), >= MIN_SEEDS seeds a policy.
    """
    key, claim = "10", "Boltzmann records the lowest curiosity; ε-greedy and UCB alike"
    evidence = "fig. 11, section 4.1 (one agent; one run per policy)"
    return _policy_curiosity_claim(presets, key, claim, evidence, "single_agent", "multi_agent",
                                   (("eps", "boltzmann"), ("ucb", "boltzmann")), similar=("eps", "ucb"))


def claim_ucb_more_curious(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 11: UCB's curiosity is higher than ε-greedy's (section 4.2, figs. 17 and 18 against
    fig. 8: "the UCB runs ... show a significantly higher and more distinct curiosity reward").

    Measured on multi_agent (figs. 17 and 18 are two-agent runs), per run: the mean curiosity over
    the whole run (`run_curiosity`). Welch t-test UCB > ε-greedy across runs. Verdict: holds if
    p < 0.05 in the paper's direction. Context, not the verdict: the same with one agent
    (single_agent), where loaded. Scale: runs of >= 40,000 steps, >= MIN_SEEDS seeds a policy.
    """
    key, claim = "11", "UCB's curiosity is higher than ε-greedy's"
    evidence = "section 4.2 (figs. 17, 18 against fig. 8; one run each)"
    return _policy_curiosity_claim(presets, key, claim, evidence, "multi_agent", "single_agent", (("ucb", "eps"),))


def run_curiosity(sweep: Sweep) -> np.ndarray:
    """[runs]: the mean curiosity over the whole run, averaged over the agents."""
    return _nanmean(sweep.metrics["curiosity"].astype(float), axis=(1, 2))


def _policy_curiosity_claim(presets, key, claim, evidence, preset, context, pairs, similar=None) -> ClaimResult:
    """Claims 10 and 11: Welch tests of `run_curiosity` between the policies of `preset`, each pair
    (higher in the paper, lower); the same numbers for the `context` preset, and the `similar`
    pair with the bound two one-sided tests put on its difference, as context."""
    s = presets.get(preset)
    if s is None:
        return ClaimResult(key, claim, evidence, "n/a", _missing((preset,), presets))
    values: dict = {}
    found = _compare_policy_curiosity(s, f"{preset} ", pairs, similar, values)
    if isinstance(found, str):
        return ClaimResult(key, claim, evidence, "n/a", f"not testable: {found}")
    stat, fails, gs, tests = found
    stat = f"{s.name}: {stat}"
    other = presets.get(context)
    more = None if other is None else _compare_policy_curiosity(other, f"{context} ", pairs, similar, values)
    if more is not None and not isinstance(more, str):
        agents = f"{other.n_agents} agent{'s' * (other.n_agents > 1)}"
        stat += f". Context, not the verdict: {other.name} ({agents}): {more[0]}"
    gap = _scale_gap(s, 40_000, {g.label: g.n for g in gs.values()})
    return ClaimResult(key, claim, evidence, stat,
                       _decide([gap] if gap else [], fails, "every Welch test p < 0.05 in the paper's direction"),
                       values, tests)


def _compare_policy_curiosity(sweep: Sweep, prefix: str, pairs, similar, values: dict):
    """(statistic, fails, groups, tests) of `_policy_curiosity_claim` on one sweep, its numbers
    added to `values` under `prefix`; a message where the sweep lacks a policy."""
    needed = sorted({p for pair in pairs for p in pair} | set(similar or ()), key=("eps", "boltzmann", "ucb").index)
    gs = {p: _paper_group(sweep, p) for p in needed}
    if any(g is None for g in gs.values()):
        return f"{sweep.name} has no runs of {', '.join(p for p, g in gs.items() if g is None)}"
    c = run_curiosity(sweep)
    cells = []
    for p, g in gs.items():
        m = mean_ci(c[g.indices])
        values[f"{prefix}{p}"] = _num(m[0])
        cells.append(f"{_short(p)} {_ci(m)}")
    parts, fails, tests = [f"mean curiosity over the run: {', '.join(cells)}"], [], {}
    for hi, lo in pairs:
        label = f"{_short(hi)} > {_short(lo)}"
        x, y = c[gs[hi].indices], c[gs[lo].indices]
        w = welch_t(x, y)
        values[f"{prefix}{label} t"], values[f"{prefix}{label} p"] = _num(w["t"]), _num(w["p"])
        parts.append(f"{label}: Welch t={_f(w['t'])}, p={_p(w['p'])}")
        tests[label] = Tested(x, y)
        if not (w["p"] < ALPHA and w["diff"] > 0):
            fails.append(f"{label} {'significantly the other way' if w['p'] < ALPHA else 'not significant'}")
    if similar:
        a, b = similar
        w = welch_t(c[gs[a].indices], c[gs[b].indices])
        bound = tost_bound(w["diff"], w["se"], w["df"], ALPHA)
        values.update({f"{prefix}{a} - {b}": _num(w["diff"]), f"{prefix}{a} - {b} p": _num(w["p"]),
                       f"{prefix}{a} - {b} bound": _num(bound)})
        parts.append(f"{_short(a)} - {_short(b)} {_f(w['diff'])}, p={_p(w['p'])}, within ±{_f(bound)} (two one-sided "
                     "tests at 5 %)")
    return "; ".join(parts), fails, gs, tests


CLAIMS: tuple[Callable[[Mapping[str, Sweep]], ClaimResult], ...] = (
    claim_curiosity_dip_and_rise, claim_contact_ranking, claim_two_agents_higher, claim_agents_move_together,
    claim_prefers_moving_objects, claim_stop_least, claim_boltzmann_trembles, claim_rotations_less,
    claim_temperatures_alike, claim_self_model_predicts, claim_observational_curiosity, claim_boltzmann_least_curious,
    claim_ucb_more_curious, claim_contacts_raise_curiosity, claim_contacts_begin_late,
)


def claim_results(sweeps) -> list[ClaimResult]:
    """Every claim of `CLAIMS` tested on `sweeps` (see `assign_presets` for what they may be)."""
    presets = assign_presets(sweeps)
    return [f(presets) for f in CLAIMS]


def claims_table(sweeps) -> Table:
    """The claims table: one row per claim (the claim, the paper's evidence, our statistic, the
    verdict), as a `tables.Table` (`to_markdown`, `to_csv`); `values` holds each row's numbers."""
    presets = assign_presets(sweeps)
    results = [f(presets) for f in CLAIMS]
    cols = ["#", "claim", "paper's evidence", "our statistic", "verdict"]
    rows = [[r.key, r.claim, r.evidence, r.statistic, r.verdict] for r in results]
    values = [{"key": r.key, "claim": r.claim, "verdict": r.verdict, **r.values} for r in results]
    keys = list(dict.fromkeys(k for v in values for k in v))
    values = [{k: v.get(k) for k in keys} for v in values]
    used = ", ".join(f"{p} = {s.name}" + (f" ({' + '.join(part.name for part in s.parts)})" if s.parts else "")
                     for p, s in presets.items()) or "none"
    note = (f"Sweeps as presets: {used}. Means are across runs (seeds) with 95% Student-t intervals in brackets; "
            f"p-values two-sided. holds: the paper's effect at the 5% level in its direction (claim 7: no significant "
            f"difference); does not hold: at the needed scale, the effect is not significant (or reversed); not "
            f"testable: a preset is missing, the metrics cannot show it, or the sweeps are too small (>= {MIN_SEEDS} "
            "seeds per group and each claim's run length).")
    return Table(cols, rows, values, note)


# ---------------------------------------------------------------------------------- helpers


def _nanmean(x, axis):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.nanmean(x, axis=axis)


def block_mean(sweep: Sweep, x: np.ndarray, start: int, end: int) -> np.ndarray:
    """Mean over axis 1 of x [n, windows] of the windows lying wholly in steps [start, end);
    NaN where none does."""
    e = sweep.metrics_every
    lo, hi = -(-int(start) // e), min(int(end) // e, x.shape[1])
    if hi <= lo:
        return np.full(x.shape[0], np.nan)
    return _nanmean(x[:, lo:hi], axis=1)


def _paper_group(sweep: Sweep, policy: str) -> Group | None:
    """The group of `policy` at the paper's setting, else its first group; None if it has none."""
    gs = sweep.groups(policy)
    for g in gs:
        if np.isclose(g.value, PAPER_SETTING[policy]):
            return g
    return gs[0] if gs else None


def _source_groups(presets, sources) -> list[tuple[str, Sweep, Group]]:
    out = []
    for preset, policy, fig in sources:
        s = presets.get(preset)
        g = _paper_group(s, policy) if s is not None else None
        if g is not None:
            out.append((f"{s.name} {g.label} ({fig})", s, g))
    return out


def _missing(needed: Sequence[str], presets) -> str:
    lacking = [p for p in needed if p not in presets]
    return f"not testable: the {' and '.join(lacking)} sweep{'s are' if len(lacking) > 1 else ' is'} missing"


def _scale_gap(sweep: Sweep, min_steps: int, ns: Mapping[str, int]) -> str | None:
    """What the sweep lacks for a claim (run length, seeds), or None."""
    return _scale_gaps([(sweep, min_steps, ns)])


def _scale_gaps(items) -> str | None:
    """What several (sweep, min_steps, {group label: runs}) lack, each shortfall said once."""
    short: dict[int, dict[str, None]] = {}  # min steps -> "<sweep> has <steps>", each sweep once
    small = []
    for sweep, min_steps, ns in items:
        if sweep.steps_done < min_steps:
            short.setdefault(min_steps, {})[f"{sweep.name} has {sweep.steps_done:,}"] = None
        small += [f"{label} {n}" for label, n in ns.items() if n < MIN_SEEDS]
    gaps = [f"runs of >= {k:,} steps ({', '.join(v)})" for k, v in short.items()]
    if small:
        gaps.append(f">= {MIN_SEEDS} seeds per group; {', '.join(dict.fromkeys(small))}")
    return "; ".join(gaps) or None


def _decide(gaps: Sequence[str], fails: Sequence[str], rule: str) -> str:
    if gaps:
        return f"not testable at this scale (needs {'; '.join(gaps)})"
    if fails:
        return "does not hold: " + "; ".join(fails)
    return f"holds ({rule})"


def _num(x):
    x = float(x)
    return x if math.isfinite(x) else None


def _f(x, digits: int = 3) -> str:
    x = float(x)
    if not math.isfinite(x):
        return "n/a"
    return f"{x:,.0f}" if abs(x) >= 1000 else f"{x:.{digits}g}"


def _p(p) -> str:
    p = float(p)
    if not math.isfinite(p):
        return "n/a"
    return "<0.001" if p < 0.001 else f"{p:.3f}"


def _ci(m, digits: int = 3) -> str:
    """'mean [low, high] (n=...)' from a `mean_ci` tuple of scalars."""
    mean, lo, hi, n = (float(v) for v in m)
    if not math.isfinite(mean):
        return "n/a"
    fmt = (lambda v: f"{v:,.0f}") if digits == 0 else _f
    band = f" [{fmt(lo)}, {fmt(hi)}]" if math.isfinite(lo) else ""
    return f"{fmt(mean)}{band} (n={int(n)})"


def _short(policy: str) -> str:
    return {"eps": "ε-greedy", "boltzmann": "Boltzmann", "ucb": "UCB"}[policy]
