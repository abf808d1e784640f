"""Losses, curiosity and the one-call learner update of the shared world model.

Pure functions of explicit pytrees. `cfg` (a frozen, hashable `LearnerConfig`) is always the
first argument and is static under `jax.jit` (`jax.jit(learner_update, static_argnums=0)`).

Acting loop, one step t, as the run loop is expected to use these pieces
(carry_t = (c, h) is the LSTM state *before* it has seen step t):

    z_t        = latent(cfg, state.vae, frames_t, key)            # [n_agents, Z], see cfg.z
    q          = predict_curiosity(cfg, state.self_model, z_t, carry_t[1])   # [n_agents, 7]
    a_t        = policies.select_agents(...)                      # [n_agents]
    buffer     = replay.add(buffer, Transition(frames_t, z_t, a_t, carry_t))
    carry_t+1, mix_t = rnn_step(cfg, state.rnn, carry_t, z_t, a_t)
    ... physics, render, latent -> z_t+1
    r_t        = curiosity(cfg, z_t+1, mix_t)                     # [n_agents], eq. 3

The self-model sees (z_t, h_t) with h_t the hidden state before step t, because it must
score every candidate action before one is chosen (the LSTM output after step t depends
on a_t). `learner_update` trains it the same way.
"""

from __future__ import annotations

import functools
import math
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import optax

from mjx_curio.config import LearnerConfig
from mjx_curio.nets import MDNRNN, VAE, Mixture, SelfModel, init_params

Carry = tuple  # (c, h), each [..., rnn_hidden]


class Nets(NamedTuple):
    vae: VAE
    rnn: MDNRNN
    self_model: SelfModel


class LearnerState(NamedTuple):
    """Everything the learner owns. A pytree; add a leading axis to hold many runs."""

    vae: Any  # VAE params
    vae_opt: Any  # optax Adam state
    rnn: Any  # MDN-RNN params
    rnn_opt: Any
    self_model: Any  # per-agent self-model params, every leaf [n_agents, ...]
    self_opt: Any  # per-agent Adam states, every leaf [n_agents, ...]
    step: jax.Array  # int32, number of updates done
    # The VAE's batch-normalisation running averages (vae_layers="authors"): {layer: {"mean",
    # "var"}}. Empty, no leaves, for the default layers, so their checkpoints keep one layout.
    vae_stats: Any = ()


class Batch(NamedTuple):
    """A replay sample: `batch` sequences of seq_len + 1 consecutive steps."""

    frames: jax.Array  # uint8 [B, T+1, n_agents, H, W, 3]
    latents: jax.Array  # f32 [B, T+1, n_agents, Z] (as computed when acting)
    actions: jax.Array  # int32 [B, T+1, n_agents]
    carry: Carry  # (c, h), each f32 [B, T+1, rnn_hidden]: LSTM state before each step


@functools.lru_cache(maxsize=None)
def make_nets(cfg: LearnerConfig) -> Nets:
    return Nets(
        vae=VAE(cfg.image, cfg.latent, cfg.vae_channels, cfg.dec_channels, cfg.vae_layers),
        rnn=MDNRNN(cfg.n_agents, cfg.latent, cfg.mixtures, cfg.rnn_hidden, cfg.n_actions),
        self_model=SelfModel(cfg.self_hidden, cfg.n_actions),
    )


@functools.lru_cache(maxsize=None)
def optimizer(cfg: LearnerConfig) -> optax.GradientTransformation:
    return adam(cfg.lr)  # Adam 1e-3 for all three models, as the authors' code (docs/paper_setup.md)


class AdamState(NamedTuple):
    count: jax.Array  # int32: updates done
    mu: Any  # first moments, like the params
    nu: Any  # second moments


