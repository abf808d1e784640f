"""mjx_curio/checkpoint.py on its own: what a checkpoint written in the background holds.

Written asynchronously, orbax returns from `save` holding host views of the arrays (on a CPU,
the device buffers themselves) and compresses and writes them in background threads. The sweep's
next chunk donates its input state: were a buffer orbax still reads donated and overwritten, the
checkpoint would hold the next chunk's values. Here the next "chunk" runs at once, before the
write has had time to finish, and the checkpoint must still hold the values saved.
"""

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from mjx_curio import checkpoint as ckpt_lib


class Toy(NamedTuple):  # what Checkpoints.save needs of a RunState: its fields, one of them `replay`
    params: jax.Array
    step: jax.Array
    replay: dict


def _toy(seed: int) -> Toy:
    rng = np.random.default_rng(seed)
    # Random bytes compress poorly: a write of some 50 MB takes a while on any CPU.
    frames = rng.integers(0, 256, (4, 2_000, 64, 64, 3), dtype=np.uint8)
    return Toy(params=jnp.asarray(rng.normal(size=(4, 256, 256)), jnp.float32), step=jnp.full((4,), 100, jnp.int32),
               replay={"frames": jnp.asarray(frames), "size": jnp.full((4,), 2_000, jnp.int32)})


@jax.jit
def _advance(t: Toy) -> Toy:
    return Toy(params=t.params * 2.0 + 1.0, step=t.step + 100,
               replay={"frames": t.replay["frames"] + np.uint8(1), "size": t.replay["size"]})


_advance_donating = jax.jit(_advance.__wrapped__, donate_argnums=0)


@pytest.mark.parametrize("asynchronous", [False, True], ids=["waits", "background"])
def test_a_checkpoint_holds_the_saved_state_though_the_next_step_donates_it(asynchronous, tmp_path):
    saved = _toy(0)
    want = jax.tree.map(np.array, saved)  # host copies, taken before anything is donated
    ckpts = ckpt_lib.Checkpoints(tmp_path / "checkpoints", asynchronous=asynchronous)
    ckpts.save(100, saved)
    after = _advance_donating(saved)  # as the sweep's next chunk does, at once
    jax.block_until_ready(after)
    ckpts.save(200, after)  # waits for step 100's write first
    ckpts.close()
    assert not ckpts.writing()

    reader = ckpt_lib.Checkpoints(tmp_path / "checkpoints", read_only=True)
    assert reader.latest_complete() == 200 and reader.state_steps() == [100, 200]
    state = reader.restore_raw(100)
    np.testing.assert_array_equal(state["params"], want.params)
    np.testing.assert_array_equal(state["step"], want.step)
    replay = reader.restore_raw(200, "replay")
    np.testing.assert_array_equal(replay["frames"], want.replay["frames"] + np.uint8(1))
    np.testing.assert_array_equal(reader.restore_raw(200)["params"], np.asarray(after.params))
    reader.close()
