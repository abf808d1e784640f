"""The paper's numbers beside ours: each number the paper reads off one of its figures (a
curiosity level at some step, where a curve is lowest, a policy's contacts as a share of UCB's),
measured the same way on the sweeps, as a mean over seeds with its 95% CI.

    from mjx_curio import analysis as an
    print(an.paper_numbers_table("runs/paper").to_markdown())

The paper reads each number from one run, most of them from a curve smoothed over 50 points of 20
steps (1,000 steps). Here every run becomes such a curve the same way for every source
(`run_curves`: the curiosity, the mean of the agents, in bins of 1,000 steps; the contacts summed
from the start), so a sweep's metrics and a reduced full-length sweep (the `curves` of
docs/results/full_length.json) are measured alike. The paper's runs are 80,000 steps long; a
reading about a later part of the run than a sweep reached is left out for that sweep ("—").
Imports `claims`, `stats`, `sweeps` and `tables`.
"""

from __future__ import annotations

import dataclasses
from typing import Mapping

import numpy as np

from mjx_curio.analysis.claims import assign_presets, paper_group
from mjx_curio.analysis.stats import agent_contacts, bin_windows, mean_ci, object_contacts
from mjx_curio.analysis.sweeps import POLICY_LABELS, Sweep
from mjx_curio.analysis.tables import Table

BIN_STEPS = 1_000  # the paper's smoothing span: 50 points of 20 steps
PAPER_STEPS = 80_000
# The paper's curiosity figures with readings to draw (`figures.plot_paper_readings_panels`):
# (figure, the preset that runs its setting, the policy it plots).
READING_PANELS = (("fig. 8", "single_agent", "eps"), ("fig. 17", "multi_agent", "eps"),
                  ("fig. 18", "multi_agent", "ucb"), ("fig. 20", "multi_agent", "boltzmann"))
END_STEPS = 2_000  # "at the end": the last two bins


def run_curves(sweep: Sweep, every: int = BIN_STEPS) -> dict:
    """Per run, in bins of `every` steps: {"steps" [bins] (each bin's last step), "runs" the
    curiosity (mean of the agents, NaN-skipping) [runs, bins], "object_contacts" and
    "agent_contacts" the contact steps summed from the start [runs, bins]}. The `curves` of a
    full-length sweep's JSON hold the same (there as lists)."""
    steps, c = bin_windows(sweep, np.nanmean(sweep.metrics["curiosity"].astype(float), axis=2), every=every,
                           reduce="mean")
    out = {"steps": np.asarray(steps, int), "runs": c}
    for key, counts in (("object_contacts", object_contacts(sweep)), ("agent_contacts", agent_contacts(sweep))):
        _, binned = bin_windows(sweep, counts, every=every, reduce="sum")
        out[key] = np.cumsum(binned, axis=1)
    return out


@dataclasses.dataclass(frozen=True)
class Reading:
    """One number the paper reads off a figure: where (`figure`, `preset`, `policy`), what, the
    paper's words, and how to measure it (`measure` names a function of `MEASURES`, `args` its
    arguments after the curves and the group's runs). `box`: for a curiosity level, the paper's
    words as a box on its curve, (first step, last step, low, high), which
    `figures.plot_paper_readings` draws."""

    figure: str
    preset: str
    policy: str
    what: str
    paper: str
    measure: str
    args: tuple = ()
    box: tuple | None = None


