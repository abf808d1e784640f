"""A sweep's plan: the command line's values checked, the grid of runs, and what `out` holds.

Nothing here imports JAX or writes a file: a bad key, a bad value or an `out` that cannot be
used stops the sweep before any work starts.

The grid: every policy in `policies` x every seed, and for each policy every value of its own
setting (eps for eps, temperature for boltzmann, ucb_c for ucb), so
`policies=boltzmann temperature=0.5,1,1.5,2,2.5 seeds=8` is the paper's temperature sweep on 8
seeds.
"""

from __future__ import annotations

import dataclasses
import datetime
import itertools
import json
import os
import pathlib

from mjx_curio import cli
from mjx_curio import config as config_lib
from mjx_curio import dirlock
from mjx_curio import presets as presets_lib
from mjx_curio.config import POLICY_SETTING, SWEEP_CLASSES, ConfigError, RunConfig, SweepConfig

KEYS = cli.keys_of(*SWEEP_CLASSES)
RESUME_FREE = frozenset(k.name for k in KEYS if k.resume_free)


@dataclasses.dataclass(frozen=True)
class RunSpec:
    policy: str
    seed: int
    eps: float
    temperature: float
    ucb_c: float

    @property
    def name(self) -> str:
        setting = POLICY_SETTING[self.policy]
        return f"{self.policy}-{setting}{getattr(self, setting):g}-seed{self.seed}"


@dataclasses.dataclass(frozen=True)
class Plan:
    values: dict  # every key's value, as typed (lists as tuples)
    sweep: SweepConfig
    run: RunConfig  # runs_loop still "map" for "auto": execute resolves it by device
    runs: tuple
    out: pathlib.Path
    resume: bool  # continue an existing sweep directory

    @property
    def learner(self):
        return self.run.learner


def grid(values: dict) -> tuple:
    for policy, setting in POLICY_SETTING.items():
        if policy not in values["policies"] and len(values[setting]) > 1:
            given = ",".join(f"{x:g}" for x in values[setting])
            raise ConfigError(f"{setting}={given} lists several values, but policies={','.join(values['policies'])} "
                              f"runs no {policy} agents, so none would be used; add {policy} to policies, or give "
                              f"{setting} one value")
    runs = []
    for policy in values["policies"]:
        settings = values[POLICY_SETTING[policy]]
        for setting, seed in itertools.product(settings, range(values["first_seed"], values["first_seed"] + values["seeds"])):
            kw = {"eps": values["eps"][0], "temperature": values["temperature"][0], "ucb_c": values["ucb_c"][0]}
            kw[POLICY_SETTING[policy]] = setting
            runs.append(RunSpec(policy, seed, **kw))
    if len(set(runs)) != len(runs):
        raise ConfigError("the grid holds the same run twice: a list key repeats a value (policies, eps, temperature or ucb_c)")
    return tuple(runs)


def plan(values: dict, now: datetime.datetime | None = None) -> Plan:
    """Every check of the command line and of `out`, without side effects."""
    from mjx_curio import distributed

    v = {k.name: v for k, v in zip(KEYS, (values.get(k.name, k.default) for k in KEYS))}
    if v["distributed"] != "false":
        distributed.process_env()
    sweep, run = config_lib.sweep_configs(v)
    runs = grid(v)

    if sweep.out:
        out = pathlib.Path(os.path.expanduser(sweep.out))
    else:
        now = now or datetime.datetime.now()
        out = pathlib.Path("runs") / now.strftime("%Y%m%d-%H%M%S")
        while out.exists():
            out = out.with_name(out.name + "x")
    check_creatable(out)
    distributed.compile_cache_dir(v["compile_cache"])
    if distributed.rank_from_env() == 0:  # on a cluster, process 0 holds the lock
        dirlock.check_free(out)
    manifest = out / "manifest.json"
    if sweep.resume:
        if not manifest.is_file():
            raise ConfigError(f"resume=true but out={out} holds no sweep (no manifest.json)")
        saved = saved_values(read_manifest(out))
        diff = [k.name for k in KEYS if k.name not in RESUME_FREE and _norm(saved[k.name]) != _norm(v[k.name])]
        if diff:
            detail = "; ".join(f"{k}: saved {_show(saved[k])}, given {_show(v[k])}" for k in diff)
            raise ConfigError(f"resume=true: out={out} was made with other settings ({detail}); "
                              "resume with the same values, or start a new sweep in another out")
        done = read_progress(out).get("steps_done", 0)
        if sweep.steps < done:
            raise ConfigError(f"steps={sweep.steps} is less than the {done} steps out={out} has already done; "
                              f"allowed: steps >= {done}")
        return Plan(v, sweep, run, runs, out, True)
    if manifest.exists():
        raise ConfigError(f"out={out} already holds a sweep; pass resume=true to continue it, or choose another out")
    if out.exists() and (not out.is_dir() or any(p.name != dirlock.LOCK_NAME for p in out.iterdir())):
        raise ConfigError(f"out={out} exists and is not an empty directory; choose another out")
    return Plan(v, sweep, run, runs, out, False)


