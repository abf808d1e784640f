"""The claims about what surprises an agent: the self-model's predictions of it (claim 8), watching
the other agent act (9), and touching an object (12). Imports `common`, `self_model`,
`significance`, `stats` and `sweeps`.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from mjx_curio.analysis.stats import mean_ci, moving_average
from mjx_curio.analysis.significance import fisher_z, pearson_r
from mjx_curio.analysis.self_model import records_steps, step_tracking, trailing_sum
from mjx_curio.analysis.sweeps import Group, Sweep
from mjx_curio.analysis.claims.common import (
    ClaimResult,
    SMOOTH,
    Tested,
    preset_and_sides,
    _ci,
    _decide,
    _missing,
    _nanmean,
    _num,
    _scale_gap,
    _scale_gaps,
    _source_groups,
)


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


def watching_excess(sweep: Sweep, window: int = SMOOTH, moved_m: float = 0.01, series=None) -> dict:
    """Per run: {"watching", "quiet", "diff"} mean excess curiosity, "beyond_view" the watching
    coefficient with the view's fill held fixed (`beyond_view`) (arrays [runs]), and the window
    counts {"n_watching", "n_quiet"}, as `claim_observational_curiosity` defines them. `series`
    [runs, windows, agents]: another per-agent series in place of the curiosity (a part of it,
    `curiosity_parts.situation_parts_table`)."""
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
    cur = np.asarray(sweep.metrics["curiosity"] if series is None else series, float)
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
    agent faces an object close up and a view full of objects may surprise by itself. Groups:
    single_agent ε-greedy (fig. 9's run) and multi_agent UCB (section 4.1.2's), those loaded.
    Verdict: holds if in every group the 95% CI across runs lies above 0. Context, not the
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


def contact_excess(sweep: Sweep, group: Group, window: int = SMOOTH, min_windows: int = 5, series=None) -> dict:
    """Per run of `group`: {"touching", "apart", "diff"} mean excess curiosity, "beyond_view" the
    touching coefficient with the view's fill held fixed (arrays [runs]), and the window counts
    {"n_touching", "n_apart"}, as `claim_contacts_raise_curiosity` defines them. `series`
    [group's runs, windows, agents]: another per-agent series in place of the curiosity (a part of
    it, `curiosity_parts.situation_parts_table`)."""
    m = sweep.metrics
    touching = m["contact_object"][group.indices].sum(axis=3) > 0  # [n, W, A]
    other = m["contact_agent"][group.indices] > 0
    valid = np.zeros(touching.shape, bool)
    valid[:, 1:] = True
    touching, apart = valid & touching, valid & ~touching & ~other
    cur = np.asarray(m["curiosity"][group.indices] if series is None else series, float)
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
