"""Loading: read a sweep directory into NumPy arrays.

    from mjx_curio.analysis import sweeps   # or `from mjx_curio import analysis` (re-exports all)
    sweep = sweeps.load("runs/paper")       # manifest, metrics, checkpoints
    sweep.runs, sweep.steps, sweep.metrics["curiosity"]   # [runs], [windows], [runs, windows, agents]
    ucb = sweep.select(policy="ucb")        # run indices

A sweep (written by `python -m mjx_curio.sweep`, see sweep.py and metrics.py) holds metrics per
window of `metrics_every` (20) agent steps; `Sweep.metrics` holds the windows that are final
(`progress.json`), so a sweep still running can be read too. Runs that share a policy and its
setting (eps, temperature or c) but differ in seed form a `Group`; every figure pools a group's
seeds into a mean and a 95% confidence band of that mean (Student t, across seeds).

Here: `Sweep`, `Run`, `Group`, `SweepError`, `load`, `find_sweeps`, `load_sweeps`,
`merge_sweeps` (one experiment's seeds run as several sweeps, read as one), `pick_single_multi`,
and the configs a sweep ran with rebuilt from its manifest (`learner_config`, `run_config`,
`run_specs`). Needs only NumPy (and orbax for checkpoints); imports no other module of the
analysis package (only `plan` and `config`, for what a sweep ran with).
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import logging
import os
import pathlib
import re
from typing import Any, Sequence

import numpy as np

from mjx_curio.plan import RunSpec

FORMAT = "mjx_curio.sweep/1"
SWEEP_OUTPUTS = ("manifest.json", "progress.json", "metrics", "checkpoints")  # what a sweep writes

POLICY_LABELS = {"eps": "ε-greedy", "boltzmann": "Boltzmann", "ucb": "UCB"}
SETTINGS = {"eps": ("eps", "ε"), "boltzmann": ("temperature", "T"), "ucb": ("ucb_c", "c")}
TABLE_COLUMNS = ("index", "name", "policy", "seed", "eps", "temperature", "ucb_c")


class SweepError(ValueError):
    """A directory is not a readable sweep, or lacks what was asked for. The message says what
    is missing and where."""


# ---------------------------------------------------------------------------------- loading


@dataclasses.dataclass(frozen=True)
class Run(RunSpec):
    """One row of a sweep's runs table (manifest `runs`, in the order of the metrics' first axis):
    the plan's RunSpec (policy, seed, settings, and its `name`) and its index."""

    index: int

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
      path, name: the directory and its name (a merged sweep's: its first part's directory, and
        `seeds_name` of the seeds it holds, `multi_agent.seeds-0-7`; parts of a grid merged with
        `differ`: their names joined by " + ").
      manifest, progress: the parsed manifest.json and progress.json.
      runs: list of `Run`, in the order of the metrics' first axis.
      n_agents, agent_names, actions, objects, view_targets: from the manifest.
      metrics_every: agent steps per metrics window.
      steps: int array [windows]: the agent step at the end of each final window.
      metrics: name -> array [runs, windows, ...] (see `metrics.SCHEMA` / manifest
        `metrics.schema` for units and meanings), the final windows only.
      parts: the sweeps it was merged from (`merge_sweeps`; of a merge of merged sweeps, theirs:
        the sweeps read from disk), else empty.
    """

    def __init__(self, path: pathlib.Path, manifest: dict, progress: dict, steps: np.ndarray, metrics: dict):
        self.path = pathlib.Path(path)
        self.name = pathlib.Path(os.path.abspath(self.path)).name
        self.manifest = manifest
        self.progress = progress
        self.runs = [Run(**{k: r[k] for k in ("index", "policy", "seed", "eps", "temperature", "ucb_c")})
                     for r in manifest["runs"]]
        self.n_agents = int(manifest["n_agents"])
        self.agent_names = list(manifest["agent_names"])
        self.actions = list(manifest["actions"])
        self.objects = list(manifest["objects"])
        self.view_targets = list(manifest["view_targets"])
        self.metrics_every = int(manifest["metrics"]["every"])
        self.steps = steps
        self.metrics = metrics
        self.parts: tuple[Sweep, ...] = ()
        self._ckpts = None
        self._raw_cache: dict[int, dict] = {}
        self._replay_cache: dict[tuple, dict] = {}

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
        cols = {k: [getattr(r, k) for r in self.runs] for k in TABLE_COLUMNS}
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

        def checkpoints(s: Sweep) -> str:
            try:
                return ", ".join(map(str, s.checkpoint_steps())) or "none"
            except SweepError:
                return "none"

        halted = self.progress.get("halted", {})
        where = f"{self.name}, merged from {len(self.parts)} sweeps" if self.parts else str(self.path)
        lines = [
            f"{where}: {self.n_runs} runs, {self.n_agents} agent{'s' if self.n_agents > 1 else ''}, "
            f"walls={cfg.get('walls')}, image {self.image} px",
            f"  steps done {self.steps_done:,} of {int(cfg['steps']):,} ({self.n_windows} windows of {self.metrics_every})",
            f"  groups: {'; '.join(f'{g.label} x {g.n}' for g in self.groups())}",
        ]
        if self.parts:  # the windows every part has finished; each keeps its own checkpoints
            lines += [f"  part {p.path}: seeds {', '.join(map(str, sorted({r.seed for r in p.runs})))}, "
                      f"steps done {p.steps_done:,}, checkpoints at steps: {checkpoints(p)}" for p in self.parts]
        else:
            lines.append(f"  checkpoints at steps: {checkpoints(self)}")
        if halted:
            lines.append("  halted runs (non-finite loss or physics): " + ", ".join(f"{self.runs[int(r)].name} at {s}" for r, s in halted.items()))
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

    @property
    def has_checkpoints(self) -> bool:
        """Whether `checkpoints` has any to read: a sweep's own (a merged sweep's are its parts'),
        where they were written and kept (a snapshot of the metrics, as the results page commits,
        has none)."""
        return not self.parts and (self.checkpoints_dir / "state").is_dir()

    def checkpoints(self):
        """The sweep's `checkpoint.Checkpoints`, read-only (SweepError if there are none)."""
        if self.parts:
            raise SweepError(f"{self.name} is {len(self.parts)} sweeps merged ("
                             f"{', '.join(str(s.path) for s in self.parts)}); each keeps its own checkpoints: "
                             "read them from `sweep.parts`")
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
            self._raw_cache[step] = raw
        return self._raw_cache[step]

    def restore_replay(self, step: int, keys: Sequence[str] = ("latents", "carry", "actions", "size")) -> dict:
        """The replay buffers of checkpoint `step` (only the newest checkpoint keeps them), entries
        `keys` of `replay.Replay` as NumPy arrays with a leading runs axis (possibly with
        `padded_runs` extra copies at the end); the frames are left on disk unless asked for. The
        last one read is cached."""
        steps = self.replay_steps()
        if int(step) not in steps:
            raise SweepError(f"{self.path} has no replay buffers at step {step}: only the newest checkpoint keeps them; "
                             f"they exist at steps {', '.join(map(str, steps)) or 'none'}")
        key = (int(step), tuple(keys))
        if key not in self._replay_cache:  # one kept: a paper-size replay is large
            with _quiet_orbax():
                self._replay_cache = {key: self.checkpoints().restore_raw(int(step), "replay", keys)}
        return self._replay_cache[key]

    def params(self, step: int, run: int | str) -> dict:
        """Run `run`'s network parameters at checkpoint `step`: {"vae", "rnn", "self_model"}, each
        a flax parameter tree of NumPy arrays (self_model leaves have a leading agents axis), and
        "vae_stats", the VAE's batch-normalisation running averages (world_model.encode's
        `stats`; {} for layers without batch normalisation)."""
        r = self.run(run).index
        learner = self.restore_raw(step)["learner"]
        return {k: _index_tree(learner.get(k, {}), r) for k in ("vae", "rnn", "self_model", "vae_stats")}


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
    try:
        progress = json.loads(ppath.read_text()) if ppath.is_file() else {}
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        raise SweepError(f"{ppath} is not valid JSON ({err})") from None
    if not isinstance(progress, dict):
        raise SweepError(f"{ppath} holds a JSON {type(progress).__name__}, not the sweep's progress object")
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
    diverged = drop_diverged(metrics, steps)
    if diverged:
        progress = {**progress, "halted": {**progress.get("halted", {}), **diverged}}
    return Sweep(path, manifest, progress, steps, metrics)


