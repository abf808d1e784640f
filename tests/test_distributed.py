"""Several processes, one sweep: `jax.distributed` with two CPU processes on this machine.

Each process runs the same `python -m mjx_curio.sweep` command with JAX_COORDINATOR_ADDRESS,
JAX_NUM_PROCESSES and JAX_PROCESS_ID set, as a cluster scheduler would start it on two hosts;
the runs axis spans both processes' devices. Each process's device runs the same program as a
device of the two-device sweep in one process, so the two agree bit for bit; against the
one-device tiny sweep, what sharding guarantees is compared (tests/test_sweep.py).

Opt-in (MJX_CURIO_MULTIPROCESS=1): two more compiles, ~90 s on two cores a case, which the
default suite leaves out to stay well under its time budget. Measured 2026-11-22: passes, and the two-
process sweep is bit-identical to the two-device one.
"""

import json
import os
import socket
import subprocess
import sys

import pytest

from conftest import CACHE, TINY_SWEEP
from test_sweep import _assert_same_metrics, _assert_same_tree, _metrics, _state, assert_same_runs_on_other_devices

pytestmark = pytest.mark.skipif(os.environ.get("MJX_CURIO_MULTIPROCESS") != "1",
                                reason="multi-process sweep: opt in with MJX_CURIO_MULTIPROCESS=1 (~90 s)")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


# Checkpoints written while the sweep waits (what `auto` does on a CPU), and in the background (what
# it does on a GPU or TPU), where orbax's threads of the two processes meet at barriers of their own.
@pytest.mark.parametrize("background", ["false", "true"], ids=["waited-for", "background"])
def test_two_processes_equal_two_devices_in_one(background, tiny_sweep, sharded_sweep, tmp_path):
    out = tmp_path / "two_processes"
    port = _free_port()
    args = [*TINY_SWEEP, f"out={out}", f"compile_cache={CACHE}", f"async_checkpoints={background}"]
    procs = [subprocess.Popen([sys.executable, "-m", "mjx_curio.sweep", *args],
                              stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                              env=dict(os.environ, JAX_COORDINATOR_ADDRESS=f"127.0.0.1:{port}", JAX_NUM_PROCESSES="2",
                                       JAX_PROCESS_ID=str(i)))
             for i in range(2)]
    errors = [p.communicate(timeout=900)[1] for p in procs]
    for p, err in zip(procs, errors):
        assert p.returncode == 0, err[-4000:]
    device = json.loads((out / "manifest.json").read_text())["device"]
    assert (device["processes"], device["count"]) == (2, 2)
    _assert_same_metrics(_metrics(out), _metrics(sharded_sweep), "2 processes vs 2 devices in one")
    _assert_same_tree(_state(out, 200), _state(sharded_sweep, 200), "final checkpoint, 2 processes vs 2 devices in one")
    assert_same_runs_on_other_devices(out, tiny_sweep, "2 processes vs 1 device")