READINGS = (
    Reading("fig. 8", "single_agent", "eps", "curiosity, steps 0-1,000", "close to 1", "level", (0, 1_000),
            box=(0, 1_000, 0.95, 1.05)),
    Reading("fig. 8", "single_agent", "eps", "curiosity, steps 4,000-6,000", "about 0.55", "level", (4_000, 6_000),
            box=(4_000, 6_000, 0.53, 0.57)),
    Reading("fig. 8", "single_agent", "eps", "curiosity, steps 10,000-15,000", "0.57-0.59", "level", (10_000, 15_000),
            box=(10_000, 15_000, 0.57, 0.59)),
    Reading("fig. 8", "single_agent", "eps", "curiosity, the last 2,000 steps", "about 0.63 (at 80,000)", "end",
            box=(78_000, 80_000, 0.61, 0.65)),
    Reading("fig. 17", "multi_agent", "eps", "curiosity, steps 0-1,000", "0.7", "level", (0, 1_000),
            box=(0, 1_000, 0.68, 0.72)),
    Reading("fig. 17", "multi_agent", "eps", "lowest curiosity (1,000-step bins)", "about 0.53", "lowest",
            box=(20_000, 25_000, 0.51, 0.55)),
    Reading("fig. 17", "multi_agent", "eps", "step of the lowest curiosity", "20,000-25,000", "lowest_step"),
    Reading("fig. 17", "multi_agent", "eps", "curiosity, the last 2,000 steps", "over 0.6 (at 80,000)", "end",
            box=(78_000, 80_000, 0.60, 0.65)),
    Reading("fig. 18", "multi_agent", "ucb", "curiosity, steps 0-1,000", "above 1", "level", (0, 1_000),
            box=(0, 1_000, 1.0, 1.1)),
    Reading("fig. 18", "multi_agent", "ucb", "step of the lowest curiosity", "10,000-30,000", "lowest_step"),
    Reading("fig. 18", "multi_agent", "ucb", "curiosity, steps 30,000-80,000", "0.65-0.70", "level", (30_000, 80_000),
            box=(30_000, 80_000, 0.65, 0.70)),
    Reading("fig. 20", "multi_agent", "boltzmann", "curiosity, steps 15,000-35,000", "about 0.7", "level",
            (15_000, 35_000), box=(15_000, 35_000, 0.68, 0.72)),
    Reading("fig. 21", "multi_agent", "eps", "object contacts, % of UCB's", "about 50 %", "share_of_ucb",
            ("object_contacts",)),
    Reading("fig. 21", "multi_agent", "boltzmann", "object contacts, % of UCB's", "about 15 %", "share_of_ucb",
            ("object_contacts",)),
    Reading("fig. 21", "multi_agent", "ucb", "% of the run's object contacts made by step 40,000", "60 %", "share_by",
            ("object_contacts", 40_000)),
    Reading("fig. 21", "multi_agent", "boltzmann", "runs touching an object after step 30,000", "none", "touching_after",
            ("object_contacts", 30_000)),
    Reading("fig. 22", "multi_agent", "eps", "agent-agent contacts, % of UCB's", "about 10 %", "share_of_ucb",
            ("agent_contacts",)),
    Reading("fig. 22", "multi_agent", "boltzmann", "agent-agent contacts, % of UCB's", "about 50 %", "share_of_ucb",
            ("agent_contacts",)),
)


# ------------------------------------------------------------------------------- the measures
# Each takes the curves (`run_curves`), the runs of the reading's group and of the same sweep's
# UCB group, and its arguments; it returns (cell text, number) or None where the sweep's runs are
# too short for it.


def _steps(cv) -> np.ndarray:
    return np.asarray(cv["steps"], int)


def _mean_cell(x, digits: int = 3, unit: str = "") -> tuple[str, float]:
    m, lo, hi, _ = mean_ci(np.asarray(x, float))
    return f"{m:.{digits}g}{unit} [{lo:.{digits}g}, {hi:.{digits}g}]", float(m)


def _level(cv, runs, ucb, start, end):
    steps = _steps(cv)
    if steps[-1] < end:
        return None
    bins = (steps > start) & (steps <= end)
    return _mean_cell(np.nanmean(np.asarray(cv["runs"], float)[np.ix_(runs, bins)], axis=1))


def _end(cv, runs, ucb):
    steps = _steps(cv)
    return _level(cv, runs, ucb, int(steps[-1]) - END_STEPS, int(steps[-1]))


def _lowest_bins(cv, runs) -> tuple[np.ndarray, np.ndarray] | None:
    """Each run's lowest binned curiosity after the first bin, and the middle step of its bin
    (NaN for a run with no finite bin there); None for curves of fewer than two bins."""
    steps = _steps(cv)
    if len(steps) < 2:
        return None
    c = np.asarray(cv["runs"], float)[np.ix_(runs, np.arange(1, len(steps)))]
    some = np.isfinite(c).any(axis=1)
    i = np.nanargmin(np.where(some[:, None], c, 0.0), axis=1)
    middle = steps[1:][i] - (steps[1] - steps[0]) / 2
    return np.where(some, c[np.arange(len(runs)), i], np.nan), np.where(some, middle, np.nan)