def adam(lr: float, b1: float = 0.9, b2: float = 0.999, eps: float = 1e-8) -> optax.GradientTransformation:
    """Adam (Kingma & Ba), the same maths as `optax.adam`, written in their "efficient" form:
    the bias corrections fold into one scalar step size and a scaled epsilon,
        p <- p - lr * sqrt(1 - b2^t) / (1 - b1^t) * m / (sqrt(v) + eps * sqrt(1 - b2^t)),
    which equals lr * m_hat / (sqrt(v_hat) + eps) exactly in real arithmetic. Why not optax's:
    its per-element divisions by the bias corrections are what XLA's algebraic simplifier
    reassociates, differently in differently fused programs, so the same run rounded differently
    on one device and sharded over two. Here no array is divided by a scalar, and nothing is
    left to reassociate."""

    def init(params):
        zeros = lambda: jax.tree.map(jnp.zeros_like, params)  # noqa: E731
        return AdamState(jnp.zeros((), jnp.int32), zeros(), zeros())

    def update(grads, state, params=None):
        del params
        count = state.count + 1
        mu = jax.tree.map(lambda m, g: b1 * m + (1.0 - b1) * g, state.mu, grads)
        nu = jax.tree.map(lambda v, g: b2 * v + (1.0 - b2) * jnp.square(g), state.nu, grads)
        t = count.astype(jnp.float32)
        root_c2 = jnp.sqrt(1.0 - jnp.power(jnp.float32(b2), t))
        step = -lr * root_c2 / (1.0 - jnp.power(jnp.float32(b1), t))
        eps_hat = eps * root_c2
        updates = jax.tree.map(lambda m, v: step * (m / (jnp.sqrt(v) + eps_hat)), mu, nu)
        return updates, AdamState(count, mu, nu)

    return optax.GradientTransformation(init, update)


# ----------------------------------------------------------------------------------------
# Initialisation
# ----------------------------------------------------------------------------------------


def initial_carry(cfg: LearnerConfig) -> Carry:
    z = jnp.zeros((cfg.rnn_hidden,), jnp.float32)
    return (z, z)


@functools.partial(jax.jit, static_argnums=0)  # eager flax init dispatches op by op: slow
def init_learner(cfg: LearnerConfig, key: jax.Array) -> LearnerState:
    nets = make_nets(cfg)
    kv, kr, ks, kz = jax.random.split(key, 4)
    frames = jnp.zeros((1, cfg.image, cfg.image, 3), jnp.uint8)
    vae = init_params(nets.vae, kv, frames, kz)
    z = jnp.zeros((cfg.n_agents, cfg.latent), jnp.float32)
    a = jnp.zeros((cfg.n_agents,), jnp.int32)
    rnn = init_params(nets.rnn, kr, initial_carry(cfg), z, a)
    # each agent its own self-model: independent inits stacked along a leading agent axis
    h = jnp.zeros((cfg.rnn_hidden,), jnp.float32)
    self_model = jax.vmap(lambda k: init_params(nets.self_model, k, z[0], h))(
        jax.random.split(ks, cfg.n_agents)
    )
    opt = optimizer(cfg)
    return LearnerState(
        vae_stats=initial_vae_stats(cfg),
        vae=vae,
        vae_opt=opt.init(vae),
        rnn=rnn,
        rnn_opt=opt.init(rnn),
        self_model=self_model,
        self_opt=jax.vmap(opt.init)(self_model),  # per-agent optimiser state
        step=jnp.zeros((), jnp.int32),
    )


def initial_vae_stats(cfg: LearnerConfig):
    """The VAE's batch-normalisation running averages before any training (means 0, variances
    1, as PyTorch and flax start them), or () for layers without batch normalisation."""
    if cfg.vae_layers == "hs":
        return ()
    frames = jnp.zeros((1, cfg.image, cfg.image, 3), jnp.uint8)
    shapes = jax.eval_shape(lambda: make_nets(cfg).vae.init(jax.random.PRNGKey(0), frames, jax.random.PRNGKey(0)))
    return jax.tree_util.tree_map_with_path(
        lambda path, a: (jnp.ones if path[-1].key == "var" else jnp.zeros)(a.shape, a.dtype), shapes["batch_stats"])


def apply_vae(cfg: LearnerConfig, vae_params, stats, *args, method=None, train: bool = False):
    """The VAE on `args` -> (its output, the running averages after it).

    With batch normalisation (vae_layers="authors") `train=True` normalises by the batch's own
    statistics and folds them into the running averages, as PyTorch's train mode does; otherwise
    the running averages normalise and come back unchanged. Layers without it ignore `stats`."""
    net = make_nets(cfg).vae
    if cfg.vae_layers == "hs":
        return net.apply({"params": vae_params}, *args, method=method), stats
    if not jax.tree.leaves(stats):
        raise ValueError("vae_layers=authors: the VAE needs its batch-normalisation running averages "
                         "(LearnerState.vae_stats, or a sweep's params(...)['vae_stats'])")
    variables = {"params": vae_params, "batch_stats": stats}
    if not train:
        return net.apply(variables, *args, method=method, train=False), stats
    out, updated = net.apply(variables, *args, method=method, train=True, mutable=["batch_stats"])
    return out, updated["batch_stats"]


