"""One curious-agent run of the paper as pure functions, and many runs as one program.

A run's whole state is a `RunState` pytree. One agent step (`act`) is: predict each action's
curiosity with every agent's self-model, let each agent's policy pick, store the step in replay,
advance the shared MDN-RNN memory, step the arena with all actions at once, render every agent's
view, encode it, and score curiosity (eq. 3) against the MDN-RNN's prediction. Every
`update_every` steps `learn` trains the VAE, the MDN-RNN and every self-model from one replay
sample (paper 3.2-3.3). `run_chunk` is a `lax.scan` of these and returns the chunk's
metrics already reduced to windows of `metrics_every` steps.

A sweep is a `RunState` with a leading runs axis. `sweep_chunk` advances every run; how the runs
axis is traversed is `RunConfig.runs_loop`:
- "map": one run after another inside the compiled program (an in-place `fori_loop` over the
  runs axis). Every run then executes exactly the program of a run alone, so a run's results are
  bit-identical alone and inside any sweep on one device. It is also the faster
  choice on a CPU: there each run's convolutions are XLA convolutions, while under vmap their
  per-run kernels make them batched matmuls (nets.conv2x2), which XLA CPU runs slower for the
  encoder (`python -m mjx_curio.bench what=sweep` compares the two loops).
- "vmap": all runs in lockstep, batched. What an accelerator wants; results agree with a run
  alone to float rounding (about 1e-6 after one update), so trajectories can part after many
  steps where an argmax flips.
Across devices the runs axis is sharded with `shard_map` (program.py): each device advances its
own runs, with no communication, so a run's random stream, policy and settings are the same on
any number of devices. Its float results are not bit for bit: the sharded program is another
compiled program (measured: even against a one-device sweep of exactly the runs one device
holds), whose rounding may differ in the last bit (MJX's contact solver among others), and such
differences grow along a chaotic run.

Ordering within a step t (carry_t = LSTM state before step t, z_t = encoding of o_t):
    q_t = self-models(z_t, h_t); a_t = policy(q_t); replay <- (o_t, z_t, a_t, carry_t)
    carry_t+1, mix_t = MDN-RNN(carry_t, z_t, a_t); world_t+1 = arena.step(world_t, a_t)
    o_t+1 = render(world_t+1); z_t+1 = latent(o_t+1); r_t = ||z_t+1 - E[mix_t]||^2
A frame's latent z is a sample of the VAE's posterior (or its mean, `LearnerConfig.z`) and the
curiosity r the mean (or sum, `LearnerConfig.curiosity`) of the squared error over the latent
dimensions. The sampling noise comes from the run's own key stream, so a run stays a pure
function of its seed.
"""

from __future__ import annotations

import functools
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from mjx_curio import arena as arena_lib
from mjx_curio import policies
from mjx_curio import replay as replay_lib
from mjx_curio import world_model as wm
from mjx_curio.config import RUNS_LOOPS, ConfigError, RunConfig  # noqa: F401  (RunConfig: part of this module's API)

N_VIEW = len(arena_lib.OBJECTS) + 1  # view fractions: the four objects, then the other agent


class RunState(NamedTuple):
    env: arena_lib.EnvState
    learner: wm.LearnerState
    replay: replay_lib.Replay
    carry: tuple  # (c, h) LSTM state before the current step, each [rnn_hidden]
    frames: jax.Array  # uint8 [n_agents, H, W, 3], the current observation o_t
    z: jax.Array  # f32 [n_agents, latent], its latent (a posterior sample or the mean: LearnerConfig.z)
    counts: jax.Array  # int32 [n_agents, n_actions], UCB's N(a)
    key: jax.Array  # uint32 [2], this run's random stream
    step: jax.Array  # int32, agent steps taken
    policy: policies.PolicyParams
    halted: jax.Array  # bool: a loss or the physics went non-finite; the run is frozen at its last good state
    halted_step: jax.Array  # int32, the step at which it halted, -1 if running


# ------------------------------------------------------------------------------ one run


def init_run(cfg: RunConfig, key: jax.Array, policy: policies.PolicyParams) -> RunState:
    """A run at step 0: the arena reset, fresh networks, the first views rendered and encoded.
    `key` (a raw uint32[2] PRNG key) alone decides everything random in the run."""
    arena = cfg.arena
    # k_z: the first views' latent noise. Splits are prefix-stable (JAX's default threefry), so
    # the other three keys are those of the three-way split used before k_z existed.
    k_env, k_learn, k_run, k_z = jax.random.split(key, 4)
    env = arena.reset(k_env)
    learner = wm.init_learner(cfg.learner, k_learn)
    frames, _ = arena.render(env)
    z = wm.latent(cfg.learner, learner.vae, frames, k_z, learner.vae_stats)
    lc = cfg.learner
    return RunState(
        env=env,
        learner=learner,
        replay=replay_lib.init_for(lc, cfg.buffer),
        carry=wm.initial_carry(lc),
        frames=frames,
        z=z,
        counts=jnp.zeros((cfg.n_agents, lc.n_actions), jnp.int32),
        key=k_run,
        step=jnp.zeros((), jnp.int32),
        policy=policy,
        halted=jnp.zeros((), bool),
        halted_step=jnp.full((), -1, jnp.int32),
    )


