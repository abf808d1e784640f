"""Read a sweep directory and redraw the paper's figures from it.

    from mjx_curio import analysis
    sweep = analysis.load("runs/paper")             # manifest, metrics, checkpoints
    sweep.runs, sweep.steps, sweep.metrics["curiosity"]   # [runs], [windows], [runs, windows, agents]
    ucb = sweep.select(policy="ucb")                 # run indices
    fig, ax = plt.subplots(); analysis.plot_curiosity(sweep, ax, "ucb")

A sweep (written by `python -m mjx_curio.sweep`, see sweep.py and metrics.py) holds metrics per
window of `metrics_every` (20) agent steps; `Sweep.metrics` holds the windows that are final
(`progress.json`), so a sweep still running can be read too. Runs that share a policy and its
setting (eps, temperature or c) but differ in seed form a `Group`; every figure pools a group's
seeds into a mean and a 95% confidence band of that mean (Student t, across seeds).

One function per figure of the paper (section 4), each drawing into a matplotlib Axes (or
Figure) it is given and returning it:

    plot_curiosity                 figs 8, 15, 17, 18, 20: curiosity per agent, raw + moving average
    plot_curiosity_groups          fig 11: curiosity per policy
    plot_temperatures              fig 19: Boltzmann temperatures compared
    plot_single_vs_multi           fig 23: curiosity, single- vs multi-agent sweep
    plot_vae_single_vs_multi       fig 24: VAE loss, single- vs multi-agent sweep
    plot_cumulative_interactions   figs 21 (objects), 22 (agent-agent), normalised to the maximum
    plot_interaction_frequency     figs 9, 14: contacts per object over time, 100-step bins
    plot_action_histogram          figs 10, 12: actions chosen per agent
    plot_reconstructions           figs 7, 13: real views and VAE reconstructions, early vs late
    plot_view_fractions            what each agent looks at over time (objects, other agent)
    plot_observational             curiosity in windows where an agent only watches the other act
    plot_losses                    the world model's training losses
    headline_table                 mean +- sd across seeds per group of the key numbers

and the numbers behind them (`moving_average`, `mean_ci`, `cumulative_interactions`,
`interaction_frequency`, `action_totals`, `observation_classes`, `reconstructions`), which the
tests check. Loading needs only NumPy (and orbax for checkpoints); plotting needs matplotlib.
"""

from __future__ import annotations

import contextlib
import csv
import dataclasses
import functools
import io
import json
import logging
import math
import os
import pathlib
import re
import warnings
from typing import Any, Iterable, Sequence

import numpy as np

FORMAT = "mjx_curio.sweep/1"
FIGURES_DIRNAME = "figures"  # where the notebook saves figures inside a sweep directory (never written by a sweep)
SWEEP_OUTPUTS = ("manifest.json", "progress.json", "metrics", "checkpoints")  # what a sweep writes

POLICY_LABELS = {"eps": "ε-greedy", "boltzmann": "Boltzmann", "ucb": "UCB"}
SETTINGS = {"eps": ("eps", "ε"), "boltzmann": ("temperature", "T"), "ucb": ("ucb_c", "c")}
# The paper's colours in figs 21 and 22: eps blue, UCB orange, Boltzmann green.
POLICY_COLORS = {"eps": "tab:blue", "ucb": "tab:orange", "boltzmann": "tab:green"}
AGENT_COLORS = ("#1e9e3c", "#8a3fb0")  # the green and the purple cube
TARGET_COLORS = {"pyramid": "#ff8000", "cylinder": "#d62020", "sphere": "#e0c000", "disc": "#2050d0",
                 "other_agent": "#707070"}
STEPS_LABEL = "agent steps"
CURIOSITY_LABEL = "curiosity reward (squared latent distance)"


class SweepError(ValueError):
    """A directory is not a readable sweep, or lacks what was asked for. The message says what
    is missing and where."""


# ---------------------------------------------------------------------------------- loading


@dataclasses.dataclass(frozen=True)
class Run:
    """One row of a sweep's runs table (manifest `runs`, in the order of the metrics' first axis)."""

    index: int
    name: str
    policy: str
    seed: int
    eps: float
    temperature: float
    ucb_c: float

    @property
    def setting(self) -> tuple[str, float]:
        """(name, value) of the policy's own setting: eps, temperature or ucb_c."""
        name = SETTINGS[self.policy][0]
        return name, getattr(self, name)

    @property
    def group_label(self) -> str:
        return f"{POLICY_LABELS[self.policy]} ({SETTINGS[self.policy][1]}={self.setting[1]:g})"


@dataclasses.dataclass(frozen=True)
class Group:
    """Runs with the same policy and setting (they differ in seed only)."""

    label: str
    policy: str
    setting: str
    value: float
    indices: np.ndarray  # run indices, ascending

    @property
    def n(self) -> int:
        return len(self.indices)

    @property
    def slug(self) -> str:
        return f"{self.policy}-{self.setting}{self.value:g}"

    @property
    def seeds_text(self) -> str:
        return f"{self.n} seed{'s' if self.n != 1 else ''}"