# ----------------------------------------------------------------------------------------
# Acting-time pieces
# ----------------------------------------------------------------------------------------


def encode(cfg: LearnerConfig, vae_params, frames, stats=()):
    """frames uint8 [..., H, W, 3] -> (mu, logvar), each [..., latent]. `stats`: the VAE's
    running averages (LearnerState.vae_stats), which batch normalisation normalises by."""
    return encode_and_stats(cfg, vae_params, frames, stats)[0]


def encode_and_stats(cfg: LearnerConfig, vae_params, frames, stats=(), train: bool = False):
    """`encode`, and the running averages after it: with `train`, batch normalisation uses the
    statistics of all these frames together and folds them in (`apply_vae`)."""
    lead = frames.shape[:-3]
    flat = frames.reshape((-1,) + frames.shape[-3:])
    (mu, logvar), stats = apply_vae(cfg, vae_params, stats, flat, method=VAE.encode, train=train)
    return (mu.reshape(lead + (cfg.latent,)), logvar.reshape(lead + (cfg.latent,))), stats


def decode(cfg: LearnerConfig, vae_params, z, stats=()):
    """z [..., latent] -> images float32 [..., H, W, 3] in [0, 1]."""
    lead = z.shape[:-1]
    img, _ = apply_vae(cfg, vae_params, stats, z.reshape(-1, cfg.latent), method=VAE.decode)
    return img.reshape(lead + img.shape[1:])


def sample_latent(key, mu, logvar):
    """z ~ N(mu, exp(logvar)), reparameterised: mu + sigma * eps with eps ~ N(0, I) from `key`."""
    return mu + jnp.exp(0.5 * logvar) * jax.random.normal(key, mu.shape, mu.dtype)


def latent(cfg: LearnerConfig, vae_params, frames, key, stats=()):
    """The latent of frames uint8 [..., H, W, 3] as the acting loop and the memory use it,
    [..., latent]: a reparameterised sample of the posterior q(z|o) = N(mu, sigma^2) drawn
    with `key` (cfg.z == "sample", the paper's z ~ q(z|o) and the authors' code), or its mean
    mu (cfg.z == "mean"; `key` unused). `stats`: as `encode`'s."""
    return latent_and_spread(cfg, vae_params, frames, key, stats)[0]


def latent_and_spread(cfg: LearnerConfig, vae_params, frames, key, stats=()):
    """`latent`, and the posterior's variance sigma^2 reduced over the latent dimensions as
    `curiosity` reduces them, [...]: 0 under z == "mean".

    With z = mu + sigma * eps, the curiosity of this latent has the expectation over eps
    ||mu - E[z_hat]||^2 + sum(sigma^2) (or both means over the dimensions): the spread is the part
    no prediction can remove, so curiosity minus spread is, in expectation, the MDN-RNN's error
    against the posterior mean."""
    mu, logvar = encode(cfg, vae_params, frames, stats)
    if cfg.z != "sample":
        return mu, jnp.zeros(mu.shape[:-1], mu.dtype)
    return sample_latent(key, mu, logvar), _over_latent(cfg, jnp.exp(logvar))


def rnn_step(cfg: LearnerConfig, rnn_params, carry: Carry, z, a):
    """One MDN-RNN step: carry (c, h) [hidden], z [n_agents, Z], a int [n_agents]
    -> (new carry, Mixture over z_{t+1}, fields [n_agents, Z, K])."""
    return make_nets(cfg).rnn.apply({"params": rnn_params}, carry, z, a)


