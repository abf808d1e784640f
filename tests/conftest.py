"""Shared pytest setup: GL for MuJoCo's renderer, one XLA compilation cache for the whole
session (in-process and subprocess alike), and one tiny sweep that several test files read."""

import os
import pathlib
import subprocess
import sys
import tempfile

import pytest

# MuJoCo chooses its OpenGL backend when `mujoco` is first imported, by whichever test module
# imports it first; tests/test_render.py compares against MuJoCo's off-screen renderer, which
# on a headless machine needs OSMesa (apt-get install -y libosmesa6).
os.environ.setdefault("MUJOCO_GL", "osmesa")

# Compiling an MJX step takes ~30 s on a 2-core CPU, and the sweep tests start several
# processes that compile the same programs: a persistent cache shared by every process of the
# session (set before JAX initialises) makes each program compile once.
CACHE = pathlib.Path(os.environ.setdefault("JAX_COMPILATION_CACHE_DIR", tempfile.mkdtemp(prefix="mjx_curio_xla_")))

# The tiny sweep: image 16, 2 seeds x (eps, boltzmann at T=0.5 and 1.5, ucb) = 8 runs, 200 steps, checkpoints at 100 and 200.
TINY_SWEEP = ("seeds=2", "temperature=0.5,1.5", "steps=200", "image=16", "buffer=500", "chunk=100", "checkpoint_every=100",
              "keep_steps=100", "keep_every=0", "progress=false")


def run_sweep(*args: str, env: dict | None = None, check: bool = True, timeout: float = 900) -> subprocess.CompletedProcess:
    """`python -m mjx_curio.sweep *args` in a subprocess sharing the session's compile cache."""
    full_env = dict(os.environ, **(env or {}))
    proc = subprocess.run([sys.executable, "-m", "mjx_curio.sweep", *args, f"compile_cache={CACHE}"],
                          capture_output=True, text=True, env=full_env, timeout=timeout)
    if check and proc.returncode != 0:
        raise AssertionError(f"sweep {' '.join(args)} failed ({proc.returncode}):\n{proc.stderr[-4000:]}")
    return proc


@pytest.fixture(scope="session")
def tiny_sweep(tmp_path_factory) -> pathlib.Path:
    """A finished tiny sweep directory (made once per test session)."""
    out = tmp_path_factory.mktemp("sweeps") / "tiny"
    run_sweep(*TINY_SWEEP, f"out={out}")
    return out