def act(cfg: RunConfig, s: RunState) -> tuple[RunState, dict]:
    """One agent step of every agent at once. Returns the new state and this step's metrics.

    A halted run does not move: its small state is selected back and its replay buffer is left
    untouched (`replay.add(..., enabled=False)`); its metrics are masked by `reduce_windows`.
    A physics step that leaves a non-finite position or velocity (the simulation diverged) halts
    the run the same way, at its last finite state: that step is not taken."""
    arena, lc = cfg.arena, cfg.learner
    k_policy, k_next, k_z = jax.random.split(s.key, 3)  # prefix-stable: k_policy, k_next as before k_z
    q = wm.predict_curiosity(lc, s.learner.self_model, s.z, s.carry[1])  # [n, A]
    a = policies.select_agents(s.policy, q, k_policy, s.counts, s.step)
    carry, mix = wm.rnn_step(lc, s.learner.rnn, s.carry, s.z, a)
    env = arena.step(s.env, a)
    diverged = ~(jnp.all(jnp.isfinite(env.data.qpos)) & jnp.all(jnp.isfinite(env.data.qvel)))
    go = ~s.halted & ~diverged
    replay = replay_lib.add(s.replay, replay_lib.Transition(s.frames, s.z, a, s.carry), enabled=go)
    frames, geom_id = arena.render(env)
    z, spread = wm.latent_and_spread(lc, s.learner.vae, frames, k_z, s.learner.vae_stats)  # the next step's input and this step's target
    reward = wm.curiosity(lc, z, mix)  # [n]
    metrics = {
        "curiosity": reward,
        "curiosity_spread": spread,
        "predicted": jnp.take_along_axis(q, a[:, None], axis=1)[:, 0],
        "action": a,
        "contact_object": env.touch,
        "contact_agent": env.touch_agent,
        "view_fraction": view_fractions(arena, geom_id),
        "taken": go,
    }
    moved = (env, carry, frames, z, policies.update_counts_agents(s.counts, a), k_next, s.step + 1)
    kept = (s.env, s.carry, s.frames, s.z, s.counts, s.key, s.step)
    env, carry, frames, z, counts, key, step = jax.tree.map(lambda n, o: jnp.where(go, n, o), moved, kept)
    # Poses of the state kept: a halted run's stay those of its last good state, never a diverged step's.
    xy, yaw = arena.agent_pose(env)
    metrics["agent_pose"] = jnp.concatenate([xy, yaw[:, None]], axis=1)
    metrics["object_pos"] = arena.object_pos(env)
    halt_now = ~s.halted & diverged
    new = s._replace(env=env, replay=replay, carry=carry, frames=frames, z=z, counts=counts, key=key, step=step,
                     halted=s.halted | halt_now, halted_step=jnp.where(halt_now, s.step, s.halted_step))
    return new, metrics


def view_fractions(arena: arena_lib.Arena, geom_id: jax.Array) -> jax.Array:
    """[n_agents, 5]: share of each agent's pixels showing each object, then the other agent."""
    objects = jnp.asarray(arena.object_geoms)
    frac = jnp.mean(geom_id[:, :, :, None] == objects, axis=(1, 2))  # [n, 4]
    if arena.n_agents == 1:
        other = jnp.zeros((1, 1), jnp.float32)
    else:
        others = jnp.asarray(arena.agent_geoms[::-1].copy())  # agent i sees agent 1 - i
        other = jnp.mean(geom_id == others[:, None, None], axis=(1, 2))[:, None]
    return jnp.concatenate([frac, other], axis=1).astype(jnp.float32)


