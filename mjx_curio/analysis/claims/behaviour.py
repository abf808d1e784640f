"""The claims about what the agents do: their contacts by policy (claims 2 and 15), moving objects
preferred (5), the actions chosen (6a, 6c), trembling (6b), and when frequent contacts begin (13).
Imports `common`, `significance`, `stats` and `sweeps`.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from mjx_curio.analysis.stats import agent_contacts, mean_ci, nan_ratio, object_contacts, turn_reversals
from mjx_curio.analysis.significance import welch_t
from mjx_curio.analysis.sweeps import Group, Sweep
from mjx_curio.analysis.claims.common import (
    ALPHA,
    ClaimResult,
    Tested,
    block_mean,
    paper_group,
    preset_and_sides,
    _ci,
    _decide,
    _f,
    _missing,
    _nanmean,
    _num,
    _p,
    _scale_gap,
    _scale_gaps,
    _short,
    _source_groups,
)


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
    found = _every_policy(presets, key, claim, evidence)
    if isinstance(found, ClaimResult):
        return found
    s, gs = found
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


def _every_policy(presets: Mapping[str, Sweep], key: str, claim: str, evidence: str):
    """The multi_agent sweep and its group of each policy in the paper's setting, (sweep,
    {policy: group}), as claims 2 and 15 compare them; or the ClaimResult saying what is missing."""
    s = presets.get("multi_agent")
    if s is None:
        return ClaimResult(key, claim, evidence, "n/a", _missing(("multi_agent",), presets))
    gs = {p: paper_group(s, p) for p in ("eps", "boltzmann", "ucb")}
    if any(g is None for g in gs.values()):
        lacking = [p for p, g in gs.items() if g is None]
        return ClaimResult(key, claim, evidence, "n/a", f"not testable: {s.name} (multi_agent) has no runs of "
                                                        f"{', '.join(lacking)}")
    return s, gs


AGENT_PHASE_STEPS = 80_000  # the paper's run length: its Boltzmann agents meet mostly after step ~55,000


def claim_boltzmann_agents_meet(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 15: Boltzmann agents touch each other more often than ε-greedy agents, which almost
    never do (fig. 22: over 80,000 steps ε-greedy reaches "only about 10 %" of UCB's agent-agent
    contacts, Boltzmann "roughly 50 %"; section 4.1.4: the Boltzmann run's last phase, from about
    step 55,000, is "dominated by agent-to-agent interactions").

    Measured on multi_agent, per run: the steps with the two agents touching over the whole run
    (`stats.agent_contacts`), one group per policy (`agent_contact_order`). Welch t Boltzmann -
    ε-greedy. Verdict: holds if Boltzmann's are higher with p < 0.05. Scale: runs of >=
    AGENT_PHASE_STEPS steps (the phase the paper's Boltzmann contacts come from begins at ~55,000;
    the full-length runs on the GPU test it, "At the paper's full length" on the results
    page), >= MIN_SEEDS seeds a policy. Below that scale the statistic is shown and its test is
    left out of the power table: the seeds a 40,000-step comparison would need say nothing about a
    phase the runs did not reach.
    """
    key, claim = "15", "Boltzmann agents touch each other more often than ε-greedy agents, which almost never do"
    evidence = ("fig. 22, sections 4.1.4 and 4.1.5 (two agents; one run per policy: ε-greedy ~10 % of UCB's "
                "agent-agent contacts, Boltzmann ~50 %, mostly after step ~55,000)")
    found = _every_policy(presets, key, claim, evidence)
    if isinstance(found, ClaimResult):
        return found
    s, gs = found
    agt = agent_contacts(s).sum(axis=1).astype(float)
    d = agent_contact_order({p: agt[g.indices] for p, g in gs.items()})
    gap = _scale_gap(s, AGENT_PHASE_STEPS, {g.label: g.n for g in gs.values()})
    return ClaimResult(key, claim, evidence, f"{s.name}: {d['text']}", _decide([gap], [], "") if gap else d["verdict"],
                       d["values"], {} if gap else {"agent-agent Boltzmann > ε": d["tested"]})


def agent_contact_order(contacts: Mapping[str, np.ndarray]) -> dict:
    """Claim 15's statistic from the agent-agent contact steps of each run, {"eps", "boltzmann",
    "ucb"}: arrays [runs], wherever they were counted (a sweep's metrics, or a full-length sweep's
    cumulative curves): {"text", "values", "tested" (Boltzmann against ε-greedy), "verdict" (the
    claim's, for runs at its scale)}. Each policy's mean is also given as a share of UCB's, as fig.
    22 normalises to UCB's total."""
    top = float(np.nanmean(contacts["ucb"]))
    cells, values = [], {}
    for p in ("eps", "boltzmann", "ucb"):
        m = mean_ci(contacts[p])
        share = 100 * m[0] / top if top > 0 else np.nan
        values.update({f"agent-agent {p}": _num(m[0]), f"agent-agent {p} share of UCB": _num(share)})
        cells.append(f"{_short(p)} {_ci(m, 0)}" + (f" ({share:.0f} % of UCB's)" if p != "ucb" else ""))
    w = welch_t(contacts["boltzmann"], contacts["eps"])
    values.update({"Boltzmann > ε t": _num(w["t"]), "Boltzmann > ε p": _num(w["p"])})
    fails = [] if (w["p"] < ALPHA and w["diff"] > 0) else [
        "Boltzmann agents do not touch each other significantly more than ε-greedy ones"
        + (" (fewer)" if w["diff"] < 0 else "")]
    text = (f"agent-agent contact steps per run: {', '.join(cells)}; Boltzmann > ε-greedy: Welch t={_f(w['t'])}, "
            f"p={_p(w['p'])}")
    return {"text": text, "values": values, "tested": Tested(contacts["boltzmann"], contacts["eps"]),
            "verdict": _decide([], fails, "Welch p < 0.05, Boltzmann > ε-greedy")}


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
    g = paper_group(s, "eps")
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
    gs = {p: paper_group(s, p) for p in ("boltzmann", "eps", "ucb")}
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
    gs = {p: paper_group(s, p) for p in ("boltzmann", "eps", "ucb")}
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
