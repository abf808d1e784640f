"""runs_loop=vmap: per-run convolution kernels compute as batched matmuls (no grouped
convolutions in the program), and a batched sweep agrees with the one-run-at-a-time one. With
either runs loop a chunk of steps is one program that never calls back into Python or
exchanges data with the host (no callback, infeed, outfeed, send or recv): a sweep's Python waits
on the device only between chunks. (XLA's own runtime may still read a loop's predicate back
between iterations on a GPU, for loops whose trip count depends on the data, as MJX's solver's
does; that is no op of the program.)"""

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

import dataclasses
import functools
import os
import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax import lax

from mjx_curio import policies
from mjx_curio import run as run_lib
from mjx_curio import world_model as wm
from mjx_curio.config import LearnerConfig

# 16 px (two encoder layers, four upconvs), small networks; an update every 4 steps from the
# 4th on (a batch of 2 sequences of 2 transitions needs 3 stored steps).
LEARNER = LearnerConfig(image=16, latent=4, vae_channels=(8, 8, 8, 8), dec_channels=(8, 8, 8, 8), rnn_hidden=8,
                        mixtures=2, self_hidden=8, batch=2, seq_len=2)
CFG = run_lib.RunConfig(image=16, buffer=8, update_every=4, metrics_every=4, learner=LEARNER)
STEPS = 12  # three learner updates: long enough to use every learned network, too short for rounding to grow


def group_counts(hlo: str) -> list[int]:
    """feature_group_count and batch_group_count of every convolution in StableHLO text."""
    return [int(n) for n in re.findall(r"(?:feature|batch)_group_count = (\d+)", hlo)]


def test_group_counts_sees_what_vmap_makes_of_a_per_run_lax_conv():
    # the check below is only as good as its parser: vmapping a plain convolution over
    # batched kernels must show up as a grouped one
    def conv(x, w):
        return lax.conv_general_dilated(x, w, (1, 1), "VALID", dimension_numbers=("NHWC", "HWIO", "NHWC"))

    hlo = jax.jit(jax.vmap(conv)).lower(jnp.zeros((2, 1, 5, 5, 3)), jnp.zeros((2, 2, 2, 3, 4))).as_text()
    assert max(group_counts(hlo)) == 2


def test_vmapped_learner_update_has_no_grouped_convolution():
    keys = jax.random.split(jax.random.PRNGKey(0), 2)
    states = jax.eval_shape(jax.vmap(lambda k: wm.init_learner(LEARNER, k)), keys)
    shp = (2, LEARNER.batch, LEARNER.seq_len + 1, LEARNER.n_agents)
    batch = wm.Batch(frames=jax.ShapeDtypeStruct(shp + (16, 16, 3), jnp.uint8),
                     latents=jax.ShapeDtypeStruct(shp + (LEARNER.latent,), jnp.float32),
                     actions=jax.ShapeDtypeStruct(shp, jnp.int32),
                     carry=(jax.ShapeDtypeStruct(shp[:3] + (LEARNER.rnn_hidden,), jnp.float32),) * 2)
    update = jax.jit(jax.vmap(functools.partial(wm.learner_update, LEARNER)))
    hlo = update.lower(states, batch, keys).as_text()
    assert "dot_general" in hlo
    assert set(group_counts(hlo)) <= {1}, "a convolution of the vmapped update is grouped"


# What in a lowered program makes the device wait on the host: a Python callback (jax.debug,
# pure_callback, io_callback: a custom call to the runtime's callback target) or a transfer op.
HOST_OPS = re.compile(r"custom_call @(\w*callback\w*)|stablehlo\.(infeed|outfeed|send|recv)\b")


def host_ops(hlo: str) -> list[str]:
    """The ops of StableHLO text that wait on the host (`HOST_OPS`), by name."""
    return sorted({a or b for a, b in HOST_OPS.findall(hlo)})


def test_host_ops_sees_callbacks():
    # the check below is only as good as its parser: a debug print and a pure callback must show
    def f(x):
        jax.debug.callback(lambda v: None, x)
        return jax.pure_callback(lambda v: v, jax.ShapeDtypeStruct(x.shape, x.dtype), x)

    assert host_ops(jax.jit(f).lower(jnp.zeros(3)).as_text())
    assert host_ops(jax.jit(lambda x: x + 1).lower(jnp.zeros(3)).as_text()) == []