def rnn_sequence(cfg: LearnerConfig, rnn_params, carry: Carry, z, a):
    """Scan the MDN-RNN over one sequence: z [T, n_agents, Z], a [T, n_agents].

    Returns (final carry, Mixture [T, n_agents, Z, K], h_in [T, hidden]) where h_in[t] is
    the hidden state *before* step t (what the self-model sees when acting at t).
    """

    net, v = make_nets(cfg).rnn, {"params": rnn_params}
    gx = net.apply(v, z, a, method=MDNRNN.input_gates)  # all steps in one matmul

    def body(carry, g):
        h_in = carry[1]
        carry = net.apply(v, carry, g, method=MDNRNN.cell)
        return carry, (carry[1], h_in)

    carry, (h_out, h_in) = jax.lax.scan(body, carry, gx)
    return carry, net.apply(v, h_out, method=MDNRNN.mixture), h_in


def predict_curiosity(cfg: LearnerConfig, self_params, z, h):
    """Each agent's self-model on (z_i, h): z [n_agents, Z], h [hidden] -> [n_agents, n_actions]."""
    sm = make_nets(cfg).self_model
    return jax.vmap(lambda p, zi: sm.apply({"params": p}, zi, h))(self_params, z)


# ----------------------------------------------------------------------------------------
# Mixture maths, curiosity, losses
# ----------------------------------------------------------------------------------------

_LOG_SQRT_2PI = 0.5 * math.log(2.0 * math.pi)


def mixture_mean(mix: Mixture):
    """E[z_{t+1}] = sum_k pi_k mu_k, per agent and dimension: [..., n_agents, Z]."""
    return jnp.sum(jnp.exp(mix.log_pi) * mix.mu, axis=-1)


def mixture_log_prob(mix: Mixture, z):
    """log p(z) per agent: [..., n_agents] (dimensions independent given the mixture params)."""
    zk = z[..., None]
    log_n = -0.5 * jnp.square((zk - mix.mu) * jnp.exp(-mix.log_std)) - mix.log_std - _LOG_SQRT_2PI
    return jnp.sum(jax.nn.logsumexp(mix.log_pi + log_n, axis=-1), axis=-1)


def mdn_nll(mix: Mixture, z_next):
    """Eq. 2/6 per transition: -sum_i log P(z^i_{t+1} | ...), shape [...] (summed over agents)."""
    return -jnp.sum(mixture_log_prob(mix, z_next), axis=-1)


def curiosity(cfg: LearnerConfig, z_next, mix: Mixture):
    """Eq. 3 per agent: the squared error between z_{t+1} and the MDN-RNN's expectation
    E[z_hat_{t+1}], shape [..., n_agents]: its mean over the latent dimensions (cfg.curiosity ==
    "mean", the authors' code: `mse_loss(...).mean(dim=1)`) or their sum, ||.||^2 ("sum")."""
    return _over_latent(cfg, jnp.square(z_next - mixture_mean(mix)))


def _over_latent(cfg: LearnerConfig, x):
    """Curiosity's reduction over the latent dimensions (the last axis): mean or sum."""
    return jnp.mean(x, axis=-1) if cfg.curiosity == "mean" else jnp.sum(x, axis=-1)


def vae_loss(cfg: LearnerConfig, vae_params, frames, key, stats=()):
    """Eq. 1/5 on frames uint8 [B, n_agents, H, W, 3]: summed over agents, mean over B.

    Reconstruction is the per-image sum of squared errors and KL is weighted by beta; with
    kl_tolerance > 0 the KL term has Ha & Schmidhuber's free bits (a floor of
    kl_tolerance * latent nats per image; the default 0 is the paper's plain KL).
    Returns (loss, (recon, kl)) with recon and kl on the same scale (agents summed).
    """
    loss, (recon, kl, _, _) = vae_loss_and_posterior(cfg, vae_params, frames, key, stats)
    return loss, (recon, kl)