def drop_diverged(metrics: dict[str, np.ndarray], steps: np.ndarray) -> dict[str, int]:
    """Blank, in place, every window of a run from the first one whose physics state is not
    finite (a NaN agent pose or object position in a window that took steps) to the end, as a
    halted run's windows are (NaN, or 0 for counts); returns {run index: first such window's
    step}. Sweeps written before a diverged simulation halted its run kept stepping the NaN
    state, and its views, curiosity and losses from then on are not data."""
    if "agent_pose" not in metrics or "object_pos" not in metrics or "steps_taken" not in metrics:
        return {}
    n, w = metrics["steps_taken"].shape
    state = np.concatenate([metrics["agent_pose"].reshape(n, w, -1), metrics["object_pos"].reshape(n, w, -1)], axis=2)
    bad = ~np.isfinite(state).all(axis=2) & (metrics["steps_taken"] > 0)
    found = {}
    for r in np.flatnonzero(bad.any(axis=1)):
        first = int(np.argmax(bad[r]))
        for x in metrics.values():
            x[r, first:] = np.nan if np.issubdtype(x.dtype, np.floating) else 0
        found[str(r)] = int(steps[first])
    return found


def merge_sweeps(parts: Sequence[Sweep], differ: Sequence[str] = ()) -> Sweep:
    """One `Sweep` of the runs of `parts`: sweeps of one experiment that ran different seeds, e.g.
    a preset's first 3 seeds and, later, `first_seed=3 seeds=5` more in another directory. They
    must agree in every key the results depend on but `seeds` and `first_seed`
    (`plan.result_values`) and may not repeat a run (policy, setting, seed). The runs stand part
    after part, the parts in order of their first seed (as given where it ties); the windows are
    those every part has finished; `halted` runs keep their mark; the metrics those every part
    records (a part made before a metric was added lacks it). The merged sweep holds metrics
    only: each part keeps its own checkpoints (`Sweep.parts`), and is named by the seeds it holds
    (`multi_agent.seeds-0-7`). SweepError, naming what differs, where they do not fit.

    `differ`: more keys the parts may differ in, for parts that each ran a piece of one grid, e.g.
    `("temperature", "preset")` for the paper's Boltzmann temperatures and the low ones, read as
    one sweep over all of them; the merged manifest records each such key's values from every
    part (a list's values pooled and sorted)."""
    from mjx_curio.plan import result_values

    parts = sorted(parts, key=lambda s: min((r.seed for r in s.runs), default=0))  # ties: in the order given
    if not parts:
        raise SweepError("merge_sweeps: no sweeps given")
    if len(parts) == 1:
        return parts[0]
    first = parts[0]
    free = {"seeds", "first_seed", *differ}
    want = {k: v for k, v in result_values(first.manifest).items() if k not in free}
    seen: dict[tuple, pathlib.Path] = {}
    for s in parts:
        got = {k: v for k, v in result_values(s.manifest).items() if k not in free}
        diff = sorted(k for k in want.keys() | got.keys() if want.get(k) != got.get(k))
        if diff:
            raise SweepError(f"{s.path} and {first.path} are not seeds of one experiment: they differ in "
                             + "; ".join(f"{k} ({got.get(k)!r} against {want.get(k)!r})" for k in diff))
        mine, firsts = _arrays(s), _arrays(first)
        if any(mine[k] != firsts[k] for k in mine.keys() & firsts.keys()) or s.metrics_every != first.metrics_every:
            raise SweepError(f"{s.path} and {first.path} record different metrics")
        for r in s.runs:
            key = (r.policy, r.setting, r.seed)
            if key in seen:
                raise SweepError(f"{s.path} and {seen[key]} both ran {r.group_label} with seed {r.seed}")
            seen[key] = s.path
    windows = min(s.n_windows for s in parts)
    steps = first.steps[:windows]
    for s in parts:
        if not np.array_equal(s.steps[:windows], steps):
            raise SweepError(f"{s.path} and {first.path} end their metrics windows at different steps")
    rows, halted, offset = [], {}, 0
    for s in parts:
        rows += [{**r, "index": offset + i} for i, r in enumerate(s.manifest["runs"])]
        halted.update({str(offset + int(r)): step for r, step in s.progress.get("halted", {}).items()})
        offset += s.n_runs
    config = {**first.manifest["config"], "seeds": len({r.seed for s in parts for r in s.runs}),
              "first_seed": min(r.seed for s in parts for r in s.runs)}
    for k in differ:
        values = [s.manifest["config"].get(k) for s in parts]
        if all(isinstance(v, list) for v in values):
            config[k] = sorted({x for v in values for x in v})
        else:
            config[k] = list(dict.fromkeys(values))
    common = [k for k in first.metrics if all(k in s.metrics for s in parts)]
    recorded = {**first.manifest["metrics"], "windows": windows}
    if "schema" in recorded:
        recorded["schema"] = {k: v for k, v in recorded["schema"].items() if all(k in _arrays(s) for s in parts)}
    # A merge of merged sweeps (seed parts joined, then policies) keeps the sweeps read from disk.
    leaves = tuple(leaf for s in parts for leaf in (s.parts or (s,)))
    manifest = {**first.manifest, "runs": rows, "metrics": recorded,
                "config": config,
                "parts": [{"path": str(s.path), "command": s.manifest.get("command"), "git": s.manifest.get("git")}
                          for s in leaves]}
    progress = {"windows_done": windows, "steps_done": int(steps[-1]) if windows else 0, "halted": halted}
    metrics = {k: np.concatenate([s.metrics[k][:, :windows] for s in parts]) for k in common}
    merged = Sweep(first.path, manifest, progress, steps, metrics)
    # Seeds of one experiment read as one sweep named by its seeds; pieces of a grid by their parts.
    merged.name = (" + ".join(s.name for s in parts) if differ
                   else seeds_name(parts[0].name, [r.seed for r in merged.runs]))
    merged.parts = leaves
    return merged


