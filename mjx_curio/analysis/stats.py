"""Statistics: the numbers behind the figures, from a loaded `Sweep`.

Confidence intervals across seeds (`t_quantile_975`, `mean_ci`, `mean_sd`), smoothing and binning
over windows (`moving_average`, `bin_windows`), and the quantities the figures draw
(`per_agent_vae_loss`, `object_contacts`, `agent_contacts`, `cumulative_interactions`,
`interaction_frequency`, `action_totals`, `observation_classes` with its `OBS_CLASSES`,
`turn_reversals`, `reversal_rates`), which the tests check. NumPy only; imports `sweeps` and no
other module of this package.
"""

from __future__ import annotations

import warnings
from typing import Any, Sequence

import numpy as np

from mjx_curio.analysis.sweeps import Group, Sweep, SweepError


# ---------------------------------------------------------------------------------- statistics

_T975 = (12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160, 2.145,
         2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045,
         2.042)


def t_quantile_975(df) -> np.ndarray:
    """Student t 97.5% quantile for `df` degrees of freedom (table to 30, then a series); NaN for df < 1."""
    df = np.asarray(df, float)
    z = 1.959964
    with np.errstate(divide="ignore", invalid="ignore"):
        series = z + (z**3 + z) / (4 * df) + (5 * z**5 + 16 * z**3 + 3 * z) / (96 * df**2)
    table = np.asarray(_T975)[np.clip(df.astype(int) - 1, 0, len(_T975) - 1)] if df.size else df
    out = np.where(df <= len(_T975), table, series)
    return np.where(df >= 1, out, np.nan)


