"""How many JAX devices the CPU is split into: every physical core advances its own runs.

XLA runs one CPU device's program on a shared thread pool, but a run's learner update is a chain
of small convolutions and matmuls that keeps two cores only partly busy. Split into as many host
devices as there are physical cores, the sweep's runs axis is sharded over them (program.py) and
each core steps its own runs side by side; bench.py's `what=sweep` measures the gain.

The count must be fixed before JAX starts its CPU backend (XLA reads
`--xla_force_host_platform_device_count` once), so the sweep and the bench call `apply` after
reading their command line and before their first JAX computation. The rule (`choose`):
- a number given on the command line wins (`host_devices=1`: one device, the old behaviour);
- else a count the user put in XLA_FLAGS themselves;
- else, resuming a sweep made on the CPU, the count it was made with: the same program then
  continues the runs bit for bit as if they had never stopped (another count is another program,
  see run.py), and the checkpoints hold as many padding runs as that count required;
- else as many devices as physical cores allow, no more than the runs, while padding adds at most
  a tenth to the work (`PADDING_TOLERANCE`): the largest such count (24 runs on 2 cores: 2; 15
  runs: 2, one padding run; 9 runs: 1, as one padding run would add 11 %; 1 run: 1). Padding
  fills the last device's slots with copies of run 0 whose results are dropped (program.py), and
  they cost as much as real runs. One device still uses every core through XLA's thread pool,
  only less well than a device per core, so a second device pays for a little padding, not for
  much. Measured on 2 cores (`bench what=sweep runs=R steps=100 repeats=1 host_devices=D`, AMD
  EPYC, the defaults, D = 1 then 2, twice): 15 runs 12.2 → 14.3 and 13.1 → 14.8 run-steps/s
  (1.17x, 1.13x, one padding run in 16 slots); 9 runs 13.9 → 13.3 and 14.7 → 13.0 (0.96x,
  0.88x, one in 10); one run alone 18.0 on one device and 9.8 on two (its copy on the other).
  No more devices than cores: 24 runs on four devices of a 2-core CPU ran 7-12 % slower than on
  two (README, Benchmarks), the programs sharing a core contending for it.
On a GPU the flag changes nothing that the sweep uses: it only splits the host CPU platform.
"""

from __future__ import annotations

import os
import re

from mjx_curio.config import ConfigError

FLAG = "xla_force_host_platform_device_count"
# The most padding runs `auto` accepts, as a share of the real runs: between the 1/15 that measured
# faster on a second device and the 1/9 that measured slower (module docstring).
PADDING_TOLERANCE = 0.1


def physical_cores() -> int:
    """Physical cores this process may run on (hyperthreads share a core's FMA units, so they
    are not counted twice), from Linux's CPU topology; the logical count elsewhere."""
    try:
        cpus = sorted(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)
    cores = set()
    for cpu in cpus:
        base = f"/sys/devices/system/cpu/cpu{cpu}/topology/"
        try:
            with open(base + "core_id") as f, open(base + "physical_package_id") as g:
                cores.add((g.read().strip(), f.read().strip()))
        except OSError:
            cores.add(("cpu", str(cpu)))
    return max(1, len(cores))


def from_xla_flags(flags: str | None = None) -> int | None:
    """The host device count set in XLA_FLAGS, or None."""
    found = re.findall(rf"--{FLAG}=(\d+)", os.environ.get("XLA_FLAGS", "") if flags is None else flags)
    return int(found[-1]) if found else None


def choose(requested, n_runs: int, saved: int | None = None) -> int:
    """The host device count for a sweep of `n_runs` runs (see the module docstring).

    requested: "auto" or a positive int (the `host_devices` key); saved: the CPU device count a
    resumed sweep was made with (None for a new sweep or one made on another platform)."""
    if requested != "auto":
        return int(requested)
    given = from_xla_flags()
    if given is not None:
        return given
    if saved is not None:
        return saved
    return max(d for d in range(1, max(1, min(physical_cores(), n_runs)) + 1)
               if padding(n_runs, d) <= PADDING_TOLERANCE * n_runs)


def padding(n_runs: int, count: int) -> int:
    """Copies of run 0 that fill `count` devices' equal shares of `n_runs` runs."""
    return -n_runs % count


def _backends_started() -> bool:
    """Whether JAX's backends already started in this process. JAX has no public way to ask, so
    this reads a private function; a JAX release without it counts as not started (the flag is
    then set and simply has no effect on a backend that already runs)."""
    try:
        from jax._src import xla_bridge

        return bool(xla_bridge.backends_are_initialized())
    except (ImportError, AttributeError):
        return False


def apply(count: int, requested="auto") -> int:
    """Make JAX's CPU platform `count` devices; returns the count JAX will have.

    Before JAX's backend starts this sets XLA_FLAGS. After it started (a test, a notebook that
    already computed something) the count can no longer change: with `requested="auto"` the
    backend's own count is kept, while a count the user asked for explicitly is an error."""
    if _backends_started():
        import jax

        have = len(jax.devices("cpu"))
        if requested != "auto" and have != count:
            raise ConfigError(f"host_devices={count} cannot be applied: JAX already started with {have} CPU "
                              f"device(s) in this process; set it before the first JAX computation")
        return have
    flags = re.sub(rf"\s*--{FLAG}=\d+", "", os.environ.get("XLA_FLAGS", "")).strip()
    os.environ["XLA_FLAGS"] = f"{flags} --{FLAG}={count}".strip()
    return count
