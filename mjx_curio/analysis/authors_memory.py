"""The curiosity the authors' code logs, rebuilt on a run's replay buffer, with its memory's
training pairs as that code forms them and as they belong together.

The authors' code logs as the curiosity of its figures the mean, over each update's replay batch of
16 transitions, of its memory's squared error predicting each agent's next latent one step from a
zero state (README, Fidelity), and trains that memory (an LSTM of 256 units with a linear head per
agent, mean squared error, Adam at 1e-3) and the self-models on the same batch. With two agents it
flattens the batch's views transition by transition (item k = transition k // 2, agent k % 2) and
then cuts that list into one block per agent (agent slot i, row j = item 16 i + j), while each
agent's actions stay in transition order (row j = transition j). So row j of agent slot i holds the
view of transition (16 i + j) // 2 seen by agent (16 i + j) % 2, beside the action agent i took in
transition j and, in the other slot, a view from another transition: the memory is trained to
predict each view's successor with actions, and the other agent's view, that belong to other
transitions (`authors_pairing`). With one agent the blocks are the batch itself, so nothing moves.

`logged_curiosity` trains such a memory, as the authors' code builds it, on the consecutive steps of a
run's replay buffer, each view encoded by the run's VAE at that checkpoint and drawn from its
posterior afresh at every update, as theirs does, and returns the logged number of every update
(before that update, as logged), with the authors' pairing or with every view beside its own
transition's actions and other view (`pairing_name="matched"`), and the posterior's floor, which
no memory can go below. The VAE is the run's, held fixed, and
the memory starts fresh on the buffer's last `capacity` steps: the difference the pairing makes, not
the authors' curve. Imports `sweeps` and `action_values`; JAX is imported when called.
"""

from __future__ import annotations

import functools

import numpy as np

from mjx_curio.analysis.action_values import replay_step
from mjx_curio.analysis.sweeps import Sweep, SweepError

PAIRINGS = ("authors", "matched")
BATCH = 16  # the authors' BATCH_SIZE: transitions per update
HIDDEN = 256  # their RNN_HIDDEN_DIM
LEARNING_RATE = 1e-3  # their LEARNING_RATE_RNN


def authors_pairing(batch: int, n_agents: int) -> tuple[np.ndarray, np.ndarray]:
    """(transition, agent), each int [n_agents, batch]: the batch transition and the agent whose view
    the authors' code puts in agent slot i, row j of its memory's input and target. The views are
    flattened transition by transition and cut into one block of `batch` per agent."""
    item = np.arange(n_agents)[:, None] * batch + np.arange(batch)[None, :]
    return item // n_agents, item % n_agents


def matched_pairing(batch: int, n_agents: int) -> tuple[np.ndarray, np.ndarray]:
    """(transition, agent) as `authors_pairing`, every view in its own transition's row and its own
    agent's slot."""
    return (np.broadcast_to(np.arange(batch)[None, :], (n_agents, batch)).copy(),
            np.broadcast_to(np.arange(n_agents)[:, None], (n_agents, batch)).copy())


def pairing(name: str, batch: int, n_agents: int) -> tuple[np.ndarray, np.ndarray]:
    """`authors_pairing` or `matched_pairing` by name (ValueError naming the choices otherwise)."""
    if name not in PAIRINGS:
        raise ValueError(f"pairing={name!r}: choose one of {', '.join(PAIRINGS)}")
    return (authors_pairing if name == "authors" else matched_pairing)(batch, n_agents)


def _torch_uniform(key, shape, fan_in):
    """PyTorch's default initialisation of LSTM and Linear weights and biases: U(-1/sqrt(fan_in), +)."""
    import jax

    bound = 1.0 / np.sqrt(fan_in)
    return jax.random.uniform(key, shape, minval=-bound, maxval=bound)


def init_memory(key, latent: int, n_actions: int, n_agents: int, hidden: int = HIDDEN) -> dict:
    """The authors' memory: one LSTM layer on every agent's (latent, action) side by side, a linear
    head per agent onto its next latent. Actions one-hot (theirs: a 4-vector of the same seven). It
    only ever steps from a zero state, where the recurrent weights multiply zeros: they are left out."""
    import jax

    k = jax.random.split(key, 5)
    n_in = n_agents * (latent + n_actions)
    return {"w_ih": _torch_uniform(k[0], (n_in, 4 * hidden), hidden),
            # PyTorch's LSTM has two bias vectors, each drawn so; only their sum acts.
            "b": _torch_uniform(k[1], (4 * hidden,), hidden) + _torch_uniform(k[2], (4 * hidden,), hidden),
            "head_w": _torch_uniform(k[3], (n_agents, hidden, latent), hidden),
            "head_b": _torch_uniform(k[4], (n_agents, latent), hidden)}


def predict(params: dict, z, onehot):
    """One LSTM step from a zero state (h = c = 0, as the authors' update starts every row), then each
    agent's head. z [B, agents, Z], onehot [B, agents, A] -> predicted next latents [B, agents, Z]."""
    import jax
    import jax.numpy as jnp

    x = jnp.concatenate([z, onehot], -1).reshape(z.shape[0], -1)  # agent 0's (z, a), then agent 1's
    i, _, g, o = jnp.split(x @ params["w_ih"] + params["b"], 4, -1)  # PyTorch's gate order i, f, g, o
    h = jax.nn.sigmoid(o) * jnp.tanh(jax.nn.sigmoid(i) * jnp.tanh(g))  # the forget gate scales c0 = 0
    return jnp.einsum("bh,ahz->baz", h, params["head_w"]) + params["head_b"]