def mean_ci(x, axis: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Mean over `axis` (NaNs ignored) and its 95% confidence interval (mean +- t * sd / sqrt(n)).
    Returns (mean, low, high, n); low/high are NaN where fewer than 2 values exist."""
    x = np.asarray(x, float)
    n = np.sum(np.isfinite(x), axis=axis)
    with warnings.catch_warnings(), np.errstate(invalid="ignore", divide="ignore"):
        warnings.simplefilter("ignore", RuntimeWarning)
        mean = np.nanmean(x, axis=axis)
        sd = np.nanstd(x, axis=axis, ddof=1)
    half = t_quantile_975(np.maximum(n - 1, 0)) * sd / np.sqrt(np.maximum(n, 1))
    half = np.where(n >= 2, half, np.nan)
    return mean, mean - half, mean + half, n


def mean_sd(x, axis: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean and sample standard deviation over `axis` (NaNs ignored; sd NaN below 2 values), and n."""
    x = np.asarray(x, float)
    n = np.sum(np.isfinite(x), axis=axis)
    with warnings.catch_warnings(), np.errstate(invalid="ignore", divide="ignore"):
        warnings.simplefilter("ignore", RuntimeWarning)
        mean = np.nanmean(x, axis=axis)
        sd = np.where(n >= 2, np.nanstd(x, axis=axis, ddof=1), np.nan)
    return mean, sd, n


def moving_average(x, window: int = 50, axis: int = -1) -> np.ndarray:
    """Trailing moving average over `window` points along `axis`: point i is the mean of the
    finite values among points max(0, i - window + 1) .. i (so the first points average what
    exists so far), NaN where none is finite. The paper smooths with 50 points of the curiosity
    sampled every 20 steps, i.e. 1,000 agent steps."""
    if window < 1:
        raise ValueError(f"window={window} must be >= 1")
    x = np.moveaxis(np.asarray(x, float), axis, -1)
    ok = np.isfinite(x)
    csum = np.cumsum(np.where(ok, x, 0.0), axis=-1)
    ccnt = np.cumsum(ok, axis=-1)
    pad = lambda c: np.concatenate([np.zeros(c.shape[:-1] + (1,)), c], axis=-1)  # noqa: E731
    csum, ccnt = pad(csum), pad(ccnt)
    i = np.arange(x.shape[-1])
    lo = np.maximum(i + 1 - window, 0)
    total = csum[..., i + 1] - csum[..., lo]
    count = ccnt[..., i + 1] - ccnt[..., lo]
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(count > 0, total / np.maximum(count, 1), np.nan)
    return np.moveaxis(out, -1, axis)


def bin_windows(sweep: Sweep, x: np.ndarray, every: int = 100, reduce: str = "sum") -> tuple[np.ndarray, np.ndarray]:
    """Windows (axis 1 of x, [runs, windows, ...]) combined into bins of `every` agent steps
    (rounded to whole windows, at least one); a last partial bin is dropped unless it is the
    only one. Returns (step at each bin's end [bins], binned x [runs, bins, ...])."""
    k = max(1, int(round(every / sweep.metrics_every)))
    w = x.shape[1]
    nb = max(w // k, 1)
    k = min(k, w)
    xs = np.asarray(x[:, : nb * k], float).reshape((x.shape[0], nb, k) + x.shape[2:])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        out = np.nansum(xs, axis=2) if reduce == "sum" else np.nanmean(xs, axis=2)
    return sweep.steps[: nb * k][k - 1 :: k], out


# ----------------------------------------------------------------------------- derived numbers


def per_agent_vae_loss(sweep: Sweep) -> np.ndarray:
    """VAE loss per image [runs, windows]: the recorded loss is summed over the agents' views
    (eq. 5), so a 2-agent sweep's is divided by 2 to compare with a single agent's."""
    return sweep.metrics["vae_loss"] / sweep.n_agents


def object_contacts(sweep: Sweep) -> np.ndarray:
    """[runs, windows]: agent-object contact steps in each window, summed over agents and objects."""
    return sweep.metrics["contact_object"].sum(axis=(2, 3))


def agent_contacts(sweep: Sweep) -> np.ndarray:
    """[runs, windows]: steps in which the two agents touched each other (0 for one agent). The
    flag is symmetric (both agents see the contact), so this counts each collision step once."""
    return sweep.metrics["contact_agent"].max(axis=2)


def cells_visited(pose, cell: float = 0.25) -> np.ndarray:
    """How much of the floor each agent went over: the number of distinct `cell` x `cell` m
    squares its position fell in at the windows' ends. `pose` [runs, windows, agents, 3] (x, y,
    heading; the `agent_pose` metric, NaN windows skipped) -> [runs, agents]. Sampled every window
    (20 steps), so it counts where an agent was, not every square it crossed."""
    pose = np.asarray(pose, float)
    out = np.zeros(pose.shape[0:1] + pose.shape[2:3], int)
    for r in range(pose.shape[0]):
        for a in range(pose.shape[2]):
            xy = pose[r, :, a, :2]
            xy = xy[np.isfinite(xy).all(axis=1)]
            out[r, a] = len(np.unique(np.floor(xy / cell).astype(np.int64), axis=0))
    return out


def cumulative_interactions(sweep: Sweep, kind: str = "object", groups: Sequence[Group] | None = None) -> dict:
    """Cumulative interactions per group, normalised to the global maximum (paper figs 21, 22).

    kind: "object" (agent-object contact steps, both agents summed) or "agent" (steps with an
    agent-agent contact). Per run the counts are summed cumulatively over windows; a group's curve
    is the mean over its seeds; every curve and band is divided by the largest final value of any
    group's mean curve, so the top curve ends at 1.
    Returns {group label: {"group", "steps", "mean", "low", "high", "runs" ([n, windows])}} plus
    "_max": the normaliser in contact steps (0 when nothing was touched: curves are then all 0).
    """
    if kind not in ("object", "agent"):
        raise ValueError(f"kind={kind!r}: choose 'object' or 'agent'")
    counts = object_contacts(sweep) if kind == "object" else agent_contacts(sweep)
    cum = np.cumsum(counts, axis=1).astype(float)
    groups = list(groups) if groups is not None else sweep.groups()
    out: dict[str, Any] = {}
    top = 0.0
    for g in groups:
        mean, lo, hi, _ = mean_ci(cum[g.indices])
        out[g.label] = {"group": g, "steps": sweep.steps, "mean": mean, "low": lo, "high": hi, "runs": cum[g.indices]}
        top = max(top, float(np.nanmax(mean)) if mean.size else 0.0)
    scale = 1.0 / top if top > 0 else 0.0
    for d in out.values():
        for k in ("mean", "low", "high", "runs"):
            d[k] = d[k] * scale
    out["_max"] = top
    return out


def interaction_frequency(sweep: Sweep, group: Any = None, every: int = 100, agent: int | None = None):
    """Share of agent steps in contact with each object, per bin of `every` steps (figs 9, 14).
    agent: one agent's index, or None for all agents together (contact steps / agent steps).
    Returns (bin end steps [bins], frequency [runs of the group, bins, objects])."""
    g = sweep.group(group)
    c = sweep.metrics["contact_object"][g.indices].astype(float)  # [n, W, agents, objects]
    c = c.sum(axis=2) if agent is None else c[:, :, agent]
    taken = sweep.metrics["steps_taken"][g.indices].astype(float) * (sweep.n_agents if agent is None else 1)
    steps, num = bin_windows(sweep, c, every)
    _, den = bin_windows(sweep, taken, every)
    with np.errstate(invalid="ignore", divide="ignore"):
        return steps, np.where(den[..., None] > 0, num / den[..., None], np.nan)


def action_totals(sweep: Sweep, group: Any = None) -> np.ndarray:
    """[runs of the group, agents, actions]: how often each agent chose each action in the whole
    run (sums to the steps the run took, per agent)."""
    g = sweep.group(group)
    return sweep.metrics["action_counts"][g.indices].sum(axis=1)


def turn_reversals(sweep: Sweep) -> dict[str, np.ndarray]:
    """Per run and window [runs, windows], both agents summed: `observed`, the steps at which an
    agent turned the other way than at the step before (`rotation_reversals`, both steps in the
    window); `pairs`, the pairs of consecutive steps taken in the window, where a reversal can
    happen; `shuffled`, the reversals a random order of the window's own actions would make on
    average. A window of n steps with l left and r right turns has n - 1 pairs, each of them, in a
    uniformly random order, a left and a right turn with probability 2 l r / (n (n - 1)): 2 l r / n
    reversals expected. Needs a sweep that records `rotation_reversals`."""
    if "rotation_reversals" not in sweep.metrics:
        raise SweepError(f"{sweep.name} does not record rotation_reversals (the order of turns): a sweep made "
                         "before that metric counts each action per window but not their order")
    a = sweep.metrics["action_counts"].astype(float)  # [R, W, agents, actions]
    left, right = a[..., sweep.actions.index("rotate_left")], a[..., sweep.actions.index("rotate_right")]
    return {"observed": sweep.metrics["rotation_reversals"].astype(float).sum(axis=2),
            "pairs": np.maximum(sweep.metrics["steps_taken"].astype(float) - 1, 0) * sweep.n_agents,
            "shuffled": (2 * left * right / np.maximum(a.sum(axis=-1), 1)).sum(axis=2)}


def nan_ratio(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    """num / den where den > 0, NaN elsewhere."""
    return np.where(den > 0, num / np.where(den > 0, den, 1), np.nan)


def reversal_rates(sweep: Sweep, group: Any = None, every: int = 1000) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A group's turning back over time, in bins of `every` agent steps (`bin_windows`): (step at
    each bin's end [bins], reversals per pair of consecutive steps [runs of the group, bins],
    reversals over those a random order of each window's actions would make [runs, bins];
    `turn_reversals`)."""
    g = sweep.group(group)
    t = {k: v[g.indices] for k, v in turn_reversals(sweep).items()}
    steps, b = bin_windows(sweep, np.stack([t["observed"], t["pairs"], t["shuffled"]], axis=-1), every, reduce="sum")
    return steps, nan_ratio(b[..., 0], b[..., 1]), nan_ratio(b[..., 0], b[..., 2])


OBS_CLASSES = ("touches an object or the other agent itself",
               "only watches the other agent touch an object",
               "sees the other agent, no contact anywhere",
               "none of these")


def observation_classes(sweep: Sweep, window: int = 50) -> dict:
    """What each agent did or saw in each 20-step window, and its curiosity then (the paper's
    claim that curiosity rises when an agent merely watches the other act, section 5).

    Classes (per run, agent and window; first that applies): 0 the agent touched an object or the
    other agent; 1 it touched nothing, but the other agent touched an object that was in this
    agent's view during the window; 2 no contact by anyone, the other agent in view; 3 otherwise.
    Curiosity is taken relative to the agent's own trailing moving average over `window` windows
    (`excess`), which removes the slow trend of learning.
    Returns {"cls" int [runs, windows, agents], "excess" [runs, windows, agents],
    "per_run" [runs, classes] mean excess over agents and windows of each class, "count" [classes]}.
    Needs a 2-agent sweep.
    """
    if sweep.n_agents != 2:
        raise SweepError(f"{sweep.path} has {sweep.n_agents} agent(s): watching another agent needs two")
    touch = sweep.metrics["contact_object"]  # [R, W, 2, K]
    own = (touch.sum(axis=3) > 0) | (sweep.metrics["contact_agent"] > 0)  # [R, W, 2]
    other_touch = touch[:, :, ::-1]  # the other agent's contacts per object
    view = sweep.metrics["view_fraction"]  # [R, W, 2, K + 1]
    k = len(sweep.objects)
    watched = np.any((other_touch > 0) & (view[..., :k] > 0), axis=3)
    sees_other = view[..., k] > 0
    anyone = own | own[:, :, ::-1]
    cls = np.full(own.shape, 3, np.int32)
    cls = np.where(~anyone & sees_other, 2, cls)
    cls = np.where(~own & watched, 1, cls)
    cls = np.where(own, 0, cls)
    cur = sweep.metrics["curiosity"].astype(float)
    excess = cur - moving_average(cur, window, axis=1)
    per_run = np.full((sweep.n_runs, len(OBS_CLASSES)), np.nan)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        for c in range(len(OBS_CLASSES)):
            per_run[:, c] = np.nanmean(np.where(cls == c, excess, np.nan), axis=(1, 2))
    count = np.asarray([(cls == c).sum() for c in range(len(OBS_CLASSES))])
    return {"cls": cls, "excess": excess, "per_run": per_run, "count": count}
