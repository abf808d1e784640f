"""Does the self-model know, step by step, what will surprise it? (claim 8, per step)

A sweep keeps no per-step pairs of (curiosity the self-model predicted for the action taken,
curiosity obtained), but it records enough of each 20-step window to correlate them step by step
within windows: the means of both, their variances and covariance over the window's steps, and
each action's count and mean curiosity there (`metrics.SCHEMA`). Correlating within windows leaves
out the slow fall and rise of curiosity over a run that any two smooth curves share, without a
moving average.

For a run, an agent and a set of windows (a third of the run), the pooled within-window
correlation of per-step values x and y is

    r = sum_w n_w cov_w(x, y) / sqrt(sum_w n_w var_w(x) * sum_w n_w var_w(y)),

n_w the window's steps: the Pearson correlation of the steps after each window's means are taken
out. The baseline predicts each step's curiosity as the running mean of the curiosity the same
action brought over the previous `history` windows (shrunk towards their mean curiosity by
`prior_weight` steps): what an agent would know from counting alone, with no self-model. Its
within-window moments follow from the windows' per-action counts and means.
"""

from __future__ import annotations

import numpy as np

from mjx_curio.analysis.significance import fisher_z
from mjx_curio.analysis.stats import bin_windows
from mjx_curio.analysis.sweeps import Sweep

STEP_METRICS = ("predicted_var", "curiosity_var", "predicted_curiosity_cov", "curiosity_by_action")


def records_steps(sweep: Sweep) -> bool:
    """Whether the sweep records the within-window moments the per-step test needs (sweeps made
    before they were added do not)."""
    return all(k in sweep.metrics for k in STEP_METRICS)


def trailing_sum(v: np.ndarray, history: int) -> np.ndarray:
    """Along axis 1, the sum over the previous `history` entries (not this one): out[:, w] =
    v[:, max(w - history, 0):w].sum(axis=1)."""
    cs = np.concatenate([np.zeros_like(v[:, :1]), np.cumsum(v, axis=1)], axis=1)  # cs[w] = sum of v[:w]
    w = np.arange(v.shape[1])
    return cs[:, w] - cs[:, np.maximum(w - history, 0)]


def action_baseline_moments(counts, by_action, history: int, prior_weight: float = 1.0):
    """The per-action running-mean predictor's within-window moments with the curiosity obtained.

    counts [R, W, A, K] steps of each action, by_action [R, W, A, K] their mean curiosity (NaN
    where none). Returns (n var_w(b), n cov_w(b, c)) [R, W, A], b the baseline's per-step
    prediction m_w[a_t], m_w from the previous `history` windows alone."""
    n_a = np.asarray(counts, float)
    s_a = np.where(n_a > 0, np.nan_to_num(np.asarray(by_action, float)) * n_a, 0.0)  # curiosity summed per action
    seen_n, seen_s = trailing_sum(n_a, history), trailing_sum(s_a, history)
    tot_n, tot_s = seen_n.sum(axis=-1, keepdims=True), seen_s.sum(axis=-1, keepdims=True)
    prior = np.where(tot_n > 0, tot_s / np.maximum(tot_n, 1), 0.0)
    m = (seen_s + prior_weight * prior) / (seen_n + prior_weight)  # [R, W, A, K]
    n = n_a.sum(axis=-1)
    safe_n = np.maximum(n, 1)
    b_mean = (n_a * m).sum(axis=-1) / safe_n
    c_mean = s_a.sum(axis=-1) / safe_n
    n_var_b = (n_a * m * m).sum(axis=-1) - n * b_mean ** 2
    n_cov = (m * s_a).sum(axis=-1) - n * b_mean * c_mean
    first = (tot_n[..., 0] == 0)  # nothing seen yet: no baseline
    return np.where(first, np.nan, n_var_b), np.where(first, np.nan, n_cov)