def check_creatable(path: pathlib.Path, key: str = "out") -> None:
    """`path`, the directory `key` names, exists or can be made: its nearest existing ancestor
    is a writable directory. Checked by asking, not by making anything."""
    probe = path.absolute()
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    if probe != path.absolute() and (not probe.is_dir() or not os.access(probe, os.W_OK | os.X_OK)
                                     or _pseudo_fs(probe)):
        why = "is not a directory" if not probe.is_dir() else "is not writable"
        raise ConfigError(f"{key}={path} cannot be created: {probe} {why}; choose a directory you can write")


def _pseudo_fs(path: pathlib.Path) -> bool:
    """True on a kernel filesystem (/proc, /sys) where nobody, root included, can make a directory."""
    try:
        mounts = [line.split()[1:3] for line in open("/proc/self/mounts")]
    except OSError:
        return False
    best = max((m for m in mounts if str(path) == m[0] or str(path).startswith(m[0].rstrip("/") + "/")),
               key=lambda m: len(m[0]), default=None)
    return best is not None and best[1] in ("proc", "sysfs", "devtmpfs", "cgroup", "cgroup2", "debugfs", "securityfs")


def saved_values(manifest: dict) -> dict:
    """Every key's value as the sweep of `manifest` ran with it. A key newer than the sweep is
    read from the manifest's run config where that records it, else as the behaviour the code
    had before the key existed (the knob's `legacy` value), else as its default."""
    config, run = manifest.get("config", {}), manifest.get("run_config", {})
    learner = run.get("learner", {})
    out = {}
    for cls, recorded in ((config_lib.SweepConfig, {}), (config_lib.RunConfig, run), (config_lib.LearnerConfig, learner)):
        for f in config_lib.knobs(cls):
            if not f.metadata["cli"]:
                continue
            key = config_lib.key_name(f)
            if key in config:
                value = config[key]
            elif f.name in recorded:
                value = recorded[f.name]
            else:
                value = f.metadata.get("legacy", f.default)
            out[key] = tuple(value) if isinstance(value, list) else value
    return out


def result_values(manifest: dict) -> dict:
    """The keys a sweep's results depend on, as the sweep of `manifest` ran them: every key but
    those a resume may change (bookkeeping, not results). Two sweeps with equal `result_values`
    but for `seeds` and `first_seed` ran one experiment with different seeds."""
    return {k: _norm(v) for k, v in saved_values(manifest).items() if k not in RESUME_FREE}


def config_of(values: dict) -> dict:
    return {k: list(x) if isinstance(x, tuple) else x for k, x in values.items()}


def resume_command(p: Plan) -> str:
    """The command that continues this sweep: its preset, if it had one (resume checks it), every
    key the preset sets (so that its value, not the preset's, is what resumes) and every key that
    differs from its default."""
    preset = p.values.get("preset", "none")
    pinned = set(presets_lib.load_presets().get(preset, {})) if preset != "none" else set()
    items = [f"preset={preset}"] if preset != "none" else []
    items += [f"{k.name}={k.kind.show(p.values[k.name])}" for k in KEYS
              if k.name not in ("out", "resume", "preset")
              and (k.name in pinned or _norm(p.values[k.name]) != _norm(k.default))]
    return " ".join(["python -m mjx_curio.sweep", *items, f"out={p.out}", "resume=true"])


def _norm(x):
    return list(x) if isinstance(x, (tuple, list)) else x


def _show(x) -> str:
    return ",".join(map(str, x)) if isinstance(x, (tuple, list)) else repr(x)


def read_manifest(out: pathlib.Path) -> dict:
    return _read_object(pathlib.Path(out) / "manifest.json")


def read_progress(out: pathlib.Path) -> dict:
    p = pathlib.Path(out) / "progress.json"
    return _read_object(p) if p.is_file() else {}


def _read_object(path: pathlib.Path) -> dict:
    """A sweep's JSON file, or a ConfigError naming it (a damaged file is not a sweep to resume)."""
    try:
        obj = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise ConfigError(f"{path} cannot be read as a sweep's JSON ({err}); the directory is not a sweep this "
                          "command can resume: restore the file, or choose another out") from None
    if not isinstance(obj, dict):
        raise ConfigError(f"{path} holds a JSON {type(obj).__name__}, not a sweep's object; the directory is not a "
                          "sweep this command can resume: restore the file, or choose another out")
    return obj
