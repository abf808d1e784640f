"""The CPU device count a sweep chooses (mjx_curio/host_devices.py), and its key.

Whether the runs of a sweep spread over devices give the runs' own results is asked by the
sharding test in test_sweep.py (its sweep asks for host_devices=2); here: which count is chosen,
from what, and that a bad value is refused before any work."""

import io
import os

import pytest

from mjx_curio import host_devices
from mjx_curio.config import ConfigError, SweepConfig


@pytest.fixture
def no_flag(monkeypatch):
    """XLA_FLAGS without a host device count (the session's own sets one: conftest.py)."""
    flags = os.environ.get("XLA_FLAGS", "").replace(f"--{host_devices.FLAG}=1", "")
    monkeypatch.setenv("XLA_FLAGS", flags)


def test_physical_cores_counts_each_core_once(monkeypatch):
    cores = host_devices.physical_cores()
    assert 1 <= cores <= len(os.sched_getaffinity(0))
    # A made-up topology: CPUs 0-3 are two cores with two hyperthreads each on package 0, CPU 4
    # is core 0 of package 1 (a core id repeats across packages), CPU 5 has no topology files.
    topology = {0: ("0", "0"), 1: ("0", "0"), 2: ("0", "1"), 3: ("0", "1"), 4: ("1", "0")}

    def fake_open(path, *args, **kwargs):
        cpu = int(path.split("/cpu/cpu")[1].split("/")[0])
        if cpu not in topology:
            raise FileNotFoundError(path)
        package, core = topology[cpu]
        return io.StringIO(core if path.endswith("core_id") else package)

    monkeypatch.setattr(host_devices.os, "sched_getaffinity", lambda pid: {0, 1, 2, 3, 4, 5})
    monkeypatch.setattr(host_devices, "open", fake_open, raising=False)
    assert host_devices.physical_cores() == 4  # (0, 0), (0, 1), (1, 0) and CPU 5 on its own
    monkeypatch.setattr(host_devices.os, "sched_getaffinity", lambda pid: {1, 3})
    assert host_devices.physical_cores() == 2
    monkeypatch.setattr(host_devices.os, "sched_getaffinity", lambda pid: {0, 1})
    assert host_devices.physical_cores() == 1


def test_auto_is_the_most_devices_the_cores_allow_with_at_most_a_tenth_padding(no_flag, monkeypatch):
    monkeypatch.setattr(host_devices, "physical_cores", lambda: 8)
    assert host_devices.choose("auto", n_runs=24) == 8
    assert host_devices.choose("auto", n_runs=3) == 3  # never more devices than runs
    assert host_devices.choose("auto", n_runs=1) == 1
    assert host_devices.choose("auto", n_runs=20) == 7  # 8 would pad 4 runs (20 %), 7 pads 1 (5 %)
    assert host_devices.choose("auto", n_runs=7) == 7
    assert host_devices.choose("auto", n_runs=10) == 5  # 8 would pad 6, 6 and 7 pad 2 and 4
    monkeypatch.setattr(host_devices, "physical_cores", lambda: 2)
    assert host_devices.choose("auto", n_runs=24) == 2
    assert host_devices.choose("auto", n_runs=15) == 2  # one padding run, 1/15
    assert host_devices.choose("auto", n_runs=10) == 2
    assert host_devices.choose("auto", n_runs=9) == 1  # one padding run would be 1/9
    assert host_devices.choose("auto", n_runs=3) == 1


def test_padding_fills_every_device_to_the_same_number_of_runs():
    for n_runs in range(1, 30):
        for count in range(1, 9):
            pad = host_devices.padding(n_runs, count)
            assert 0 <= pad < count and (n_runs + pad) % count == 0


def test_what_the_user_set_wins(no_flag, monkeypatch):
    monkeypatch.setattr(host_devices, "physical_cores", lambda: 8)
    assert host_devices.choose(2, n_runs=24) == 2  # the key
    monkeypatch.setenv("XLA_FLAGS", f"--foo=1 --{host_devices.FLAG}=5")
    assert host_devices.from_xla_flags() == 5
    assert host_devices.choose("auto", n_runs=24) == 5  # their own XLA_FLAGS
    assert host_devices.choose(3, n_runs=24) == 3  # the key over XLA_FLAGS


def test_a_resumed_sweep_keeps_the_count_it_was_made_with(no_flag, monkeypatch):
    monkeypatch.setattr(host_devices, "physical_cores", lambda: 8)
    assert host_devices.choose("auto", n_runs=24, saved=1) == 1  # its checkpoints hold its padding runs
    assert host_devices.choose(4, n_runs=24, saved=1) == 4


def test_apply_after_jax_started_keeps_the_count_or_refuses_a_different_one():
    import jax

    have = len(jax.devices("cpu"))  # starts the backend if no test did
    assert host_devices.apply(have + 1, "auto") == have
    assert host_devices.apply(have, have) == have
    with pytest.raises(ConfigError, match=rf"host_devices={have + 1} cannot be applied"):
        host_devices.apply(have + 1, have + 1)


def test_a_jax_without_the_private_started_query_counts_as_not_started(no_flag, monkeypatch):
    # JAX offers no public way to ask whether its backends started; a release that drops the
    # private one must not break the sweep's start, only make the flag a no-op.
    from jax._src import xla_bridge

    monkeypatch.delattr(xla_bridge, "backends_are_initialized")
    assert host_devices._backends_started() is False
    assert host_devices.apply(3, "auto") == 3
    assert host_devices.from_xla_flags() == 3


@pytest.mark.parametrize("value", [0, -1, "two", 1.5])
def test_bad_host_devices_is_refused_with_the_allowed_values(value):
    with pytest.raises(ConfigError, match=r"host_devices=.*(integer|auto)"):
        SweepConfig(host_devices=value)
