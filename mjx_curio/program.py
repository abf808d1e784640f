"""A sweep's compiled program: init and chunk functions over a runs axis sharded across every
visible device (`shard_map`: each device advances its own runs, nothing crosses devices)."""

from __future__ import annotations

import functools

import numpy as np

from mjx_curio.config import POLICY_IDS


class SweepProgram:
    """The compiled init and chunk functions of a sweep. `runs` (plan.RunSpec) are padded with
    `n_pad` copies of run 0 so every device holds as many runs; the padding's results are
    computed and dropped."""

    def __init__(self, cfg, runs: tuple, n_pad: int, chunk: int):
        import jax

        from mjx_curio import policies
        from mjx_curio import run as run_lib

        self.cfg, self.chunk_steps = cfg, chunk
        self._init, self._jitted_chunk, self.sharding = _compiled(cfg, chunk, tuple(jax.devices()))
        self._chunk = self._jitted_chunk  # compile() replaces it with the compiled executable
        padded = list(runs) + [runs[0]] * n_pad
        keys = np.stack([run_lib.key_for_seed(r.seed) for r in padded])
        pol = [policies.make_policy_params(POLICY_IDS[r.policy], r.eps, r.temperature, r.ucb_c) for r in padded]
        pol = jax.tree.map(lambda *x: np.stack([np.asarray(a) for a in x]), *pol)
        self.inputs = jax.tree.map(self._global, (keys, pol))

    def _global(self, x: np.ndarray):
        import jax

        return jax.make_array_from_callback(x.shape, self.sharding, lambda idx: x[idx])

    def init(self):
        return self._init(*self.inputs)

    def abstract(self):
        import jax

        shapes = jax.eval_shape(self._init, *self.inputs)
        return jax.tree.map(lambda s: jax.ShapeDtypeStruct(s.shape, s.dtype, sharding=self.sharding), shapes)

    def lower(self, states):
        """The chunk program traced for `states` (arrays, or `abstract()`'s shapes) and lowered, not
        compiled: its StableHLO (`.as_text()`) is what the device will run. Works before and after
        compile()."""
        return self._jitted_chunk.lower(states)

    def compile(self, states) -> None:
        """Trace and compile the chunk program for `states` now (or load it from the compilation
        cache); chunk() then runs that executable. Lets a benchmark time compiling apart from
        running: a first chunk is no steady one (its replay is filling, so it trains less)."""
        self._chunk = self.lower(states).compile()

    def chunk(self, states):
        return self._chunk(states)


@functools.lru_cache(maxsize=8)
def _compiled(cfg, chunk: int, devices: tuple):
    """(init, chunk, sharding) for a config, one set per process: a second sweep with the same
    program in the same process (a resume, a test) reuses the traces and executables."""
    import jax
    from jax.sharding import NamedSharding
    from jax.sharding import PartitionSpec as P

    from mjx_curio import run as run_lib

    # The arena (MJX model arrays, contact tables) is built here, outside the sharded trace:
    # built inside it on a multi-process mesh, its arrays spanned the other processes' devices
    # and could not be closed over.
    cfg.arena  # noqa: B018
    mesh = jax.make_mesh((len(devices),), ("runs",), devices=devices)
    spec = P("runs")
    # Each device advances its own runs and nothing crosses devices, so shard_map's check of
    # which values vary across the mesh has nothing to guard (and it rejects the runs loop's
    # zero-initialised carry).
    init = jax.shard_map(lambda k, q: run_lib.init_runs(cfg, k, q), mesh=mesh,
                         in_specs=(spec, spec), out_specs=spec, check_vma=False)
    chunk_fn = jax.shard_map(lambda s: run_lib.sweep_chunk(cfg, s, chunk), mesh=mesh,
                             in_specs=(spec,), out_specs=(spec, spec), check_vma=False)
    return jax.jit(init), jax.jit(chunk_fn, donate_argnums=0), NamedSharding(mesh, spec)