def vae_loss_and_posterior(cfg: LearnerConfig, vae_params, frames, key, stats=()):
    """`vae_loss` as the learner trains it (batch normalisation, if any, by this batch's
    statistics), with the posterior its encoder computed on the way and the running averages
    after it: (loss, (recon, kl, (mu, logvar), stats)), mu and logvar [B, n_agents, latent]."""
    b, n = frames.shape[:2]
    flat = frames.reshape((b * n,) + frames.shape[2:])
    (recon_img, mu, logvar), stats = apply_vae(cfg, vae_params, stats, flat, key, train=True)
    x = flat.astype(jnp.float32) * (1.0 / 255.0)
    recon = jnp.sum(jnp.square(recon_img - x), axis=(1, 2, 3))  # [B*n]
    kl = -0.5 * jnp.sum(1.0 + logvar - jnp.square(mu) - jnp.exp(logvar), axis=-1)  # [B*n]
    kl_term = jnp.maximum(kl, cfg.kl_tolerance * cfg.latent)
    per_image = recon + cfg.beta * kl_term
    loss = jnp.sum(per_image) / b
    posterior = (mu.reshape(b, n, cfg.latent), logvar.reshape(b, n, cfg.latent))
    return loss, (jnp.sum(recon) / b, jnp.sum(kl) / b, posterior, stats)


def reencoded_latents(cfg: LearnerConfig, vae_params, frames, t_pick, posterior_pick, key, stats=()):
    """The current encoder's latents (`latent`) of a replay sample's frames uint8
    [B, T+1, n_agents, H, W, 3] -> [B, T+1, n_agents, latent], drawing the noise as `latent`
    does with `key` (one normal draw of the whole [B, T+1, n_agents, latent]).

    The frame at step t_pick[b] of each sequence was just encoded by the VAE's own update with
    the same parameters (`posterior_pick`: (mu, logvar) [B, n_agents, latent]); only the T other
    frames of each sequence go through the encoder here, one batch of B x T x n_agents images.

    Returns (latents, running averages after): batch normalisation (vae_layers="authors")
    normalises that batch by its own statistics and folds them into `stats`, as the authors' code
    encodes its training batch's next frames in train mode."""
    b, tp1 = frames.shape[:2]
    t = jnp.arange(tp1 - 1)[None, :]
    others = t + (t >= t_pick[:, None])  # [B, T]: every step but t_pick, in order
    rows = jnp.arange(b)[:, None]
    (mu_o, logvar_o), stats = encode_and_stats(cfg, vae_params, frames[rows, others], stats, train=True)
    # back to time order: step s is t_pick's posterior or `others`' entry s - (s > t_pick)
    s = jnp.arange(tp1)[None, :]
    src = s - (s > t_pick[:, None])
    picked = (s == t_pick[:, None])[..., None, None]
    mu = jnp.where(picked, posterior_pick[0][:, None], mu_o[rows, jnp.minimum(src, tp1 - 2)])
    if cfg.z != "sample":
        return mu, stats
    logvar = jnp.where(picked, posterior_pick[1][:, None], logvar_o[rows, jnp.minimum(src, tp1 - 2)])
    return sample_latent(key, mu, logvar), stats


def self_model_loss(cfg: LearnerConfig, self_params, z, h, actions, target):
    """Eq. 4, per agent: MSE between the predicted curiosity of the action actually taken and
    the curiosity obtained. z [N, n_agents, Z], h [N, hidden], actions [N, n_agents],
    target [N, n_agents]. Returns (sum over agents, per-agent losses [n_agents])."""
    pred = jax.vmap(lambda zz, hh: predict_curiosity(cfg, self_params, zz, hh))(z, h)  # [N, n, A]
    taken = jnp.take_along_axis(pred, actions[..., None], axis=-1)[..., 0]
    per_agent = jnp.mean(jnp.square(taken - target), axis=0)
    return jnp.sum(per_agent), per_agent


def mdn_loss(cfg: LearnerConfig, rnn_params, carry0: Carry, z, a):
    """Eq. 2/6 over a batch of sequences: truncated BPTT from carry0 (each [B, hidden]).

    z [B, T+1, n_agents, Z], a [B, T+1, n_agents]: step t's (z_t, a_t) predicts z_{t+1}.
    Returns (mean over batch and time of the per-transition NLL, (Mixture [B, T, ...],
    h_in [B, T, hidden])).
    """
    _, mix, h_in = jax.vmap(lambda c, zz, aa: rnn_sequence(cfg, rnn_params, c, zz, aa))(
        carry0, z[:, :-1], a[:, :-1]
    )
    nll = jnp.mean(mdn_nll(mix, z[:, 1:]))
    return nll, (mix, h_in)


# ----------------------------------------------------------------------------------------
# The learner update
# ----------------------------------------------------------------------------------------