def learn(cfg: RunConfig, s: RunState) -> tuple[RunState, dict]:
    """One learner update from replay, once the buffer holds a whole sequence.

    A non-finite loss halts the run: the update is discarded and the run stays frozen at its
    last good state from then on (checkpoints keep that state)."""
    lc = cfg.learner
    k_sample, k_update, k_next, k_z = jax.random.split(s.key, 4)  # prefix-stable, as in act

    def update(s):
        batch = replay_lib.sample(s.replay, k_sample, lc.batch, lc.seq_len)
        learner, m = wm.learner_update(lc, s.learner, batch, k_update)
        finite = jnp.all(jnp.stack([jnp.all(jnp.isfinite(v)) for v in jax.tree.leaves(m)]))
        learner = jax.tree.map(lambda new, old: jnp.where(finite, new, old), learner, s.learner)
        # The current view's latent in the updated VAE's space, so the next step's replay entry,
        # memory input and curiosity all use one encoder.
        z = jnp.where(finite, wm.latent(lc, learner.vae, s.frames, k_z, learner.vae_stats), s.z)
        m = {k: jnp.where(finite, v, jnp.nan) for k, v in m.items()}
        m["updated"] = finite.astype(jnp.int32)
        m["non_finite"] = (~finite).astype(jnp.int32)
        return s._replace(learner=learner, z=z), m

    def skip(s):
        return s, _no_update(cfg)

    ready = replay_lib.can_sample(s.replay, lc.seq_len) & ~s.halted
    s, m = lax.cond(ready, update, skip, s)
    halt_now = m["non_finite"] > 0
    s = s._replace(
        key=k_next,
        halted=s.halted | halt_now,
        halted_step=jnp.where(halt_now & (s.halted_step < 0), s.step, s.halted_step),
    )
    return s, m


def _no_update(cfg: RunConfig) -> dict:
    nan = jnp.full((), jnp.nan, jnp.float32)
    m = {k: nan for k in ("vae_loss", "recon", "kl", "nll", "self_loss", "curiosity")}
    m["self_loss_agents"] = jnp.full((cfg.n_agents,), jnp.nan, jnp.float32)
    m["curiosity_agents"] = jnp.full((cfg.n_agents,), jnp.nan, jnp.float32)
    m["updated"] = jnp.zeros((), jnp.int32)
    m["non_finite"] = jnp.zeros((), jnp.int32)
    return m