class Sweep:
    """A sweep directory read into NumPy arrays. Build with `load(path)`.

    Attributes:
      path, name: the directory and its name.
      manifest, progress: the parsed manifest.json and progress.json.
      runs: list of `Run`, in the order of the metrics' first axis.
      n_agents, agent_names, actions, objects, view_targets: from the manifest.
      metrics_every: agent steps per metrics window.
      steps: int array [windows]: the agent step at the end of each final window.
      metrics: name -> array [runs, windows, ...] (see `metrics.SCHEMA` / manifest
        `metrics.schema` for units and meanings), the final windows only.
    """

    def __init__(self, path: pathlib.Path, manifest: dict, progress: dict, steps: np.ndarray, metrics: dict):
        self.path = pathlib.Path(path)
        self.name = pathlib.Path(os.path.abspath(self.path)).name
        self.manifest = manifest
        self.progress = progress
        self.runs = [Run(**{k: r[k] for k in ("index", "name", "policy", "seed", "eps", "temperature", "ucb_c")})
                     for r in manifest["runs"]]
        self.n_agents = int(manifest["n_agents"])
        self.agent_names = list(manifest["agent_names"])
        self.actions = list(manifest["actions"])
        self.objects = list(manifest["objects"])
        self.view_targets = list(manifest["view_targets"])
        self.metrics_every = int(manifest["metrics"]["every"])
        self.steps = steps
        self.metrics = metrics
        self._ckpts = None
        self._raw_cache: dict[int, dict] = {}

    # -------------------------------------------------------------------------- the runs table

    @property
    def n_runs(self) -> int:
        return len(self.runs)

    @property
    def n_windows(self) -> int:
        return len(self.steps)

    @property
    def steps_done(self) -> int:
        return int(self.steps[-1]) if len(self.steps) else 0

    @property
    def image(self) -> int:
        return int(self.manifest["run_config"]["image"])

    @property
    def table(self) -> dict[str, np.ndarray]:
        """The runs table as columns: index, name, policy, seed, eps, temperature, ucb_c."""
        cols = {f.name: [getattr(r, f.name) for r in self.runs] for f in dataclasses.fields(Run)}
        return {k: np.asarray(v) for k, v in cols.items()}

    def select(self, policy: str | Sequence[str] | None = None, seed=None, eps=None, temperature=None,
               ucb_c=None) -> np.ndarray:
        """Indices of the runs matching every given criterion (a value or a list of values;
        floats compare with a tolerance). Raises SweepError when none matches."""
        keep = np.ones(self.n_runs, bool)
        table = self.table
        for name, want in (("policy", policy), ("seed", seed), ("eps", eps), ("temperature", temperature),
                           ("ucb_c", ucb_c)):
            if want is None:
                continue
            wants = list(want) if isinstance(want, (list, tuple, set, np.ndarray)) else [want]
            col = table[name]
            if name in ("policy",):
                match = np.isin(col, wants)
            elif name == "seed":
                match = np.isin(col, [int(w) for w in wants])
            else:
                match = np.any([np.isclose(col.astype(float), float(w)) for w in wants], axis=0)
            keep &= match
        out = np.flatnonzero(keep)
        if not len(out):
            given = {k: v for k, v in dict(policy=policy, seed=seed, eps=eps, temperature=temperature,
                                            ucb_c=ucb_c).items() if v is not None}
            raise SweepError(f"no run of {self.path} matches {given}; its runs: {', '.join(r.name for r in self.runs)}")
        return out

    def groups(self, policy: str | None = None) -> list[Group]:
        """The sweep's groups (policy and setting; seeds pooled), in the order of the runs."""
        found: dict[tuple, list[int]] = {}
        for r in self.runs:
            if policy is None or r.policy == policy:
                found.setdefault((r.policy, *r.setting), []).append(r.index)
        return [Group(self.runs[ix[0]].group_label, p, s, float(v), np.asarray(ix)) for (p, s, v), ix in found.items()]

    def group(self, key: Any = None) -> Group:
        """A group from: a Group; a policy name (its first setting); a group label; a run name
        or index (that run alone); a list of run indices; None (the first group)."""
        if isinstance(key, Group):
            return key
        gs = self.groups()
        if key is None:
            return gs[0]
        if isinstance(key, str):
            for g in gs:
                if key in (g.label, g.slug):
                    return g
            by_policy = [g for g in gs if g.policy == key]
            if by_policy:
                return by_policy[0]
            for r in self.runs:
                if r.name == key:
                    return Group(f"{r.group_label}, seed {r.seed}", r.policy, *r.setting, np.asarray([r.index]))
            raise SweepError(f"{key!r} is neither a policy, a group nor a run of {self.path}; groups: "
                             f"{', '.join(g.label for g in gs)}; runs: {', '.join(r.name for r in self.runs)}")
        if isinstance(key, (int, np.integer)):
            r = self.run(int(key))
            return Group(f"{r.group_label}, seed {r.seed}", r.policy, *r.setting, np.asarray([r.index]))
        idx = np.asarray(key, int).reshape(-1)
        for i in idx:
            self.run(int(i))
        rs = {(self.runs[i].policy, *self.runs[i].setting) for i in idx}
        label = self.runs[idx[0]].group_label if len(rs) == 1 else "runs " + ", ".join(map(str, idx))
        r0 = self.runs[idx[0]]
        return Group(label, r0.policy, *r0.setting, idx)

    def run(self, key: int | str) -> Run:
        """A run by index or name."""
        if isinstance(key, str):
            for r in self.runs:
                if r.name == key:
                    return r
            raise SweepError(f"no run named {key!r} in {self.path}; runs: {', '.join(r.name for r in self.runs)}")
        if not 0 <= int(key) < self.n_runs:
            raise SweepError(f"run index {key} is out of range: {self.path} has runs 0..{self.n_runs - 1}")
        return self.runs[int(key)]

    def agent_label(self, agent: int) -> str:
        return "agent" if self.n_agents == 1 else f"{self.agent_names[agent]} agent"

    def describe(self) -> str:
        """A few lines about the sweep: what ran, how far it got, what checkpoints exist."""
        cfg = self.manifest["config"]
        try:
            ckpts = self.checkpoint_steps()
        except SweepError:
            ckpts = []
        halted = self.progress.get("halted", {})
        lines = [
            f"{self.path}: {self.n_runs} runs, {self.n_agents} agent{'s' if self.n_agents > 1 else ''}, "
            f"walls={cfg.get('walls')}, image {self.image} px",
            f"  steps done {self.steps_done:,} of {int(cfg['steps']):,} ({self.n_windows} windows of {self.metrics_every})",
            f"  groups: {'; '.join(f'{g.label} x {g.n}' for g in self.groups())}",
            f"  checkpoints at steps: {', '.join(map(str, ckpts)) or 'none'}",
        ]
        if halted:
            lines.append("  halted runs (non-finite loss): " + ", ".join(f"{self.runs[int(r)].name} at {s}" for r, s in halted.items()))
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"Sweep({str(self.path)!r}, runs={self.n_runs}, agents={self.n_agents}, steps_done={self.steps_done})"

    # -------------------------------------------------------------------------- configs

    def learner_config(self):
        """The sweep's `LearnerConfig`, rebuilt from the manifest."""
        return learner_config(self.manifest)

    def run_config(self):
        """The sweep's `run.RunConfig`, rebuilt from the manifest."""
        return run_config(self.manifest)

    def run_specs(self) -> tuple:
        """The sweep's `sweep.RunSpec`s in order."""
        return run_specs(self.manifest)

    # -------------------------------------------------------------------------- checkpoints

    @property
    def checkpoints_dir(self) -> pathlib.Path:
        return self.path / "checkpoints"

    def checkpoints(self):
        """The sweep's `checkpoint.Checkpoints`, read-only (SweepError if there are none)."""
        if self._ckpts is None:
            state_dir = self.checkpoints_dir / "state"
            if not state_dir.is_dir():
                raise SweepError(f"{self.path} has no checkpoints: {state_dir} does not exist")
            from mjx_curio import checkpoint as ckpt_lib

            with _quiet_orbax():
                self._ckpts = ckpt_lib.Checkpoints(self.checkpoints_dir, read_only=True,
                                                   save_replay=(self.checkpoints_dir / "replay").is_dir())
        return self._ckpts

    def checkpoint_steps(self) -> list[int]:
        with _quiet_orbax():
            return self.checkpoints().state_steps()

    def replay_steps(self) -> list[int]:
        with _quiet_orbax():
            return self.checkpoints().replay_steps()

    def check_step(self, step: int) -> int:
        steps = self.checkpoint_steps()
        if int(step) not in steps:
            raise SweepError(f"{self.path} has no checkpoint at step {step}: {self.checkpoints_dir / 'state' / str(step)} "
                             f"does not exist; checkpoints exist at steps {', '.join(map(str, steps)) or 'none'}")
        return int(step)

    def restore_raw(self, step: int) -> dict:
        """Checkpoint `step` of every run as nested dicts of NumPy arrays keyed like `run.RunState`
        (leading runs axis, possibly with `padded_runs` extra copies at the end). Cached."""
        step = self.check_step(step)
        if step not in self._raw_cache:
            with _quiet_orbax():
                raw = self.checkpoints().restore_raw(step)
            while len(self._raw_cache) >= 2:  # keep two (early and late): a paper-size one is large
                self._raw_cache.pop(next(iter(self._raw_cache)))
            self._raw_cache[step] = _to_numpy(raw)
        return self._raw_cache[step]

    def params(self, step: int, run: int | str) -> dict:
        """Run `run`'s network parameters at checkpoint `step`: {"vae", "rnn", "self_model"}, each
        a flax parameter tree of NumPy arrays (self_model leaves have a leading agents axis)."""
        r = self.run(run).index
        learner = self.restore_raw(step)["learner"]
        return {k: _index_tree(learner[k], r) for k in ("vae", "rnn", "self_model")}