def _lowest_step_cell(at) -> str:
    m, lo, hi, _ = mean_ci(np.asarray(at, float))
    return f"{m:,.0f} [{lo:,.0f}, {hi:,.0f}] (runs: {np.nanmin(at):,.0f}-{np.nanmax(at):,.0f})"


def _lowest(cv, runs, ucb):
    lowest = _lowest_bins(cv, runs)
    return None if lowest is None else _mean_cell(lowest[0])


def _lowest_step(cv, runs, ucb):
    lowest = _lowest_bins(cv, runs)
    if lowest is None:
        return None
    return _lowest_step_cell(lowest[1]), float(np.nanmean(lowest[1]))


def _share_of_ucb(cv, runs, ucb, key):
    total = np.asarray(cv[key], float)[:, -1]
    top = total[ucb].mean()
    if not top > 0:
        return None
    return _mean_cell(100 * total[runs] / top, unit=" %")


def _share_by(cv, runs, ucb, key, step):
    steps = _steps(cv)
    if steps[-1] <= step or step not in steps:
        return None
    cum = np.asarray(cv[key], float)[runs]
    with np.errstate(invalid="ignore", divide="ignore"):
        share = 100 * cum[:, list(steps).index(step)] / cum[:, -1]  # NaN for a run that never touched
    return _mean_cell(share, unit=" %")


def _touching_after(cv, runs, ucb, key, step):
    steps = _steps(cv)
    if steps[-1] <= step or step not in steps:
        return None
    cum = np.asarray(cv[key], float)[runs]
    k = int((cum[:, -1] - cum[:, list(steps).index(step)] > 0).sum())
    return f"{k} of {len(runs)}", float(k)


MEASURES = {"level": _level, "end": _end, "lowest": _lowest, "lowest_step": _lowest_step,
            "share_of_ucb": _share_of_ucb, "share_by": _share_by, "touching_after": _touching_after}


def reading_value(reading: Reading, curves: Mapping, groups: Mapping[str, list]):
    """`reading` measured on `curves` (`run_curves`, or a full-length JSON's) whose runs of each
    policy are `groups` ({policy: run indices}): (cell text, number), or None where the runs are
    too short for it or lack the policy (or UCB, for a share of UCB's)."""
    if reading.policy not in groups or (reading.measure == "share_of_ucb" and "ucb" not in groups):
        return None
    return MEASURES[reading.measure](curves, list(groups[reading.policy]), list(groups.get("ucb", [])), *reading.args)


