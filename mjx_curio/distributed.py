"""Processes and devices: joining a cluster, the compile cache, and gathering global arrays.

On a cluster every process runs the same sweep command; `distributed=auto` calls
`jax.distributed.initialize()` when the environment shows one (SLURM, Open MPI, or
JAX_COORDINATOR_ADDRESS with JAX_NUM_PROCESSES and JAX_PROCESS_ID), with no launcher of ours.
"""

from __future__ import annotations

import os
import pathlib

import numpy as np

from mjx_curio.config import ConfigError


def setup_jax(distributed: str, compile_cache: str) -> None:
    import jax

    if distributed == "true" or (distributed == "auto" and cluster_detected()):
        # Coordinator, process count and id from the environment: SLURM's or Open MPI's, which
        # JAX reads itself, or plain JAX_COORDINATOR_ADDRESS, JAX_NUM_PROCESSES, JAX_PROCESS_ID.
        count, index = process_env()
        try:
            jax.distributed.initialize(num_processes=count, process_id=index)
        except (ValueError, RuntimeError) as err:
            raise ConfigError(f"distributed={distributed}: joining the cluster failed ({err}); on a cluster set "
                              "JAX_COORDINATOR_ADDRESS, JAX_NUM_PROCESSES and JAX_PROCESS_ID or run under SLURM "
                              "or Open MPI; alone, use distributed=auto or false") from None
    use_compile_cache(compile_cache_dir(compile_cache))


def compile_cache_dir(value: str) -> pathlib.Path | None:
    """The directory `compile_cache=value` names (None for none), checked without making it: a
    file in its place, or a parent nobody can write, is a ConfigError naming the key."""
    if value.lower() == "none":
        return None
    from mjx_curio.plan import check_creatable

    path = pathlib.Path(os.path.expanduser(value))
    if path.exists() and not path.is_dir():
        raise ConfigError(f"compile_cache={value} is a file, not a directory; name a directory (made if missing) "
                          "or none")
    check_creatable(path, "compile_cache")
    return path


def use_compile_cache(path: pathlib.Path | None) -> None:
    """Keep JAX's compiled programs in `path` (made if missing) across processes."""
    if path is None:
        return
    import jax

    path.mkdir(parents=True, exist_ok=True)
    jax.config.update("jax_compilation_cache_dir", str(path))


def process_env() -> tuple[int | None, int | None]:
    """JAX_NUM_PROCESSES and JAX_PROCESS_ID from the environment (None where unset)."""
    env = os.environ
    count, index = env.get("JAX_NUM_PROCESSES") or None, env.get("JAX_PROCESS_ID") or None
    if count is not None and not (count.isdigit() and int(count) >= 1):
        raise ConfigError(f"JAX_NUM_PROCESSES={count!r} must be a positive integer (the number of processes)")
    if index is not None and not (index.isdigit() and (count is None or int(index) < int(count))):
        raise ConfigError(f"JAX_PROCESS_ID={index!r} must be an integer from 0 to JAX_NUM_PROCESSES - 1"
                          f"{f' = {int(count) - 1}' if count else ''}")
    return (int(count) if count else None), (int(index) if index else None)


def rank_from_env() -> int:
    """This process's index on a cluster, read before JAX starts (0 when alone)."""
    env = os.environ
    for name in ("JAX_PROCESS_ID", "SLURM_PROCID", "OMPI_COMM_WORLD_RANK"):
        if env.get(name, "").isdigit() and (name == "JAX_PROCESS_ID" or cluster_detected()):
            return int(env[name])
    return 0


def cluster_detected() -> bool:
    env = os.environ
    if env.get("JAX_COORDINATOR_ADDRESS"):
        return True
    if int(env.get("SLURM_NTASKS", "1") or 1) > 1 and env.get("SLURM_JOB_ID"):
        return True
    return int(env.get("OMPI_COMM_WORLD_SIZE", "1") or 1) > 1


def host(x) -> np.ndarray:
    """A (possibly multi-process) global array as a NumPy array on every process. A collective
    on a cluster: every process must call it."""
    if getattr(x, "is_fully_addressable", True):
        return np.asarray(x)
    from jax.experimental import multihost_utils

    return np.asarray(multihost_utils.process_allgather(x, tiled=True))


def any_process(flag: bool) -> bool:
    """True on every process when `flag` is true on any (a collective, like `host`)."""
    import jax

    if jax.process_count() == 1:
        return flag
    from jax.experimental import multihost_utils

    return bool(np.any(multihost_utils.process_allgather(np.asarray([flag]))))


def process_count() -> int:
    import jax

    return jax.process_count()