def load(path: str | pathlib.Path) -> Sweep:
    """Read the sweep in directory `path`. Raises SweepError (what is missing, where) if `path`
    is not a sweep directory, its manifest is not in the expected format, or its metrics are
    missing or do not have the shapes the manifest gives."""
    path = pathlib.Path(path).expanduser()
    if not path.exists():
        raise SweepError(f"{path} does not exist")
    if not path.is_dir():
        raise SweepError(f"{path} is not a directory (a sweep directory holds manifest.json, metrics/ and checkpoints/)")
    mpath = path / "manifest.json"
    if not mpath.is_file():
        raise SweepError(f"{path} is not a sweep directory: it has no manifest.json (a sweep directory, written by "
                         "`python -m mjx_curio.sweep`, holds manifest.json, progress.json, metrics/ and checkpoints/)")
    try:
        manifest = json.loads(mpath.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        raise SweepError(f"{mpath} is not valid JSON ({err})") from None
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
        got = manifest.get("format") if isinstance(manifest, dict) else type(manifest).__name__
        raise SweepError(f"{mpath} has format {got!r}; this reader understands {FORMAT!r}")
    for key in ("runs", "n_agents", "agent_names", "actions", "objects", "view_targets", "metrics", "config", "run_config"):
        if key not in manifest:
            raise SweepError(f"{mpath} lacks the key {key!r}")
    mdir = path / "metrics"
    if not mdir.is_dir():
        raise SweepError(f"{path} has no metrics directory ({mdir} does not exist)")
    ppath = path / "progress.json"
    progress = json.loads(ppath.read_text()) if ppath.is_file() else {}
    every = int(manifest["metrics"]["every"])
    windows_done = int(progress.get("windows_done", int(progress.get("steps_done", 0)) // every))
    if windows_done <= 0:
        raise SweepError(f"{path} holds no finished metrics yet ({ppath} "
                         f"{'does not exist' if not ppath.is_file() else 'says no steps are done'}): "
                         "the sweep writes it at its first checkpoint")
    n_runs, n_windows, n_agents = len(manifest["runs"]), int(manifest["metrics"]["windows"]), int(manifest["n_agents"])
    sizes = {"agents": n_agents, "actions": len(manifest["actions"]), "objects": len(manifest["objects"]),
             "view_targets": len(manifest["view_targets"]), "pose": 3, "xyz": 3}
    spath = mdir / "steps.npy"
    if not spath.is_file():
        raise SweepError(f"{path}: the metrics file {spath} is missing")
    steps = np.load(spath)[:windows_done].astype(np.int64)
    metrics = {}
    for name, spec in manifest["metrics"]["schema"].items():
        f = mdir / f"{name}.npy"
        if not f.is_file():
            raise SweepError(f"{path}: the metrics file {f} is missing (the manifest lists metric {name!r})")
        arr = np.load(f, mmap_mode="r")
        shape = (n_runs, n_windows) + tuple(sizes[d] for d in spec["dims"][2:])
        if arr.shape != shape:
            raise SweepError(f"{f} has shape {arr.shape}; the manifest says {shape} ({', '.join(spec['dims'])})")
        metrics[name] = np.array(arr[:, :windows_done])
    return Sweep(path, manifest, progress, steps, metrics)


def find_sweeps(path: str | pathlib.Path) -> list[pathlib.Path]:
    """`path` itself if it is a sweep directory (holds manifest.json), else its subdirectories
    that are, sorted by name. SweepError if there is none."""
    path = pathlib.Path(path).expanduser()
    if not path.is_dir():
        raise SweepError(f"{path} does not exist or is not a directory")
    if (path / "manifest.json").is_file():
        return [path]
    found = sorted(p for p in path.iterdir() if p.is_dir() and (p / "manifest.json").is_file())
    if not found:
        raise SweepError(f"{path} is not a sweep directory (no manifest.json) and none of its subdirectories is one")
    return found


def load_sweeps(path: str | pathlib.Path) -> list[Sweep]:
    """Every sweep in `path` (a sweep directory, or a directory holding sweep directories)."""
    return [load(p) for p in find_sweeps(path)]


def pick_single_multi(sweeps: Sequence[Sweep], policy: str = "ucb") -> tuple[Sweep | None, Sweep | None]:
    """A single-agent and a multi-agent sweep of `sweeps` to compare (figs 23, 24): both with
    runs of `policy`, preferring a pair with the same walls and image size, then walls "same",
    then the order given. (None, None) where no such pair exists."""
    def has(s):
        return any(r.policy == policy for r in s.runs)

    singles = [s for s in sweeps if s.n_agents == 1 and has(s)]
    multis = [s for s in sweeps if s.n_agents > 1 and has(s)]
    best, best_score = (None, None), None
    for i, a in enumerate(singles):
        for j, b in enumerate(multis):
            wa, wb = a.manifest["config"].get("walls"), b.manifest["config"].get("walls")
            score = (wa == wb, a.image == b.image, wa == "same", -i, -j)
            if best_score is None or score > best_score:
                best, best_score = (a, b), score
    return best


# ------------------------------------------------------------------------- configs from a manifest


def _recorded(cls, recorded: dict) -> dict:
    """The fields of config dataclass `cls` as a manifest recorded them. A knob newer than the
    sweep (absent from the record) takes the value the code had before it existed, its `legacy`
    metadata, so an old sweep loads as what it ran (not as today's default); knobs without
    one take their default, which was then the behaviour."""
    from mjx_curio import config as config_lib

    fields = {}
    for f in config_lib.knobs(cls):
        if f.name in recorded:
            value = recorded[f.name]
            fields[f.name] = tuple(value) if isinstance(value, list) else value
        elif "legacy" in f.metadata:
            fields[f.name] = f.metadata["legacy"]
    return fields


def learner_config(manifest: dict):
    """The `config.LearnerConfig` a sweep ran with, from its manifest's run_config.learner."""
    from mjx_curio.config import LearnerConfig

    return LearnerConfig(**_recorded(LearnerConfig, manifest["run_config"]["learner"]))


def run_config(manifest: dict):
    """The `run.RunConfig` a sweep ran with."""
    from mjx_curio.run import RunConfig

    return RunConfig(**_recorded(RunConfig, manifest["run_config"]), learner=learner_config(manifest))


def run_specs(manifest: dict) -> tuple:
    """The sweep's `sweep.RunSpec`s, in the order of the runs axis."""
    from mjx_curio.plan import RunSpec

    return tuple(RunSpec(r["policy"], int(r["seed"]), float(r["eps"]), float(r["temperature"]), float(r["ucb_c"]))
                 for r in manifest["runs"])


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


# ---------------------------------------------------------------------------- reconstructions


@dataclasses.dataclass
class Reconstructions:
    """Real views and what a run's VAE makes of them at several checkpoints (figs 7, 13)."""

    run: Run
    steps: list[int]  # checkpoints whose VAE decoded the frames
    frames: np.ndarray  # uint8 [N, H, W, 3], the real views
    sources: list[tuple[int, int, int]]  # (checkpoint step, run index, agent) each frame comes from
    decoded: dict[int, np.ndarray]  # step -> float [N, H, W, 3] in [0, 1]


@functools.lru_cache(maxsize=None)
def _autoencoder(cfg):
    import jax

    from mjx_curio import world_model as wm

    def f(params, frames):
        mu, _ = wm.encode(cfg, params, frames)
        return wm.decode(cfg, params, mu)

    return jax.jit(f)


def reconstructions(sweep: Sweep, run: int | str = 0, steps: Sequence[int] | None = None, n_frames: int = 8) -> Reconstructions:
    """Encode real views with run `run`'s VAE restored from each checkpoint in `steps` (default:
    the earliest and the latest) and decode the latent means.

    The real views are the views the agents had at those checkpoints, as the checkpoints store
    them (`RunState.frames`: every agent's current view, exactly what the VAE was fed at that
    step): first run `run`'s own, then other runs' (same arena, other places), up to `n_frames`.
    """
    r = sweep.run(run)
    all_steps = sweep.checkpoint_steps()
    if not all_steps:
        raise SweepError(f"{sweep.path} has no checkpoints in {sweep.checkpoints_dir / 'state'}")
    steps = [all_steps[0], all_steps[-1]] if steps is None else [sweep.check_step(s) for s in steps]
    steps = list(dict.fromkeys(steps))
    own, others = [], []
    for s in steps:
        frames = sweep.restore_raw(s)["frames"]  # [runs(+pad), agents, H, W, 3]
        for i in range(sweep.n_runs):
            for a in range(sweep.n_agents):
                (own if i == r.index else others).append(((s, i, a), frames[i, a]))
    # Other runs' views interleaved across runs, so a few columns show several runs.
    others.sort(key=lambda x: (x[0][1] % max(1, sweep.n_runs), x[0][0], x[0][2]))
    chosen = (own + others)[:n_frames]
    sources = [c[0] for c in chosen]
    frames = np.stack([c[1] for c in chosen]).astype(np.uint8)
    cfg = sweep.learner_config()
    decoded = {}
    for s in steps:
        vae = sweep.params(s, r.index)["vae"]
        decoded[s] = np.clip(np.asarray(_autoencoder(cfg)(vae, frames)), 0.0, 1.0)
    return Reconstructions(r, steps, frames, sources, decoded)


# ----------------------------------------------------------------------------------- plotting


def _group_list(sweep: Sweep, groups) -> list[Group]:
    if groups is None:
        return sweep.groups()
    if isinstance(groups, (str, Group, int, np.integer)):
        return [sweep.group(groups)]
    return [sweep.group(g) for g in groups]


def _band(ax, x, lo, hi, color, label=None, floor: float | None = 0.0):
    """A 95% confidence band; clipped at `floor` (the quantities drawn with the default 0 cannot
    be negative)."""
    if np.any(np.isfinite(lo)):
        if floor is not None:
            lo = np.maximum(lo, floor)
        ax.fill_between(x, lo, hi, color=color, alpha=0.2, linewidth=0, label=label)


def _finish(ax, title, xlabel, ylabel, legend=True, loc="best"):
    ax.set_title(title, fontsize=10)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    if legend and ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7, loc=loc)
    return ax


def _group_colors(gs: Sequence[Group]) -> list:
    """One colour per group: the policy's (figs 21, 22: eps blue, UCB orange, Boltzmann green),
    in shades of it when a policy has several settings."""
    import matplotlib

    maps = {"eps": "Blues", "ucb": "Oranges", "boltzmann": "Greens"}
    out = []
    for i, g in enumerate(gs):
        same = [h for h in gs if h.policy == g.policy]
        if len(same) == 1 or g.policy not in maps:
            out.append(POLICY_COLORS.get(g.policy, f"C{i}"))
        else:
            j = same.index(g)
            out.append(matplotlib.colormaps[maps[g.policy]](0.45 + 0.5 * j / (len(same) - 1)))
    return out


def plot_curiosity(sweep: Sweep, ax, group: Any = None, window: int = 50, raw: bool = True,
                   metric: str = "curiosity_sample"):
    """Curiosity reward per agent over training for one group (figs 8, 15, 17, 18, 20).

    Thin line: the raw reward sampled every `metrics_every` (20) steps (the paper's blue line;
    with several seeds, their mean). Thick line: its trailing moving average over `window`
    points (the paper's red line), mean over seeds, with the 95% confidence band across seeds.
    metric="curiosity" uses each window's mean reward instead of its last step's."""
    g = sweep.group(group)
    x = sweep.steps
    for a in range(sweep.n_agents):
        v = sweep.metrics[metric][g.indices, :, a]
        color = AGENT_COLORS[a % len(AGENT_COLORS)] if sweep.n_agents > 1 else "tab:red"
        name = sweep.agent_label(a)
        if raw:
            raw_color = color if sweep.n_agents > 1 else "tab:blue"
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                ax.plot(x, np.nanmean(v, axis=0), color=raw_color, alpha=0.3, linewidth=0.7,
                        label=f"{name}: raw, every {sweep.metrics_every} steps")
        mean, lo, hi, _ = mean_ci(moving_average(v, window, axis=1))
        ax.plot(x, mean, color=color, linewidth=2, label=f"{name}: moving average ({window} points)")
        _band(ax, x, lo, hi, color, label="95% CI across seeds" if a == 0 else None)
    agents = "per agent" if sweep.n_agents > 1 else "single agent"
    return _finish(ax, f"Curiosity reward, {agents}: {g.label}, {g.seeds_text}", STEPS_LABEL, CURIOSITY_LABEL)


def plot_curiosity_groups(sweep: Sweep, ax, groups=None, window: int = 50, colors=None, title=None,
                          metric: str = "curiosity_sample"):
    """Curiosity reward (mean of the agents) per group: moving average over `window` points,
    mean over seeds, 95% confidence band across seeds (fig 11: one curve per policy)."""
    gs = _group_list(sweep, groups)
    x = sweep.steps
    colors = colors if colors is not None else _group_colors(gs)
    for i, g in enumerate(gs):
        v = sweep.metrics[metric][g.indices].mean(axis=2)  # agents averaged, per run
        mean, lo, hi, _ = mean_ci(moving_average(v, window, axis=1))
        color = colors[i]
        ax.plot(x, mean, color=color, linewidth=2, label=f"{g.label}, {g.seeds_text}")
        _band(ax, x, lo, hi, color)
    who = "mean of both agents" if sweep.n_agents > 1 else "single agent"
    title = title or f"Curiosity reward per policy ({who}; moving average of {window} points, 95% CI band across seeds)"
    return _finish(ax, title, STEPS_LABEL, CURIOSITY_LABEL)


def plot_temperatures(sweep: Sweep, ax, window: int = 50):
    """Boltzmann temperatures compared: curiosity per temperature (fig 19)."""
    gs = sorted(sweep.groups("boltzmann"), key=lambda g: g.value)
    if not gs:
        raise SweepError(f"{sweep.path} has no Boltzmann runs")
    import matplotlib

    cmap = matplotlib.colormaps["viridis"]
    colors = [cmap(i / max(1, len(gs) - 1) * 0.85) for i in range(len(gs))]
    who = "mean of both agents" if sweep.n_agents > 1 else "single agent"
    return plot_curiosity_groups(sweep, ax, gs, window, colors,
                                 title=f"Boltzmann policy: curiosity per temperature T ({who}; moving average of "
                                       f"{window} points, 95% CI band)")


def _policy_group(sweep: Sweep, policy: str) -> Group:
    gs = sweep.groups(policy)
    if not gs:
        raise SweepError(f"{sweep.path} has no {policy!r} runs; policies: {', '.join(sorted({r.policy for r in sweep.runs}))}")
    return gs[0]


def _check_pair(single: Sweep, multi: Sweep):
    if single.n_agents != 1:
        raise SweepError(f"{single.path} is not a single-agent sweep ({single.n_agents} agents)")
    if multi.n_agents < 2:
        raise SweepError(f"{multi.path} is not a multi-agent sweep ({multi.n_agents} agent)")


def plot_single_vs_multi(single: Sweep, multi: Sweep, ax, policy: str = "ucb", window: int = 50):
    """Curiosity of the single agent against each agent of the multi-agent sweep (fig 23):
    moving averages over `window` points, means over seeds with 95% bands."""
    _check_pair(single, multi)
    gs, gm = _policy_group(single, policy), _policy_group(multi, policy)
    v = single.metrics["curiosity_sample"][gs.indices, :, 0]
    mean, lo, hi, _ = mean_ci(moving_average(v, window, axis=1))
    ax.plot(single.steps, mean, color="black", linewidth=2, label=f"single agent ({gs.seeds_text}, {single.image} px)")
    _band(ax, single.steps, lo, hi, "black")
    for a in range(multi.n_agents):
        v = multi.metrics["curiosity_sample"][gm.indices, :, a]
        mean, lo, hi, _ = mean_ci(moving_average(v, window, axis=1))
        c = AGENT_COLORS[a % len(AGENT_COLORS)]
        ax.plot(multi.steps, mean, color=c, linewidth=2,
                label=f"multi-agent: {multi.agent_label(a)} ({gm.seeds_text}, {multi.image} px)")
        _band(ax, multi.steps, lo, hi, c)
    return _finish(ax, f"Curiosity reward, single- vs multi-agent: {gm.label} (moving average of {window} points, "
                       "95% CI band)", STEPS_LABEL, CURIOSITY_LABEL)


def plot_vae_single_vs_multi(single: Sweep, multi: Sweep, ax, policy: str = "ucb", window: int = 50, raw: bool = True):
    """The VAE's loss in the single- and the multi-agent sweep (fig 24), per image (the
    multi-agent loss of eq. 5 sums both agents' views; it is halved here so the two compare)."""
    _check_pair(single, multi)
    for sw, color, who in ((single, "black", "single agent"), (multi, "tab:purple", "multi-agent")):
        g = _policy_group(sw, policy)
        v = per_agent_vae_loss(sw)[g.indices]
        if raw:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                ax.plot(sw.steps, np.nanmean(v, axis=0), color=color, alpha=0.3, linewidth=0.7)
        mean, lo, hi, _ = mean_ci(moving_average(v, window, axis=1))
        ax.plot(sw.steps, mean, color=color, linewidth=2,
                label=f"{who}: {g.label}, {g.seeds_text}, {sw.image} px")
        _band(ax, sw.steps, lo, hi, color)
    return _finish(ax, f"VAE loss, single- vs multi-agent (thin: every {multi.metrics_every} steps; thick: moving "
                       f"average of {window} points, 95% CI band)", STEPS_LABEL,
                   "VAE loss per image (nats: squared pixel error sum + KL)")


def plot_cumulative_interactions(sweep: Sweep, ax, kind: str = "object", groups=None):
    """Cumulative interactions per policy, as % of the global maximum (fig 21: objects, both
    agents summed; fig 22: agent-agent contacts). Bands: 95% CI across seeds."""
    gs = _group_list(sweep, groups)
    data = cumulative_interactions(sweep, kind, gs)
    top = data.pop("_max")
    colors = _group_colors(gs)
    for i, (label, d) in enumerate(data.items()):
        g = d["group"]
        color = colors[i]
        ax.plot(d["steps"], 100 * d["mean"], color=color, linewidth=2, label=f"{label}, {g.seeds_text}")
        _band(ax, d["steps"], 100 * d["low"], 100 * d["high"], color)
    what = "contact steps, both agents summed" if kind == "object" else "steps with the agents touching"
    title = ("Cumulative agent-object interactions per policy" if kind == "object"
             else "Cumulative agent-agent interactions per policy")
    note = f"100% = {top:,.0f} {what}" if top > 0 else f"no {what} recorded"
    if kind == "agent" and sweep.n_agents == 1:
        note = "single-agent sweep: no other agent to touch"
    ax.set_ylim(-2, 110)  # bands above 110% (few seeds) are cut
    return _finish(ax, f"{title}\n({note})", STEPS_LABEL,
                   "cumulative interactions (% of the global maximum;\nmean over seeds, 95% CI band)", loc="upper left")


def plot_interaction_frequency(sweep: Sweep, ax, group: Any = None, every: int = 100, agent: int | None = None):
    """How often the agent(s) touch each object over time, averaged over bins of `every` steps
    (figs 9, 14), mean over seeds with a 95% band."""
    g = sweep.group(group)
    steps, f = interaction_frequency(sweep, g, every, agent)
    for k, obj in enumerate(sweep.objects):
        mean, lo, hi, _ = mean_ci(f[:, :, k])
        c = TARGET_COLORS.get(obj, f"C{k}")
        ax.plot(steps, mean, color=c, linewidth=1.5, marker="." if len(steps) < 30 else None, label=obj)
        _band(ax, steps, lo, hi, c)
    who = sweep.agent_label(agent) if agent is not None else ("both agents" if sweep.n_agents > 1 else "agent")
    return _finish(ax, f"Agent-object interactions over time, {who}: {g.label}, {g.seeds_text}",
                   STEPS_LABEL, f"share of steps touching the object\n(averaged over {every} steps)")


def plot_action_histogram(sweep: Sweep, ax, group: Any = None):
    """How often each agent chose each action over the whole run (figs 10, 12); bars are means
    over seeds, error bars 95% CIs."""
    g = sweep.group(group)
    tot = action_totals(sweep, g).astype(float)  # [n, agents, actions]
    n_a = sweep.n_agents
    width = 0.8 / n_a
    x = np.arange(len(sweep.actions))
    for a in range(n_a):
        mean, lo, hi, _ = mean_ci(tot[:, a])
        err = np.where(np.isfinite(lo), np.vstack([mean - np.maximum(lo, 0), hi - mean]), 0.0)
        ax.bar(x + (a - (n_a - 1) / 2) * width, mean, width, yerr=err if g.n > 1 else None, capsize=2,
               color=AGENT_COLORS[a % len(AGENT_COLORS)] if n_a > 1 else "tab:blue", label=sweep.agent_label(a))
    ax.set_xticks(x)
    ax.set_xticklabels([s.replace("_", "\n") for s in sweep.actions], fontsize=8)
    return _finish(ax, f"Actions chosen over {sweep.steps_done:,} steps: {g.label}, {g.seeds_text}", "action",
                   "times chosen (agent steps, mean over seeds)", legend=n_a > 1)


def plot_view_fractions(sweep: Sweep, ax, group: Any = None, agent: int = 0, every: int = 100):
    """What an agent looks at over time: the share of its view's pixels showing each object and
    the other agent, stacked, averaged over bins of `every` steps and over seeds (the rest of the
    view is floor, walls and sky)."""
    g = sweep.group(group)
    v = sweep.metrics["view_fraction"][g.indices, :, agent]  # [n, W, targets]
    steps, b = bin_windows(sweep, v, every, reduce="mean")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        m = np.nanmean(b, axis=0)  # [bins, targets]
    targets = list(sweep.view_targets)
    if sweep.n_agents == 1:
        targets, m = targets[:-1], m[:, :-1]
    labels = [t.replace("_", " ") for t in targets]
    ax.stackplot(steps, 100 * np.nan_to_num(m.T), labels=labels,
                 colors=[TARGET_COLORS.get(t, f"C{i}") for i, t in enumerate(targets)], alpha=0.85)
    return _finish(ax, f"What the {sweep.agent_label(agent)} looks at: {g.label}, {g.seeds_text}",
                   STEPS_LABEL, f"share of its view (% of pixels, mean over {every} steps;\nthe rest: floor, walls, sky)",
                   loc="upper left")


def plot_observational(sweep: Sweep, ax, window: int = 50):
    """Curiosity when an agent only watches the other agent act, against when it acts itself
    or nothing happens (per 20-step window, relative to its moving average; bars: mean over
    runs of every group, error bars 95% CI across runs)."""
    d = observation_classes(sweep, window)
    mean, lo, hi, n = mean_ci(d["per_run"])
    x = np.arange(len(OBS_CLASSES))
    err = np.where(np.isfinite(lo), np.vstack([mean - lo, hi - mean]), 0.0)  # excess: may be negative
    colors = ["tab:red", "tab:purple", "tab:gray", "lightgray"]
    ax.bar(x, np.nan_to_num(mean), yerr=err, capsize=3, color=colors)
    ax.axhline(0, color="black", linewidth=0.8)
    ax.set_xticks(x)
    ax.set_xticklabels([f"{c}\n({k:,} windows)" for c, k in zip(_wrap_all(OBS_CLASSES, 22), d["count"])], fontsize=7)
    return _finish(ax, f"Curiosity by what the agent did or saw in each {sweep.metrics_every}-step window\n"
                       f"(all {sweep.n_runs} runs, both agents; relative to the agent's moving average of {window} windows)",
                   "in the window, the agent ...", "curiosity above its moving average\n(squared latent distance)",
                   legend=False)


def plot_losses(sweep: Sweep, axes, groups=None, window: int = 50):
    """The world model's training losses per group (moving average, 95% band): the VAE loss per
    image, the MDN-RNN negative log-likelihood, the self-models' loss per agent. `axes`: 3 Axes."""
    gs = _group_list(sweep, groups)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        self_loss = np.nanmean(sweep.metrics["self_loss_agents"], axis=2)
    series = (  # (y label, what, values, lowest possible value for the bands)
        ("VAE loss per image (nats)", "VAE (eq. 5, per image)", per_agent_vae_loss(sweep), 0.0),
        ("MDN-RNN NLL per transition (nats)", "MDN-RNN (eq. 6)", sweep.metrics["nll"], None),
        ("self-model loss per agent\n(squared curiosity error)", "self-models (eq. 4)", self_loss, 0.0),
    )
    colors = _group_colors(gs)
    for ax, (ylabel, what, v, floor) in zip(axes, series):
        for i, g in enumerate(gs):
            mean, lo, hi, _ = mean_ci(moving_average(v[g.indices], window, axis=1))
            color = colors[i]
            ax.plot(sweep.steps, mean, color=color, linewidth=1.5, label=f"{g.label}, {g.seeds_text}")
            _band(ax, sweep.steps, lo, hi, color, floor=floor)
        _finish(ax, f"{what} loss (moving average of {window} windows)", STEPS_LABEL, ylabel)
    return axes


def plot_reconstructions(sweep: Sweep, fig, run: int | str = 0, steps: Sequence[int] | None = None, n_frames: int = 8,
                         rec: Reconstructions | None = None):
    """Real views (top row) and run `run`'s VAE reconstructions of them after an early and a
    late checkpoint (one row per checkpoint), figs 7 and 13."""
    rec = rec or reconstructions(sweep, run, steps, n_frames)
    rows = 1 + len(rec.steps)
    n = len(rec.frames)
    axes = fig.subplots(rows, n, squeeze=False)
    for j in range(n):
        s, i, a = rec.sources[j]
        who = "" if sweep.n_agents == 1 else f", {sweep.agent_names[a]}"
        axes[0, j].imshow(rec.frames[j], interpolation="nearest")
        axes[0, j].set_title(f"run {i}{who}\nstep {s:,}", fontsize=7)
        for k, st in enumerate(rec.steps):
            axes[k + 1, j].imshow(rec.decoded[st][j], interpolation="nearest")
    for row in axes:
        for ax in row:
            ax.set_xticks([])
            ax.set_yticks([])
    axes[0, 0].set_ylabel("real view", fontsize=8)
    for k, st in enumerate(rec.steps):
        axes[k + 1, 0].set_ylabel(f"VAE after\n{st:,} steps", fontsize=8)
    fig.suptitle(f"VAE reconstructions, {rec.run.name}: the agents' real {sweep.image}x{sweep.image} views (top; each "
                 f"from the checkpoint named) encoded and decoded\nby this run's VAE restored from checkpoints at "
                 f"{' and '.join(f'{s:,}' for s in rec.steps)} agent steps", fontsize=9)
    return fig


# ---------------------------------------------------------------------------------- headline table


@dataclasses.dataclass
class Table:
    """Rows of formatted cells (`rows`) and the numbers behind them (`values`: one dict per row)."""

    columns: list[str]
    rows: list[list[str]]
    values: list[dict]
    note: str = ""

    def to_markdown(self) -> str:
        out = ["| " + " | ".join(self.columns) + " |", "|" + "---|" * len(self.columns)]
        out += ["| " + " | ".join(r) + " |" for r in self.rows]
        return "\n".join(out) + (f"\n\n{self.note}\n" if self.note else "\n")

    def to_csv(self) -> str:
        buf = io.StringIO()
        keys = list(self.values[0]) if self.values else []
        w = csv.DictWriter(buf, fieldnames=keys)
        w.writeheader()
        w.writerows(self.values)
        return buf.getvalue()

    def _repr_markdown_(self) -> str:
        return self.to_markdown()

    def __str__(self) -> str:
        return self.to_markdown()


def headline_table(sweep: Sweep, final_fraction: float = 0.1) -> Table:
    """Per group, mean +- sd across seeds of: the final curiosity (mean over agents and the last
    `final_fraction` of the windows), total agent-object contact steps, steps with the agents
    touching, the final VAE loss per image and MDN-RNN NLL (same last windows), the share of
    'stop' actions, and the number of runs halted by a non-finite loss."""
    k = max(1, int(math.ceil(final_fraction * sweep.n_windows)))
    last = slice(sweep.n_windows - k, sweep.n_windows)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        final_cur = np.nanmean(sweep.metrics["curiosity"][:, last], axis=(1, 2))
        final_vae = np.nanmean(per_agent_vae_loss(sweep)[:, last], axis=1)
        final_nll = np.nanmean(sweep.metrics["nll"][:, last], axis=1)
    obj = object_contacts(sweep).sum(axis=1)
    agt = agent_contacts(sweep).sum(axis=1)
    acts = sweep.metrics["action_counts"].sum(axis=(1, 2))  # [runs, actions]
    stop = acts[:, sweep.actions.index("stop")] / np.maximum(acts.sum(axis=1), 1) if "stop" in sweep.actions else np.full(sweep.n_runs, np.nan)
    halted = np.zeros(sweep.n_runs, bool)
    for r in sweep.progress.get("halted", {}):
        halted[int(r)] = True
    span = f"last {k * sweep.metrics_every:,} steps"
    cols = ["group", "runs", f"curiosity ({span})", "agent-object contact steps", "agent-agent contact steps",
            f"VAE loss per image ({span})", f"MDN-RNN NLL ({span})", "'stop' share of actions", "halted runs"]
    rows, values = [], []
    for g in sweep.groups():
        ix = g.indices
        stats = {}
        for key, v in (("curiosity", final_cur), ("object_contacts", obj), ("agent_contacts", agt),
                       ("vae_loss", final_vae), ("nll", final_nll), ("stop_share", stop)):
            mean, sd, _ = mean_sd(v[ix])
            stats[key] = (float(mean), float(sd))
        fmt = lambda ms, d=3: _pm(*ms, d)  # noqa: E731
        rows.append([g.label, str(g.n), fmt(stats["curiosity"]), fmt(stats["object_contacts"], 0),
                     fmt(stats["agent_contacts"], 0) if sweep.n_agents > 1 else "n/a", fmt(stats["vae_loss"], 1),
                     fmt(stats["nll"], 2), fmt(stats["stop_share"], 3), str(int(halted[ix].sum()))])
        row = {"group": g.label, "policy": g.policy, g.setting: g.value, "runs": g.n}
        for key, (m, s) in stats.items():
            row[f"{key}_mean"], row[f"{key}_sd"] = m, s
        row["halted"] = int(halted[ix].sum())
        values.append(row)
    keys = list(dict.fromkeys(k for v in values for k in v))  # every row's columns, in order
    values = [{k: v.get(k, "") for k in keys} for v in values]
    note = (f"{sweep.path.name}: {sweep.n_agents} agent(s), {sweep.steps_done:,} steps, image {sweep.image} px. "
            "Each cell: mean ± sd across seeds (sd omitted with one seed). Contact steps: agent steps in contact, "
            "summed over agents and objects for agent-object; steps with the two agents touching for agent-agent.")
    return Table(cols, rows, values, note)


def _pm(mean: float, sd: float, digits: int) -> str:
    if not np.isfinite(mean):
        return "n/a"
    if not np.isfinite(sd):
        return f"{mean:,.{digits}f}"
    return f"{mean:,.{digits}f} ± {sd:,.{digits}f}"


# ---------------------------------------------------------------------------------- saving


def figures_dir(path: str | pathlib.Path, create: bool = True) -> pathlib.Path:
    """Where figures of the sweep (or directory of sweeps) at `path` go: `<path>/figures`, a
    name no sweep writes."""
    d = pathlib.Path(path).expanduser() / FIGURES_DIRNAME
    if create:
        d.mkdir(parents=True, exist_ok=True)
    return d


def empty_axes(fig) -> list[str]:
    """Titles of the visible axes of `fig` that show nothing: no line with a finite point, no
    bar, band, area or image."""
    empty = []
    for ax in fig.axes:
        if not ax.get_visible():
            continue
        lines = any(np.isfinite(np.asarray(ln.get_ydata(), float)).any() for ln in ax.lines)
        if not (lines or ax.collections or ax.patches or ax.images):
            empty.append(ax.get_title() or f"axes {fig.axes.index(ax)}")
    return empty


def save_figure(fig, directory: str | pathlib.Path, name: str, dpi: int = 110, check: bool = True) -> pathlib.Path:
    """Save `fig` as `<directory>/<name>.png` (name made file-safe). With `check`, raise
    SweepError if an axes shows nothing. Refuses to write inside a sweep's own outputs
    (metrics/, checkpoints/, manifest.json, progress.json)."""
    directory = pathlib.Path(directory)
    if check and empty_axes(fig):
        raise SweepError(f"figure {name!r} has empty axes: {'; '.join(empty_axes(fig))}")
    _check_not_sweep_output(directory)
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / f"{slug(name)}.png"
    fig.savefig(path, dpi=dpi, bbox_inches="tight")
    return path


def save_text(text: str, directory: str | pathlib.Path, name: str) -> pathlib.Path:
    directory = pathlib.Path(directory)
    _check_not_sweep_output(directory)
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / name
    path.write_text(text)
    return path


def _check_not_sweep_output(directory: pathlib.Path) -> None:
    d = directory.resolve()
    for parent in (d, *d.parents):
        if (parent / "manifest.json").is_file() and parent != d:
            rel = d.relative_to(parent).parts
            if rel and rel[0] in SWEEP_OUTPUTS:
                raise SweepError(f"refusing to write into {directory}: it is part of the sweep {parent}'s own output")
    if (d / "manifest.json").is_file():
        raise SweepError(f"refusing to write figures into the sweep directory {directory} itself; "
                         f"use {directory / FIGURES_DIRNAME}")


def slug(text: str) -> str:
    text = text.replace("ε", "eps").replace("±", "pm")
    return re.sub(r"[^A-Za-z0-9._-]+", "-", text).strip("-").lower() or "figure"


# ---------------------------------------------------------------------------------- helpers


@contextlib.contextmanager
def _quiet_orbax():
    """Orbax's read-only managers log warnings that say nothing useful here; hide them."""
    log = logging.getLogger("absl")
    old = log.level
    log.setLevel(logging.ERROR)
    try:
        yield
    finally:
        log.setLevel(old)


def _to_numpy(tree):
    if isinstance(tree, dict):
        return {k: _to_numpy(v) for k, v in tree.items()}
    if isinstance(tree, (list, tuple)):
        return type(tree)(_to_numpy(v) for v in tree)
    return np.asarray(tree)


def _index_tree(tree, i: int):
    if isinstance(tree, dict):
        return {k: _index_tree(v, i) for k, v in tree.items()}
    return np.asarray(tree)[i]


def _wrap(text: str, width: int) -> str:
    words, lines, cur = text.split(), [], ""
    for w in words:
        if cur and len(cur) + 1 + len(w) > width:
            lines.append(cur)
            cur = w
        else:
            cur = f"{cur} {w}".strip()
    return "\n".join(lines + [cur])


def _wrap_all(texts: Iterable[str], width: int) -> list[str]:
    return [_wrap(t, width) for t in texts]