def learner_update(cfg: LearnerConfig, state: LearnerState, batch: Batch, key):
    """One update of VAE, MDN-RNN and every self-model from one replay sample.

    - VAE: one frame per sequence and agent (a random step of each sequence): B x n_agents
      images, so its cost does not grow with seq_len.
    - MDN-RNN: truncated BPTT over the seq_len transitions of each sequence, starting
      from the LSTM carry stored in replay at the sequence start; inputs are the stored
      latents (cfg.latents == "stored") or the frames re-encoded by the current VAE
      ("reencode": `latent` of every frame, see `reencoded_latents`; with cfg.z == "sample" a
      posterior sample whose noise is drawn with `jax.random.split(key, 3)[2]`).
    - Self-models: targets = curiosity of the sampled transitions under the current
      MDN-RNN (stop-gradient), inputs (z_t^i, h_t), trained on the actions actually taken.
    Returns (new state, metrics dict: scalars, and `self_loss_agents` [n_agents]).
    """
    opt = optimizer(cfg)
    # k_z: the re-encoding noise (latents="reencode", z="sample"). JAX's threefry splits are
    # prefix-stable (jax_threefry_partitionable, the default), so k_frame and k_vae are the keys
    # of the two-way split used before k_z existed, and old settings reproduce their runs.
    k_frame, k_vae, k_z = jax.random.split(key, 3)
    b, tp1 = batch.actions.shape[:2]

    # --- VAE -----------------------------------------------------------------------------
    t_pick = jax.random.randint(k_frame, (b,), 0, tp1)
    frames = batch.frames[jnp.arange(b), t_pick]  # [B, n_agents, H, W, 3]
    (vae_l, (recon, kl, posterior, vae_stats)), g_vae = jax.value_and_grad(
        lambda p: vae_loss_and_posterior(cfg, p, frames, k_vae, state.vae_stats), has_aux=True
    )(state.vae)

    # --- MDN-RNN ---------------------------------------------------------------------------
    if cfg.latents == "reencode":
        posterior = jax.lax.stop_gradient(posterior)
        z, vae_stats = jax.lax.stop_gradient(
            reencoded_latents(cfg, state.vae, batch.frames, t_pick, posterior, k_z, vae_stats))
    else:
        z = batch.latents
    carry0 = jax.tree.map(lambda x: x[:, 0], batch.carry)
    (nll, (mix, h_in)), g_rnn = jax.value_and_grad(
        lambda p: mdn_loss(cfg, p, carry0, z, batch.actions), has_aux=True
    )(state.rnn)

    # --- self-models ---------------------------------------------------------------------
    mix = jax.lax.stop_gradient(mix)
    cur = curiosity(cfg, z[:, 1:], mix)  # [B, T, n]: the self-models' targets, on cfg.curiosity's scale
    n_tr = b * (tp1 - 1)
    z_in = z[:, :-1].reshape(n_tr, cfg.n_agents, cfg.latent)
    h_in = jax.lax.stop_gradient(h_in).reshape(n_tr, cfg.rnn_hidden)
    a_in = batch.actions[:, :-1].reshape(n_tr, cfg.n_agents)
    (self_l, per_agent), g_self = jax.value_and_grad(
        lambda p: self_model_loss(cfg, p, z_in, h_in, a_in, cur.reshape(n_tr, cfg.n_agents)),
        has_aux=True,
    )(state.self_model)

    # --- Adam steps ------------------------------------------------------------------------
    def adam(g, s, p):
        u, s = opt.update(g, s, p)
        return optax.apply_updates(p, u), s

    vae, vae_opt = adam(g_vae, state.vae_opt, state.vae)
    rnn, rnn_opt = adam(g_rnn, state.rnn_opt, state.rnn)
    self_model, self_opt = jax.vmap(adam)(g_self, state.self_opt, state.self_model)

    new = LearnerState(vae, vae_opt, rnn, rnn_opt, self_model, self_opt, state.step + 1, vae_stats)
    metrics = {
        "vae_loss": vae_l,
        "recon": recon,
        "kl": kl,
        "nll": nll,
        "self_loss": self_l,
        "self_loss_agents": per_agent,  # [n_agents]
        "curiosity": jnp.mean(cur),
        "curiosity_agents": jnp.mean(cur, axis=(0, 1)),  # [n_agents]
    }
    return new, metrics