def run_chunk(cfg: RunConfig, s: RunState, n_steps: int) -> tuple[RunState, dict]:
    """`n_steps` agent steps (a multiple of metrics_every) of one run: `update_every` acting steps
    then one learner update, scanned. Returns the state and the chunk's metrics in windows
    (`reduce_windows`)."""
    if n_steps % cfg.metrics_every:
        raise ConfigError(f"a chunk of {n_steps} steps must be a multiple of metrics_every={cfg.metrics_every}")
    def period(s, _):
        s, step_m = lax.scan(lambda s, _: act(cfg, s), s, None, length=cfg.update_every)
        s, learn_m = learn(cfg, s)
        return s, (step_m, learn_m)

    s, (step_m, learn_m) = lax.scan(period, s, None, length=n_steps // cfg.update_every)
    step_m = jax.tree.map(lambda x: x.reshape((n_steps,) + x.shape[2:]), step_m)
    return s, reduce_windows(cfg, step_m, learn_m)


_ROTATIONS = (arena_lib.ACTIONS.index("rotate_left"), arena_lib.ACTIONS.index("rotate_right"))


def count_reversals(actions: jax.Array, ran: jax.Array) -> jax.Array:
    """Per window and agent, the steps at which the agent turned the other way than at the step
    before, both steps in the window and taken. actions int [T, agents]; ran bool [W, T / W]."""
    a = actions.reshape(ran.shape + actions.shape[1:])  # [W, w, agents]
    left, right = _ROTATIONS
    turned_back = ((a[:, 1:] == left) & (a[:, :-1] == right)) | ((a[:, 1:] == right) & (a[:, :-1] == left))
    both_ran = (ran[:, 1:] & ran[:, :-1])[..., None]
    return jnp.sum(turned_back & both_ran, axis=1).astype(jnp.int32)


def reduce_windows(cfg: RunConfig, step_m: dict, learn_m: dict) -> dict:
    """Per-step metrics [T, ...] and per-update metrics [T / update_every, ...] -> windows of
    `metrics_every` steps. See metrics.SCHEMA for the meaning of every output."""
    w = cfg.metrics_every
    per = w // cfg.update_every

    def win(x, k=w):
        return x.reshape((x.shape[0] // k, k) + x.shape[1:])

    ran = win(step_m["taken"], w)  # [W, w]: step was actually taken (not halted)
    n_ran = jnp.sum(ran, axis=1)  # [W]

    def sum_steps(x):  # sum over the steps taken in each window (a halted step's NaN left out)
        x = win(x)
        r = ran.reshape(ran.shape + (1,) * (x.ndim - 2))
        return jnp.sum(jnp.where(r, x, jnp.zeros((), x.dtype)), axis=1)

    def per_step(total, n):  # total / n where n > 0, NaN elsewhere
        n = n.reshape(n.shape + (1,) * (total.ndim - n.ndim))
        return jnp.where(n > 0, total / jnp.maximum(n, 1), jnp.nan)

    def mean_steps(x):  # mean over the steps taken in each window, NaN if none
        return per_step(sum_steps(x.astype(jnp.float32)), n_ran)

    def count_steps(x):
        return sum_steps(x.astype(jnp.int32))

    def cov_steps(x, y):  # covariance over the steps taken in each window (population), NaN if none
        mx, my = jnp.repeat(mean_steps(x), w, axis=0), jnp.repeat(mean_steps(y), w, axis=0)
        return mean_steps((x - mx) * (y - my))

    def last(x):
        return win(x)[:, -1]

    a = step_m["action"]
    c, q = step_m["curiosity"], step_m["predicted"]
    took = jax.nn.one_hot(a, cfg.learner.n_actions, dtype=jnp.int32)  # [T, agents, actions]
    counts = count_steps(took)
    out = {
        "predicted_var": cov_steps(q, q),
        "curiosity_var": cov_steps(c, c),
        "predicted_curiosity_cov": cov_steps(q, c),
        "curiosity_by_action": per_step(sum_steps(c[..., None] * took), counts),
        "rotation_reversals": count_reversals(a, ran),
        "curiosity": mean_steps(step_m["curiosity"]),
        "curiosity_sample": jnp.where(ran[:, -1][:, None], last(step_m["curiosity"]), jnp.nan),
        "curiosity_spread": mean_steps(step_m["curiosity_spread"]),
        "predicted": mean_steps(step_m["predicted"]),
        "action_counts": counts,
        "contact_object": count_steps(step_m["contact_object"]),
        "contact_agent": count_steps(step_m["contact_agent"]),
        "view_fraction": mean_steps(step_m["view_fraction"]),
        "agent_pose": last(step_m["agent_pose"]),
        "object_pos": last(step_m["object_pos"]),
        "steps_taken": n_ran.astype(jnp.int32),
    }
    upd = learn_m["updated"]
    u = win(upd, per)  # [W, per]
    n_upd = jnp.sum(u, axis=1)
    learned = {name: name for name in ("vae_loss", "recon", "kl", "nll", "self_loss", "self_loss_agents")}
    for name, source in {**learned, "batch_curiosity": "curiosity_agents"}.items():
        x = win(learn_m[source], per)
        m = u.reshape(u.shape + (1,) * (x.ndim - 2)) > 0
        total = jnp.sum(jnp.where(m, x, 0.0), axis=1)
        n = n_upd.reshape(n_upd.shape + (1,) * (x.ndim - 2))
        out[name] = jnp.where(n > 0, total / jnp.maximum(n, 1), jnp.nan)
    out["updates"] = n_upd.astype(jnp.int32)
    out["non_finite"] = jnp.sum(win(learn_m["non_finite"], per), axis=1).astype(jnp.int32)
    return out


# ------------------------------------------------------------------------------ many runs


def map_runs_inplace(fn, xs: Any):
    """fn: state -> (state, out) applied to every run of xs (leading runs axis), one run after
    another. A scan over run indices whose carry is the whole stacked state, read and written
    one run at a time with dynamic slices, so with a donated input no second copy of the sweep
    state exists; the per-run outputs are stacked by the scan. `fn` is traced once."""
    n = jax.tree.leaves(xs)[0].shape[0]

    def body(xs, i):
        xi = jax.tree.map(lambda x: lax.dynamic_index_in_dim(x, i, keepdims=False), xs)
        xo, yo = fn(xi)
        return jax.tree.map(lambda buf, v: lax.dynamic_update_index_in_dim(buf, v, i, 0), xs, xo), yo

    return lax.scan(body, xs, jnp.arange(n))


def init_runs(cfg: RunConfig, keys: jax.Array, policy: policies.PolicyParams) -> RunState:
    """RunStates for keys [R, 2] and policy settings with a leading R axis."""
    fn = lambda kp: init_run(cfg, *kp)  # noqa: E731
    if cfg.runs_loop == "vmap":
        return jax.vmap(fn)((keys, policy))
    return lax.map(fn, (keys, policy))


def sweep_chunk(cfg: RunConfig, states: RunState, n_steps: int) -> tuple[RunState, dict]:
    """Advance every run of `states` (leading runs axis) by n_steps; metrics [R, windows, ...]."""
    fn = functools.partial(run_chunk, cfg, n_steps=n_steps)
    if cfg.runs_loop == "vmap":
        return jax.vmap(fn)(states)
    return map_runs_inplace(fn, states)


def split_replay(states: RunState) -> tuple[RunState, replay_lib.Replay]:
    """(state without its replay buffer, the buffer): the two are checkpointed separately."""
    return states._replace(replay=None), states.replay


def with_replay(states: RunState, replay: replay_lib.Replay) -> RunState:
    return states._replace(replay=replay)


def key_for_seed(seed: int) -> np.ndarray:
    """A run's key: from its seed only, so a seed means the same run in every sweep."""
    return np.asarray(jax.random.key_data(jax.random.key(int(seed), impl="threefry2x32")), np.uint32)