def paper_numbers_table(sweeps, full_length: Mapping[str, tuple[Mapping, Mapping]] | None = None,
                        full_length_label: str = "80,000 steps", label: str = "the sweeps") -> Table:
    """One row per reading of `READINGS`: the figure, the setting, what is read, the paper's
    number, and ours on the preset sweeps (`sweeps`, as `claims.assign_presets` takes them; each
    preset's group in the paper's setting; the column headed `label`); with `full_length` ({preset:
    (curves, {policy: run indices})}, e.g. from full_length.json), a column of the same on those
    runs, headed `full_length_label`."""
    presets = assign_presets(sweeps)
    curves = {}
    for name in dict.fromkeys(r.preset for r in READINGS):
        s = presets.get(name)
        if s is not None:
            gs = {p: paper_group(s, p) for p in ("eps", "boltzmann", "ucb")}
            curves[name] = (run_curves(s), {p: g.indices for p, g in gs.items() if g is not None}, s)
    cols = ["figure", "setting", "what", "the paper (one run, 80,000 steps)", f"here: {label}"]
    if full_length:
        cols.append(f"here: {full_length_label}")
    rows, values = [], []
    for r in READINGS:
        ours = curves.get(r.preset)
        cell = reading_value(r, ours[0], ours[1]) if ours else None
        long = full_length.get(r.preset) if full_length else None
        cell_long = reading_value(r, *long) if long else None
        agents = "one agent" if r.preset.startswith("single") else "two agents"
        row = [r.figure, f"{agents}, {POLICY_LABELS[r.policy]}", r.what, r.paper, cell[0] if cell else "—"]
        if full_length:
            row.append(cell_long[0] if cell_long else "—")
        rows.append(row)
        values.append({"figure": r.figure, "preset": r.preset, "policy": r.policy, "what": r.what, "paper": r.paper,
                       "ours": cell[1] if cell else None, "ours_long": cell_long[1] if cell_long else None})
    sizes = "; ".join(f"{s.name}, {s.steps_done:,} steps, " + ", ".join(
        f"{POLICY_LABELS[p]} {len(i)}" for p, i in g.items()) + " runs" for _, g, s in curves.values())
    note = (f"Mean over runs [95 % CI]; every run's curiosity averaged over its agents and over bins of "
            f"{BIN_STEPS:,} steps (the paper's smoothing span), the contacts summed from the start. The lowest "
            f"curiosity: each run's lowest bin after the first; its step: the bin's middle. % of UCB's: each run's "
            f"total over the mean total of the UCB runs. —: the runs are shorter than the reading needs. "
            f"{label[0].upper() + label[1:]}: {sizes}.")
    return Table(cols, rows, values, note)


