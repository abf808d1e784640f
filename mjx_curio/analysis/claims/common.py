"""What every claim shares: the significance level and the scale a comparison needs, the presets a
sweep stands for (`assign_presets`), the record of one test (`Tested`) and of one claim
(`ClaimResult`), and the helpers that pick a claim's groups, format its statistic and decide its
verdict. Imports `sweeps`.
"""

from __future__ import annotations

import dataclasses
import math
import pathlib
import warnings
from typing import Mapping, Sequence

import numpy as np

from mjx_curio.analysis.sweeps import Group, Sweep, SweepError, load_sweeps, merge_sweeps, side_experiment

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
    """The sweep serving `preset`, then those of its side experiments (`<preset>.<label>`) given
    that learn as it does: a claim may read a metric the preset's sweep lacks from a side
    experiment only where it is the same algorithm (not one with the authors' VAE layers or
    `z=mean`, which stand beside the preset to compare, not in its place)."""
    own = presets.get(preset)
    return [s for key, s in presets.items()
            if key == preset or (key.startswith(preset + ".")
                                 and (own is None or s.learner_config() == own.learner_config()))]


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


def paper_group(sweep: Sweep, policy: str) -> Group | None:
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
        g = paper_group(s, policy) if s is not None else None
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