def pooled_r(n_cov, n_var_x, n_var_y) -> np.ndarray:
    """The pooled within-window correlation over axis 1 ([R, W, A] -> [R, A]), from each window's
    n cov and n var (windows where any is not finite left out)."""
    cov, vx, vy = (v.sum(axis=1) for v in _finite_windows(n_cov, n_var_x, n_var_y))
    return _r(cov, vx, vy)


def _finite_windows(*moments):
    """The moments with every window where any of them is not finite set to 0 in all."""
    ok = np.logical_and.reduce([np.isfinite(v) for v in moments])
    return [np.where(ok, v, 0.0) for v in moments]


def _r(cov, vx, vy):
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where((vx > 0) & (vy > 0), cov / np.sqrt(vx * vy), np.nan)


def _agents_z(r):
    """[R, A, ...] -> [R, ...]: the mean over agents on Fisher's z scale, NaN where none is finite."""
    z = fisher_z(r)
    ok = np.isfinite(z)
    return np.where(ok.any(axis=1), np.where(ok, z, 0.0).sum(axis=1) / np.maximum(ok.sum(axis=1), 1), np.nan)


def window_moments(sweep: Sweep, history: int = 50, prior_weight: float = 1.0) -> dict:
    """Each window's n var and n cov [runs, windows, agents] of the predicted (q), obtained (c) and
    baseline (b) curiosity: {"qc": (n cov(q, c), n var q, n var c), "bc": (n cov(b, c), n var b,
    n var c)}, each triple with the windows where any is not finite set to 0."""
    m = sweep.metrics
    n = m["steps_taken"].astype(float)[..., None]  # [R, W, 1]: both agents step together
    n_var_c = n * m["curiosity_var"].astype(float)
    n_var_b, n_cov_bc = action_baseline_moments(m["action_counts"], m["curiosity_by_action"], history, prior_weight)
    return {"qc": _finite_windows(n * m["predicted_curiosity_cov"].astype(float), n * m["predicted_var"].astype(float),
                                  n_var_c),
            "bc": _finite_windows(n_cov_bc, n_var_b, n_var_c)}


def step_tracking(sweep: Sweep, history: int = 50, prior_weight: float = 1.0) -> dict:
    """Per run (agents averaged on Fisher's z scale): {"self_early", "self_late", "base_late",
    "rise", "edge"} ([runs]), as the window version in `claims.self_model_tracking`, with per-step
    correlations pooled within windows: self = corr(predicted, obtained), base = corr(the
    per-action running mean, obtained); early and late are the first and last third of the
    windows."""
    mo = window_moments(sweep, history, prior_weight)
    n_runs, n_w = sweep.metrics["steps_taken"].shape
    third = n_w // 3
    first, last = slice(0, third), slice(n_w - third, n_w)
    over = lambda triple, part: _agents_z(pooled_r(*(v[:, part] for v in triple)))  # noqa: E731
    if third >= 3:
        out = {"self_early": over(mo["qc"], first), "self_late": over(mo["qc"], last), "base_late": over(mo["bc"], last)}
    else:
        out = {k: np.full(n_runs, np.nan) for k in ("self_early", "self_late", "base_late")}
    out["rise"] = out["self_late"] - out["self_early"]
    out["edge"] = out["self_late"] - out["base_late"]
    return out


def tracking_over_time(sweep: Sweep, group=None, every: int = 1000, history: int = 50,
                       prior_weight: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A group's per-step tracking over training, in bins of `every` agent steps (`bin_windows`):
    (step at each bin's end [bins], corr(predicted, obtained) [runs of the group, bins], corr(the
    per-action running mean, obtained) [runs, bins]), each pooled within the bin's windows and
    averaged over agents on Fisher's z scale (then back to r)."""
    g = sweep.group(group)
    mo = window_moments(sweep, history, prior_weight)
    curves = []
    for triple in (mo["qc"], mo["bc"]):
        steps, binned = bin_windows(sweep, np.stack([v[g.indices] for v in triple], axis=-1), every, reduce="sum")
        curves.append(np.tanh(_agents_z(_r(binned[..., 0], binned[..., 1], binned[..., 2]).transpose(0, 2, 1))))
    return steps, curves[0], curves[1]