@functools.lru_cache(maxsize=None)
def _trainer(updates: int, batch: int, n_agents: int, n_actions: int, name: str):
    """jit(train(params, key, mu, sigma, actions, now, next) -> logged [updates, agents]): `updates`
    Adam steps of the authors' memory, each on `batch` transitions drawn without replacement from
    (now[k], next[k]), buffer positions of consecutive steps."""
    import jax
    import jax.numpy as jnp
    import optax

    trans, agent = (jnp.asarray(x) for x in pairing(name, batch, n_agents))
    opt = optax.adam(LEARNING_RATE)

    def loss(params, z_in, z_out, onehot):
        err = jnp.square(predict(params, z_in, onehot) - z_out).mean(-1)  # [B, agents]
        per_agent = err.mean(0)  # each head's mean squared error: the number logged per agent
        return per_agent.sum(), per_agent

    def train(params, key, mu, sigma, actions, now, nxt):
        def update(carry, k):
            params, state = carry
            k_rows, k_now, k_next = jax.random.split(k, 3)
            rows = jax.random.choice(k_rows, now.shape[0], (batch,), replace=False)
            t_now, t_next = now[rows], nxt[rows]
            # Each view drawn from its posterior, then laid out as the pairing lays it: slot i, row j.
            z_t = mu[t_now] + sigma[t_now] * jax.random.normal(k_now, sigma[t_now].shape)  # [B, agents, Z]
            z_n = mu[t_next] + sigma[t_next] * jax.random.normal(k_next, sigma[t_next].shape)
            z_in, z_out = z_t[trans, agent].swapaxes(0, 1), z_n[trans, agent].swapaxes(0, 1)
            onehot = jax.nn.one_hot(actions[t_now], n_actions)  # row j, slot i: transition j's agent i
            (_, logged), grads = jax.value_and_grad(loss, has_aux=True)(params, z_in, z_out, onehot)
            change, state = opt.update(grads, state, params)
            return (optax.apply_updates(params, change), state), logged

        _, logged = jax.lax.scan(update, (params, opt.init(params)), jax.random.split(key, updates))
        return logged

    return jax.jit(train)


@functools.lru_cache(maxsize=None)
def _encoder(cfg):
    import jax

    from mjx_curio import world_model as wm

    return jax.jit(lambda vae, stats, frames: wm.encode(cfg, vae, frames, stats))


def _posteriors(sweep: Sweep, run_index: int, step: int, frames: np.ndarray, chunk: int = 500):
    """(mu, sigma), each float32 [steps, agents, Z]: the run's VAE at `step` on `frames`
    [steps, agents, H, W, 3], `chunk` steps at a time (every chunk one shape: one compilation)."""
    f = _encoder(sweep.learner_config())
    params = sweep.params(step, run_index)
    n = frames.shape[0]
    pad = -n % chunk
    padded = np.concatenate([frames, np.repeat(frames[-1:], pad, axis=0)]) if pad else frames
    parts = [f(params["vae"], params["vae_stats"], padded[k:k + chunk]) for k in range(0, n + pad, chunk)]
    mu = np.concatenate([np.asarray(p[0]) for p in parts])[:n]
    logvar = np.concatenate([np.asarray(p[1]) for p in parts])[:n]
    return mu, np.exp(0.5 * logvar)


def logged_curiosity(sweep: Sweep, run: int | str = 0, step: int | None = None, pairing_name: str = "authors",
                     updates: int = 2500, seed: int = 0, batch: int = BATCH) -> dict:
    """The curiosity the authors' code would log at each of `updates` updates of a fresh authors'
    memory trained on run `run`'s replay buffer at checkpoint `step` (default: the newest that kept
    it), its views encoded by the run's VAE there, with `pairing_name` ("authors" or "matched").
    `seed` picks the memory's initialisation, batches and posterior draws. Returns {"logged": float
    [updates, agents], "floor": the mean posterior variance over the buffer's views and latent
    dimensions, what a memory that predicted every next posterior mean exactly would still log}."""
    import jax
    import jax.numpy as jnp

    if pairing_name not in PAIRINGS:  # before any work
        raise ValueError(f"pairing_name={pairing_name!r}: choose one of {', '.join(PAIRINGS)}")
    if not (isinstance(updates, (int, np.integer)) and updates >= 1):
        raise ValueError(f"updates={updates!r}: want a whole number >= 1")
    r = sweep.run(run)
    step = replay_step(sweep, step)
    rp = sweep.restore_replay(step, keys=("frames", "actions", "index", "size"))
    i = r.index
    size, head, cap = int(rp["size"][i]), int(rp["index"][i]), rp["actions"].shape[1]
    if size < batch + 1:
        raise SweepError(f"{sweep.path}: run {r.name}'s replay buffer at step {step} holds {size} step(s); "
                         f"want at least {batch + 1} for batches of {batch} transitions")
    order = (head - size + np.arange(size)) % cap  # oldest first; below `size` until the ring wraps
    mu, sigma = _posteriors(sweep, i, step, rp["frames"][i, :size] if size < cap else rp["frames"][i])
    cfg = sweep.learner_config()
    n_agents = mu.shape[1]
    key_init, key_train = jax.random.split(jax.random.PRNGKey(seed))
    params = init_memory(key_init, cfg.latent, cfg.n_actions, n_agents)
    train = _trainer(int(updates), int(batch), n_agents, cfg.n_actions, pairing_name)
    logged = train(params, key_train, jnp.asarray(mu), jnp.asarray(sigma), jnp.asarray(rp["actions"][i]),
                   jnp.asarray(order[:-1]), jnp.asarray(order[1:]))
    return {"logged": np.asarray(logged, np.float64), "floor": float(np.mean(np.square(sigma, dtype=np.float64)))}