def readings_side_by_side(a: Sweep, b: Sweep, labels: tuple[str, str], figure: str = "fig. 8",
                          shared_only: bool = False) -> Table:
    """Two sweeps of one figure's setting that differ in one setting (e.g. the VAE's layers),
    beside the paper's curiosity levels for that figure: per level reading of `READINGS` that both
    sweeps reach, in the window where the paper's curve is lowest (its `lowest` reading's box)
    where both reach it, and over the last 2,000 steps both ran, each sweep's curiosity, the
    posterior spread within it and, where a sweep records it, the curiosity of its training batches
    (`batch_curiosity`, the statistic the authors' code logs in its place): each run's mean over
    the window's 1,000-step bins; mean over the runs of the figure's policy [95 % CI], and b minus
    a (Welch: [95 % CI], p) where both have it. Where the paper reads the figure's lowest point,
    also each run's lowest 1,000-step bin after the first, over the steps both ran, and the bin's
    middle step, as `paper_numbers_table` reads them. `labels` name a and b. `shared_only`: only
    the measures both sweeps record (set against a sweep that records the curiosity alone, the
    other's further measures would repeat a table that has them on both sides)."""
    from mjx_curio.analysis.significance import t_critical, welch_t

    readings = [r for r in READINGS if r.figure == figure and r.measure in ("level", "end")]
    if not readings:
        raise ValueError(f"figure={figure!r} has no curiosity levels among the paper's readings")
    policy = readings[0].policy
    groups = {}
    for s in (a, b):
        groups[s.name] = paper_group(s, policy)
        if groups[s.name] is None:
            raise ValueError(f"{s.name} has no {POLICY_LABELS[policy]} runs in {figure}'s setting")
    reached = min(a.steps_done, b.steps_done)
    # A level as its window; the lowest point as the window where the paper's curve is lowest.
    windows = sorted([(r.what, r.paper, *r.args) for r in readings if r.measure == "level"]
                     + [(f"curiosity, steps {r.box[0]:,}-{r.box[1]:,} (the paper's lowest)", r.paper, *r.box[:2])
                        for r in READINGS if r.figure == figure and r.measure == "lowest" and r.box],
                     key=lambda w: w[2])
    windows = [w for w in windows if w[3] <= reached]
    last = reached // BIN_STEPS * BIN_STEPS
    if last < END_STEPS:
        raise ValueError(f"{a.name} and {b.name} have {reached:,} steps both; want {END_STEPS:,} or more")
    windows.append((f"curiosity, steps {last - END_STEPS:,}-{last:,} (the last both ran)", "—", last - END_STEPS, last))
    metrics = [("curiosity", "curiosity"), ("curiosity_spread", "posterior spread"),
               ("batch_curiosity", "training batches' curiosity")]
    metrics = [(m, name) for m, name in metrics
               if (all if shared_only else any)(m in s.metrics for s in (a, b))]

    def per_run(s: Sweep, metric: str, start: int, end: int) -> np.ndarray | None:
        if metric not in s.metrics:
            return None
        steps, x = bin_windows(s, np.nanmean(s.metrics[metric].astype(float), axis=2), every=BIN_STEPS,
                               reduce="mean")
        bins = (np.asarray(steps) > start) & (np.asarray(steps) <= end)
        return np.nanmean(x[np.ix_(groups[s.name].indices, bins)], axis=1)

    def lowest(s: Sweep) -> tuple[np.ndarray, np.ndarray]:
        """Each run's lowest 1,000-step bin of curiosity after the first, over the steps both ran,
        and its bin's middle step (`_lowest_bins`, as the paper's readings take it)."""
        cv = run_curves(s)
        keep = cv["steps"] <= last
        return _lowest_bins({"steps": cv["steps"][keep], "runs": cv["runs"][:, keep]}, list(groups[s.name].indices))

    cols = ["window", "what", "the paper (one run)", labels[0], labels[1], f"{labels[1]} − {labels[0]}", "p"]
    rows, values = [], []

    def add(window: str, name: str, paper: str, metric: str, start: int, end: int, xa, xb,
            cell=lambda x: _mean_cell(x)[0], fmt: str = ".3f"):
        """A row: each side's runs `xa`, `xb` (None: the sweep lacks the metric) as `cell` writes
        them, and b - a with its interval in `fmt`."""
        cells = [cell(x) if x is not None else "—" for x in (xa, xb)]
        value = {"start": start, "end": end, "metric": metric,
                 labels[0]: float(np.nanmean(xa)) if xa is not None else None,
                 labels[1]: float(np.nanmean(xb)) if xb is not None else None, "diff": None, "p": None}
        diff = ["—", "—"]
        if xa is not None and xb is not None:
            w = welch_t(xb, xa)
            half = t_critical(w["df"]) * w["se"] if np.isfinite(w["se"]) else np.nan
            diff = [f"{w['diff']:+{fmt}} [{w['diff'] - half:+{fmt}}, {w['diff'] + half:+{fmt}}]", f"{w['p']:.2g}"]
            value.update(diff=w["diff"], p=w["p"])
        rows.append([window, name, paper, *cells, *diff])
        values.append(value)

    for what, paper, start, end in windows:
        for metric, name in metrics:
            add(what.split(", ", 1)[1], name, paper if metric == "curiosity" else "—", metric, start, end,
                per_run(a, metric, start, end), per_run(b, metric, start, end))
    lows = [r for r in READINGS if r.figure == figure and r.measure in ("lowest", "lowest_step")]
    if lows:
        la, lb = lowest(a), lowest(b)
        for r in lows:
            window = f"the lowest bin, steps 0-{last:,}"
            if r.measure == "lowest":
                add(window, "curiosity", r.paper, r.measure, 0, last, la[0], lb[0])
            else:
                add(window, "its step (the bin's middle)", r.paper, r.measure, 0, last, la[1], lb[1],
                    _lowest_step_cell, ",.0f")
    note = (f"{figure}'s setting ({POLICY_LABELS[policy]}): {labels[0]} is {a.name} ({len(groups[a.name].indices)} "
            f"runs, {a.steps_done:,} steps), {labels[1]} {b.name} ({len(groups[b.name].indices)} runs, "
            f"{b.steps_done:,} steps).")
    if any(m == "curiosity_spread" for m, _ in metrics):
        note += (" The posterior spread is the part of the curiosity that sampling the next view's latent adds (its "
                 "expectation), the rest is the memory's error against the posterior mean.")
    if lows:
        note += (f" The lowest bin: each run's lowest {BIN_STEPS:,}-step bin of curiosity after the first, over the "
                 "steps both ran, and that bin's middle step.")
    if any(m == "batch_curiosity" for m, _ in metrics) and not all("batch_curiosity" in s.metrics for s in (a, b)):
        note += " The training batches' curiosity: —, a sweep made before it was recorded."
    return Table(cols, rows, values, note)
