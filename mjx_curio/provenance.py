"""What a sweep's manifest records about how it was made: the command, every setting, the runs,
the package versions, the device, the XLA flags it compiled with and the git commit."""

from __future__ import annotations

import dataclasses
import datetime
import os
import platform
import subprocess
import pathlib

import mjx_curio

FORMAT = "mjx_curio.sweep/1"


def manifest(p, run_cfg, devices, n_pad: int, n_windows: int, background: bool = False) -> dict:
    """p: the sweep's `plan.Plan`; run_cfg: its RunConfig with runs_loop resolved; background:
    async_checkpoints resolved (checkpoints written while the sweep steps on)."""
    from mjx_curio import distributed
    from mjx_curio import metrics as metrics_lib
    from mjx_curio.arena import ACTIONS, OBJECTS
    from mjx_curio.plan import KEYS, config_of

    return {
        "format": FORMAT,
        "created": datetime.datetime.now().isoformat(timespec="seconds"),
        "command": " ".join(["python -m mjx_curio.sweep"] + [f"{k.name}={k.kind.show(p.values[k.name])}" for k in KEYS]),
        "config": config_of(p.values),
        "run_config": _plain(dataclasses.asdict(run_cfg)),
        "runs": [dict(index=i, name=r.name, **dataclasses.asdict(r)) for i, r in enumerate(p.runs)],
        "padded_runs": n_pad,
        "n_agents": run_cfg.n_agents,
        "agent_names": ["green", "purple"][: run_cfg.n_agents],
        "actions": list(ACTIONS),
        "objects": list(OBJECTS),
        "view_targets": list(metrics_lib.VIEW_TARGETS),
        "metrics": {"every": run_cfg.metrics_every, "windows": n_windows, "steps_file": "metrics/steps.npy",
                    "schema": metrics_lib.schema_doc()},
        "steps_planned": [{"steps": p.values["steps"], "from_step": 0}],
        "checkpoints": {"state": "checkpoints/state/<step>", "replay": "checkpoints/replay/<step>",
                        "written_in_background": background},
        "versions": versions(),
        "device": {"platform": devices[0].platform, "kind": devices[0].device_kind, "count": len(devices),
                   "processes": distributed.process_count(), "host": platform.node(), "cpu": cpu_name(),
                   # XLA's codegen options set here move float rounding, so the last bits of a run.
                   "xla_flags": os.environ.get("XLA_FLAGS", ""),
                   # JAX's default precision runs float32 matrix products and convolutions on TF32
                   # tensor cores on recent NVIDIA GPUs (JAX_DEFAULT_MATMUL_PRECISION=highest: float32).
                   "matmul_precision": _matmul_precision()},
        "git": git(),
    }


def _plain(x):
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    if isinstance(x, (tuple, list)):
        return [_plain(v) for v in x]
    return x


def _matmul_precision() -> str:
    """JAX's default precision for float32 matrix products, as set (or 'default': the backend's)."""
    import jax

    return str(jax.config.jax_default_matmul_precision or "default")


def versions() -> dict:
    from importlib import metadata

    out = {"python": platform.python_version(), "mjx_curio": mjx_curio.__version__}
    for pkg in ("jax", "jaxlib", "mujoco", "mujoco-mjx", "flax", "optax", "orbax-checkpoint", "numpy"):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = None
    return out


def cpu_name() -> str:
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor()


def git(paths=None) -> dict:
    """The commit of the checkout this package runs from, and whether what sets a run's results
    differs from it: the package's code and the scenes it loads (the arena's masses, damping,
    friction, timestep and textures live in their XML, outside the package's directory in a
    checkout). paths: the directories to look at, the first the package's (default those two);
    any outside the checkout are left out. A package git does not track there (an installed copy
    whose site-packages lies inside some other repository, such as pyenv's) has no commit."""
    if paths is None:
        from mjx_curio.arena import SCENES

        paths = [pathlib.Path(__file__).resolve().parent, SCENES]
    paths = [pathlib.Path(x).resolve() for x in paths]

    def run(*args):
        return subprocess.run(["git", "-C", str(paths[0]), *args], capture_output=True, text=True, timeout=10)

    try:
        top, commit = run("rev-parse", "--show-toplevel"), run("rev-parse", "HEAD")
        tracked = run("ls-files", "--", str(paths[0]))
        if top.returncode == 0 and commit.returncode == 0 and tracked.stdout.strip():
            root = pathlib.Path(top.stdout.strip()).resolve()
            inside = [str(q) for q in paths if q.is_relative_to(root)]
            dirty = run("status", "--porcelain", "--", *inside)
            return {"commit": commit.stdout.strip(), "dirty": bool(dirty.stdout.strip())}
    except (OSError, subprocess.TimeoutExpired):
        pass
    return {"commit": None, "dirty": None}