def experiment_name(name: str) -> str:
    """A sweep's name less the `.seeds-...` suffix of a seed part: `multi_agent.order` for
    `multi_agent.order.seeds-3-5`; any other name as it is."""
    return _SEEDS_SUFFIX.sub("", name)


def seeds_name(name: str, seeds: Sequence[int]) -> str:
    """`name` (less a `.seeds-...` suffix it has) with the seeds held: `multi_agent.seeds-0-7`;
    seeds with gaps name each run of consecutive ones, `multi_agent.seeds-0-2+5-7`, a lone seed
    by itself, `multi_agent.seeds-0-2+4`."""
    seeds = sorted(set(int(x) for x in seeds))
    spans: list[list[int]] = []
    for x in seeds:
        if spans and x == spans[-1][1] + 1:
            spans[-1][1] = x
        else:
            spans.append([x, x])
    return f"{experiment_name(name)}.seeds-" + "+".join(f"{a}-{b}" if b > a else f"{a}" for a, b in spans)


_SEEDS_SUFFIX = re.compile(r"[.]seeds-[0-9+-]+$")


def side_experiment(name: str) -> str | None:
    """`<preset>.<label>` where `name` is that, or one of its seed parts (`.seeds-3-5` after it),
    with <preset> a preset of presets.toml and <label> not a seed range: another experiment with
    that preset's settings (e.g. `multi_agent.order`), kept apart from the preset's own sweeps
    (`join_seed_parts`, `analysis.assign_presets`). None for any other name."""
    from mjx_curio.presets import load_presets

    base = experiment_name(name)
    preset, dot, label = base.partition(".")
    return base if dot and label and preset in load_presets() else None


