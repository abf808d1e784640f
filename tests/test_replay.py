"""Replay ring buffer: wrap-around, consecutive sequences, uniform valid starts."""

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from mjx_curio import replay

N_AGENTS, IMAGE, LATENT, HIDDEN = 2, 8, 3, 4


def _transition(t):
    """Step t, with t written into every field so positions can be checked."""
    return replay.Transition(
        frames=jnp.full((N_AGENTS, IMAGE, IMAGE, 3), t % 256, jnp.uint8),
        latents=jnp.full((N_AGENTS, LATENT), t, jnp.float32),
        actions=jnp.full((N_AGENTS,), t, jnp.int32),
        carry=(jnp.full((HIDDEN,), t, jnp.float32), jnp.full((HIDDEN,), -t, jnp.float32)),
    )


@pytest.fixture(scope="module")
def fns():
    add = jax.jit(replay.add)

    def fill(capacity, n_steps):
        buf = replay.init(N_AGENTS, IMAGE, LATENT, HIDDEN, capacity)
        for t in range(n_steps):
            buf = add(buf, _transition(t))
        return buf

    sample = jax.jit(replay.sample, static_argnums=(2, 3))
    return fill, sample


def test_add_wraps_around_and_keeps_the_newest(fns):
    fill, _ = fns
    buf = fill(10, 25)
    assert int(buf.index) == 5 and int(buf.size) == 10 and buf.capacity == 10
    # slot i holds the newest step congruent to i mod 10
    expected = np.array([20, 21, 22, 23, 24, 15, 16, 17, 18, 19])
    np.testing.assert_array_equal(buf.actions[:, 0], expected)
    np.testing.assert_array_equal(buf.latents[:, 1, 2], expected)
    np.testing.assert_array_equal(buf.frames[:, 0, 3, 4, 1], expected)
    np.testing.assert_array_equal(buf.carry[0][:, 0], expected)
    np.testing.assert_array_equal(buf.carry[1][:, 0], -expected)


def test_size_counts_up_before_wrapping(fns):
    fill, _ = fns
    buf = fill(10, 4)
    assert int(buf.index) == 4 and int(buf.size) == 4
    assert bool(replay.can_sample(buf, 3)) and not bool(replay.can_sample(buf, 4))


@pytest.mark.parametrize("n_steps", [7, 10, 25, 33])
def test_sequences_are_consecutive_and_never_cross_the_write_head(fns, n_steps):
    fill, sample = fns
    cap, seq_len = 10, 3
    buf = fill(cap, n_steps)
    b = sample(buf, jax.random.PRNGKey(n_steps), 512, seq_len)
    steps = np.asarray(b.actions[..., 0])  # the step number of every sampled slot
    assert steps.shape == (512, seq_len + 1)
    assert b.frames.shape == (512, seq_len + 1, N_AGENTS, IMAGE, IMAGE, 3)
    assert b.frames.dtype == jnp.uint8
    assert b.carry[0].shape == (512, seq_len + 1, HIDDEN)
    # consecutive: a sequence crossing the head would jump from the newest to the oldest
    np.testing.assert_array_equal(np.diff(steps, axis=1), 1)
    oldest = max(0, n_steps - cap)
    assert steps.min() >= oldest and steps.max() <= n_steps - 1
    # every field comes from the same step
    np.testing.assert_array_equal(b.latents[..., 0, 0], steps)
    np.testing.assert_array_equal(b.carry[1][..., 0], -steps)
    # all valid starts occur
    assert set(steps[:, 0]) == set(range(oldest, n_steps - seq_len))


def test_starts_are_uniform_over_valid_starts(fns):
    fill, sample = fns
    cap, seq_len, n = 20, 4, 16_000
    buf = fill(cap, 33)  # wrapped: steps 13..32 stored, head in the middle of the array
    starts = np.asarray(sample(buf, jax.random.PRNGKey(0), n, seq_len).actions[:, 0, 0])
    valid = np.arange(13, 33 - seq_len)  # 16 valid starts
    freq = np.array([np.sum(starts == s) for s in valid])
    assert freq.sum() == n  # nothing outside the valid starts
    expected = n / len(valid)
    chi2 = np.sum((freq - expected) ** 2 / expected)
    assert chi2 < 37.697, (chi2, freq)  # chi-square, 15 dof, p = 0.001


def test_sample_is_pure_and_jit_vmaps_over_runs(fns):
    fill, _ = fns
    bufs = [fill(10, n) for n in (12, 25)]
    stacked = jax.tree.map(lambda *x: jnp.stack(x), *bufs)
    keys = jax.random.split(jax.random.PRNGKey(3), 2)
    out = jax.jit(jax.vmap(lambda b, k: replay.sample(b, k, 8, 3)))(stacked, keys)
    for r, buf in enumerate(bufs):
        one = replay.sample(buf, keys[r], 8, 3)
        np.testing.assert_array_equal(out.actions[r], one.actions)
    np.testing.assert_array_equal(np.diff(np.asarray(out.actions[..., 0]), axis=-1), 1)
