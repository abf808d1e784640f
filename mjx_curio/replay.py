"""Fixed-capacity functional replay buffer (a ring) with sequence sampling.

The buffer is a pytree of preallocated arrays plus a write index and a size, so `add` and
`sample` are pure, jit-able and vmap over runs; shapes never change.

Slot layout: the step written at time t holds the frames o_t, latents z_t (as computed
when acting), actions a_t, and the LSTM carry *before* step t (the truncated-BPTT start
state when a sequence begins there). A sample is `batch` sequences of seq_len + 1
consecutive steps, i.e. seq_len transitions (z_t, a_t) -> z_{t+1}.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from mjx_curio.world_model import Batch

DEFAULT_CAPACITY = 10_000  # the authors' replay buffer of 10,000 (docs/paper_setup.md)


class Transition(NamedTuple):
    """One step to store: frames uint8 [n_agents, H, W, 3], latents [n_agents, Z],
    actions int32 [n_agents], carry (c, h) each [rnn_hidden]."""

    frames: jax.Array
    latents: jax.Array
    actions: jax.Array
    carry: tuple


class Replay(NamedTuple):
    frames: jax.Array  # uint8 [cap, n_agents, H, W, 3]
    latents: jax.Array  # f32 [cap, n_agents, Z]
    actions: jax.Array  # int32 [cap, n_agents]
    carry: tuple  # (c, h), each f32 [cap, rnn_hidden]
    index: jax.Array  # int32: next slot to write (the write head)
    size: jax.Array  # int32: slots written so far, at most cap

    @property
    def capacity(self) -> int:
        return self.actions.shape[0]


def init(
    n_agents: int,
    image: int,
    latent: int,
    rnn_hidden: int,
    capacity: int = DEFAULT_CAPACITY,
) -> Replay:
    if capacity < 2:
        raise ValueError(f"capacity={capacity} must be at least 2")
    z = jnp.zeros((capacity, rnn_hidden), jnp.float32)
    return Replay(
        frames=jnp.zeros((capacity, n_agents, image, image, 3), jnp.uint8),
        latents=jnp.zeros((capacity, n_agents, latent), jnp.float32),
        actions=jnp.zeros((capacity, n_agents), jnp.int32),
        carry=(z, z),
        index=jnp.zeros((), jnp.int32),
        size=jnp.zeros((), jnp.int32),
    )


def init_for(cfg, capacity: int = DEFAULT_CAPACITY) -> Replay:
    """A buffer shaped for a `LearnerConfig`."""
    return init(cfg.n_agents, cfg.image, cfg.latent, cfg.rnn_hidden, capacity)


def add(buffer: Replay, tr: Transition, enabled=True) -> Replay:
    """Write one step at the head; the oldest step is overwritten once full.

    `enabled` (a traced bool) False leaves the buffer as it was: the slot is rewritten with its
    own content and the head does not move. A run that must not advance (run.py halts a run
    whose loss went non-finite) uses it instead of selecting between two whole buffers, which
    would copy the buffer every step.
    """
    i = buffer.index
    cap = buffer.capacity
    gate = enabled is not True

    def put(store, value):
        value = jnp.asarray(value, store.dtype)
        if gate:
            value = jnp.where(enabled, value, jax.lax.dynamic_index_in_dim(store, i, keepdims=False))
        return jax.lax.dynamic_update_index_in_dim(store, value, i, axis=0)

    advance = jnp.asarray(enabled, jnp.int32) if gate else 1
    return Replay(
        frames=put(buffer.frames, tr.frames),
        latents=put(buffer.latents, tr.latents),
        actions=put(buffer.actions, tr.actions),
        carry=jax.tree.map(put, buffer.carry, tuple(tr.carry)),
        index=(i + advance) % cap,
        size=jnp.minimum(buffer.size + advance, cap),
    )


def n_valid_starts(buffer: Replay, seq_len: int):
    """How many start slots give seq_len + 1 consecutive, written, non-wrapping steps."""
    return jnp.maximum(buffer.size - seq_len, 0)


def can_sample(buffer: Replay, seq_len: int):
    return n_valid_starts(buffer, seq_len) > 0


def sample_indices(buffer: Replay, key, batch: int, seq_len: int):
    """Slot indices [batch, seq_len + 1], starts uniform over the valid start points.

    Steps are ordered oldest -> newest starting at slot (index - size) mod cap; a start at
    offset u from the oldest is valid when u + seq_len <= size - 1, so a sequence never runs
    past the newest step into the oldest one (the write head). Requires `can_sample`;
    otherwise the indices are meaningless (the caller gates the update).
    """
    cap = buffer.capacity
    oldest = (buffer.index - buffer.size) % cap
    u = jax.random.randint(key, (batch,), 0, jnp.maximum(n_valid_starts(buffer, seq_len), 1))
    return (oldest + u[:, None] + jnp.arange(seq_len + 1)[None, :]) % cap


def gather(buffer: Replay, idx) -> Batch:
    """The steps at slot indices idx [batch, L] as a world_model.Batch."""
    return Batch(
        frames=buffer.frames[idx],
        latents=buffer.latents[idx],
        actions=buffer.actions[idx],
        carry=jax.tree.map(lambda x: x[idx], buffer.carry),
    )


def sample(buffer: Replay, key, batch: int, seq_len: int) -> Batch:
    """`batch` sequences of seq_len + 1 consecutive steps (static shapes).

    This gathers every frame of every sequence (6.7 MB at the defaults) although the
    learner in "stored" mode reads one per sequence; a run loop that cares can call
    `sample_indices` and gather frames only where needed.
    """
    return gather(buffer, sample_indices(buffer, key, batch, seq_len))