def _arrays(s: Sweep) -> dict:
    """What the metrics arrays are (dtype, dims, unit), without their `meaning`, whose wording
    may have grown between the sweeps of one experiment."""
    schema = s.manifest["metrics"].get("schema") or {}
    return {k: {f: v.get(f) for f in ("dtype", "dims", "unit")} for k, v in schema.items()}


def join_seed_parts(sweeps: Sequence[Sweep]) -> list[Sweep]:
    """`sweeps` with the parts of one experiment joined: sweeps whose results depend on the same
    settings but for `seeds` and `first_seed` (a preset's first seeds, then `first_seed=3 seeds=5`
    more in a directory of their own) become one `merge_sweeps` Sweep, named after its first part
    with the seeds it holds (`multi_agent.seeds-0-7`), where the first of them stood in `sweeps`.
    A sweep that repeats a run (policy, setting, seed) of parts with lower first seeds stays
    apart: it is a rerun, not more seeds; so does a side experiment (`side_experiment`), which
    joins only its own seed parts. A part made after a metric was added records it and the
    earlier parts do not: it still joins them (the merge keeps the metrics all parts record), as
    what a sweep records does not change its runs; a metric recorded as another array (dtype,
    dims or unit) in two parts keeps them apart. A merged sweep reads its checkpoints from its
    `parts`."""
    from mjx_curio.plan import result_values

    def settings(s: Sweep) -> str:
        values = {k: v for k, v in result_values(s.manifest).items() if k not in ("seeds", "first_seed")}
        return json.dumps([values, s.metrics_every, side_experiment(s.name)], sort_keys=True, default=str)

    def runs(s: Sweep) -> set:
        return {(r.policy, r.setting, r.seed) for r in s.runs}

    def same_arrays(s: Sweep, parts: list[int]) -> bool:
        mine = _arrays(s)
        return all(mine[k] == theirs[k]
                   for j in parts for theirs in [_arrays(sweeps[j])] for k in mine.keys() & theirs.keys())

    # Parts join in order of their first seed (the fuller first where they tie), so that which of
    # two sweeps with a run in common stays apart does not depend on the order given.
    order = sorted(range(len(sweeps)), key=lambda i: (min((r.seed for r in sweeps[i].runs), default=0),
                                                      -sweeps[i].n_runs, i))
    experiments: list[tuple[str, list[int]]] = []
    for i in order:
        key = settings(sweeps[i])
        home = next((parts for k, parts in experiments
                     if k == key and same_arrays(sweeps[i], parts)
                     and not runs(sweeps[i]) & set().union(*(runs(sweeps[j]) for j in parts))), None)
        if home is None:
            experiments.append((key, [i]))
        else:
            home.append(i)
    joined = []
    for parts in sorted((parts for _, parts in experiments), key=min):
        joined.append(merge_sweeps([sweeps[i] for i in parts]))
    return joined


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


def _index_tree(tree, i: int):
    if isinstance(tree, dict):
        return {k: _index_tree(v, i) for k, v in tree.items()}
    return np.asarray(tree)[i]