def _policies():
    # eps-greedy and Boltzmann: two runs that act differently from the first step
    return jax.tree.map(lambda *xs: jnp.stack(xs), policies.make_policy_params(0, 0.2, 1.5, 1.0),
                        policies.make_policy_params(1, 0.2, 1.5, 1.0))


# Two whole sweep programs (map and vmap) to compile: four and a half minutes on a 2-core CPU,
# a third of the suite's budget, for the path a CPU never takes by default. The learner's
# vmap path is checked above (no grouped convolution) and in test_world_model.py (a vmapped
# update equals separate ones); this whole-sweep check runs where it matters, before a GPU run
# or a change to run.py: MJX_CURIO_VMAP_SWEEP=1 pytest tests/test_runs_loop.py
@pytest.mark.slow
@pytest.mark.skipif(os.environ.get("MJX_CURIO_VMAP_SWEEP") != "1",
                    reason="whole vmap sweep vs map sweep: opt in with MJX_CURIO_VMAP_SWEEP=1 (~4.5 min)")
def test_vmap_sweep_equals_map_sweep_over_a_short_horizon():
    keys = jnp.asarray(np.stack([run_lib.key_for_seed(s) for s in (0, 1)]))
    pol = _policies()
    vcfg = dataclasses.replace(CFG, runs_loop="vmap")
    states = jax.jit(functools.partial(run_lib.init_runs, CFG))(keys, pol)
    vstates = jax.jit(functools.partial(run_lib.init_runs, vcfg))(keys, pol)

    lowered = jax.jit(functools.partial(run_lib.sweep_chunk, vcfg, n_steps=STEPS)).lower(vstates)
    assert set(group_counts(lowered.as_text())) <= {1}, "a convolution of the vmapped sweep is grouped"
    got = lowered.compile()(vstates)
    want = jax.jit(functools.partial(run_lib.sweep_chunk, CFG, n_steps=STEPS))(states)

    assert np.all(np.asarray(want[1]["updates"]) == 1)  # each window of 4 steps held one update
    for (path, a), b in zip(jax.tree_util.tree_flatten_with_path((vstates, got))[0],
                            jax.tree.leaves((states, want))):
        name = jax.tree_util.keystr(path)
        if ".env.data." in name and not name.endswith((".qpos", ".qvel", ".time")):
            # MJX's solver workspace: warm starts converged only to the solver's tolerance, and
            # contact slots not in contact, whose positions and Jacobians mean nothing
            continue
        a, b = np.asarray(a), np.asarray(b)
        if np.issubdtype(a.dtype, np.floating):
            np.testing.assert_allclose(a, b, rtol=1e-4, atol=1e-6, err_msg=name)
        else:  # frames, actions, counts, contacts, keys, replay slots: exactly
            np.testing.assert_array_equal(a, b, err_msg=name)


@pytest.mark.parametrize("runs_loop", ["vmap", "map"])
def test_a_sweep_chunk_never_waits_on_the_host(runs_loop, tmp_path):
    """The chunk program the sweep runs (`program.SweepProgram`, the tiny sweep's 8 runs, a chunk of
    100 steps), lowered, not compiled (a few seconds), holds no op that waits on the host
    (`host_ops`): the whole chunk of steps, learner updates included, runs without Python."""
    from conftest import TINY_SWEEP
    from mjx_curio import cli
    from mjx_curio import plan as plan_lib
    from mjx_curio import sweep as sweep_lib
    from mjx_curio.program import SweepProgram

    p = plan_lib.plan(cli.parse([*TINY_SWEEP, f"out={tmp_path / 'unused'}"], sweep_lib.KEYS))
    cfg = dataclasses.replace(p.run, runs_loop=runs_loop)
    program = SweepProgram(cfg, p.runs, -len(p.runs) % len(jax.devices()), p.values["chunk"])
    hlo = program.lower(program.abstract()).as_text()
    assert "while" in hlo  # the lowered chunk holds its loop over steps
    assert host_ops(hlo) == []
