"""World model maths, learning behaviour and the learner update."""

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

import dataclasses
import functools

import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest

from conftest import USERS_CODEGEN
from mjx_curio import world_model as wm
from mjx_curio.config import LearnerConfig
from mjx_curio.nets import Mixture

# ----------------------------------------------------------------------------------------
# Mixture maths against NumPy
# ----------------------------------------------------------------------------------------


def test_mixture_mean_nll_and_curiosity_match_numpy():
    rng = np.random.default_rng(0)
    shape = (5, 2, 3, 4)  # [batch, agents, latent, K]
    logits = rng.normal(size=shape)
    mu = rng.normal(size=shape)
    log_std = rng.uniform(-1.0, 1.0, size=shape)
    z = rng.normal(size=shape[:-1])
    log_pi = logits - np.log(np.sum(np.exp(logits), -1, keepdims=True))
    mix = Mixture(*(jnp.asarray(a, jnp.float32) for a in (log_pi, mu, log_std)))

    pi, std = np.exp(log_pi), np.exp(log_std)
    dens = np.sum(pi * np.exp(-0.5 * ((z[..., None] - mu) / std) ** 2) / (std * np.sqrt(2 * np.pi)), -1)
    nll_np = -np.sum(np.log(dens), axis=(-1, -2))  # summed over latent dims and agents
    mean_np = np.sum(pi * mu, -1)
    cur_np = np.sum((z - mean_np) ** 2, -1)

    summed, averaged = (LearnerConfig(latent=3, curiosity=c) for c in ("sum", "mean"))
    f = jax.jit(lambda m, z: (wm.mdn_nll(m, z), wm.mixture_mean(m), wm.curiosity(summed, z, m),
                              wm.curiosity(averaged, z, m)))
    nll, mean, cur, cur_mean = f(mix, jnp.asarray(z, jnp.float32))
    assert nll.shape == (5,) and mean.shape == (5, 2, 3) and cur.shape == cur_mean.shape == (5, 2)
    np.testing.assert_allclose(nll, nll_np, rtol=1e-4, atol=1e-4)
    np.testing.assert_allclose(mean, mean_np, rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(cur, cur_np, rtol=1e-4, atol=1e-5)
    # curiosity="mean" (the authors' code: mean over the latent dimensions) is the sum / latent
    np.testing.assert_allclose(cur_mean, cur_np / 3, rtol=1e-4, atol=1e-5)
    np.testing.assert_allclose(cur_mean, np.asarray(cur) / 3, rtol=1e-6)


# ----------------------------------------------------------------------------------------
# MDN-RNN learning on a synthetic latent process with action-dependent dynamics
# ----------------------------------------------------------------------------------------

MDN_CFG = LearnerConfig(image=8, n_agents=2, latent=3, mixtures=3, rnn_hidden=48, self_hidden=8, batch=32, seq_len=8)
N_ACT = 7


def _process(rng, n_seq, steps, effects, sigma):
    """z_{t+1} = 0.5 z_t + effects[i, a_t^i] + sigma * noise, per agent i; uniform actions."""
    n, zdim = MDN_CFG.n_agents, MDN_CFG.latent
    z = np.empty((n_seq, steps + 1, n, zdim), np.float32)
    a = rng.integers(0, N_ACT, (n_seq, steps + 1, n))
    z[:, 0] = rng.normal(size=(n_seq, n, zdim))
    for t in range(steps):
        eff = effects[np.arange(n)[None, :], a[:, t]]  # [n_seq, n, Z]
        z[:, t + 1] = 0.5 * z[:, t] + eff + sigma * rng.normal(size=(n_seq, n, zdim))
    return z, a.astype(np.int32)


def _action_blind_nll(z, a, effects, sigma):
    """Exact NLL of the best predictor that does not see a_t: the actions are i.i.d. uniform,
    so p(z'|history) = mean over the 7 actions of N(0.5 z + effect, sigma^2 I), per agent."""
    mean = 0.5 * z[:, :-1, :, None, :] + effects[None, None]  # [S, T, n, A, Z]
    x = z[:, 1:, :, None, :]
    logn = np.sum(-0.5 * ((x - mean) / sigma) ** 2 - np.log(sigma) - 0.5 * np.log(2 * np.pi), -1)
    m = logn.max(-1, keepdims=True)
    logp = (m + np.log(np.mean(np.exp(logn - m), -1, keepdims=True)))[..., 0]  # [S, T, n]
    return float(np.mean(-np.sum(logp, -1)))


@pytest.fixture(scope="module")
def mdn_fns():
    cfg = MDN_CFG
    opt = wm.optimizer(cfg)

    def seq_loss(p, z, a):
        carry = jax.tree.map(lambda x: jnp.broadcast_to(x, (z.shape[0],) + x.shape), wm.initial_carry(cfg))
        return wm.mdn_loss(cfg, p, carry, z, a)

    # Run thousands of times: compiled as users' runs are, it runs several times faster (conftest.py).
    @functools.partial(jax.jit, compiler_options=USERS_CODEGEN)
    def train(p, s, z, a):
        (nll, _), g = jax.value_and_grad(seq_loss, has_aux=True)(p, z, a)
        u, s = opt.update(g, s, p)
        return optax.apply_updates(p, u), s, nll

    @jax.jit
    def evaluate(p, z, a):
        nll, (mix, _) = seq_loss(p, z, a)
        return nll, jnp.mean(wm.curiosity(dataclasses.replace(cfg, curiosity="sum"), z[:, 1:], mix))

    return train, evaluate


def _fit(mdn_fns, effects, sigma, steps, seed):
    train, evaluate = mdn_fns
    rng = np.random.default_rng(seed)
    z_tr, a_tr = _process(rng, 4096, MDN_CFG.seq_len, effects, sigma)
    z_te, a_te = _process(rng, 512, MDN_CFG.seq_len, effects, sigma)
    st = wm.init_learner(MDN_CFG, jax.random.PRNGKey(seed))
    p, s = st.rnn, st.rnn_opt
    before = evaluate(p, z_te, a_te)
    for _ in range(steps):
        idx = rng.integers(0, z_tr.shape[0], MDN_CFG.batch)
        p, s, _ = train(p, s, z_tr[idx], a_tr[idx])
    after = evaluate(p, z_te, a_te)
    return [float(v) for v in before], [float(v) for v in after], (z_te, a_te)


def _effects(seed):
    return np.random.default_rng(seed).uniform(-1.5, 1.5, (MDN_CFG.n_agents, N_ACT, MDN_CFG.latent))


@pytest.mark.slow
def test_mdn_nll_falls_below_best_action_blind_predictor(mdn_fns):
    sigma = 0.1
    effects = _effects(10)
    (nll0, _), (nll1, _), (z_te, a_te) = _fit(mdn_fns, effects, sigma, steps=1200, seed=1)
    blind = _action_blind_nll(z_te, a_te, effects, sigma)
    optimum = MDN_CFG.n_agents * MDN_CFG.latent * (np.log(sigma) + 0.5 * np.log(2 * np.pi) + 0.5)
    print(f"nll before {nll0:.2f} after {nll1:.2f}; action-blind optimum {blind:.2f}; true optimum {optimum:.2f}")
    assert nll1 < nll0 - 10.0
    # must use the actions: beat the best predictor that ignores them by a clear margin
    # (the gap between the blind and the true optimum is ~2 x ln 7 = 3.9 nats here)
    assert nll1 < blind - 1.5, (nll1, blind)


@pytest.mark.slow
def test_curiosity_near_zero_for_a_learned_deterministic_process(mdn_fns):
    effects = _effects(20)
    (_, cur0), (_, cur1), (z_te, _) = _fit(mdn_fns, effects, 0.0, steps=2500, seed=2)
    spread = float(np.mean(np.sum((z_te[:, 1:] - z_te[:, 1:].mean((0, 1))) ** 2, -1)))
    print(f"curiosity before {cur0:.4f} after {cur1:.5f}; variance of z_t+1 {spread:.3f}")
    assert cur1 < 0.005 * cur0
    assert cur1 < 0.01 * spread  # explains > 99% of the next latent's variance


# ----------------------------------------------------------------------------------------
# Self-model: learns which action surprises most
# ----------------------------------------------------------------------------------------


STEPS = 1500


def test_self_model_learns_which_action_yields_the_largest_error():
    cfg = LearnerConfig(image=8, n_agents=2, latent=4, rnn_hidden=8, self_hidden=64)
    opt = wm.optimizer(cfg)
    rng = np.random.default_rng(0)

    def toy(n):
        z = rng.normal(size=(n, 2, 4)).astype(np.float32)
        h = rng.normal(size=(n, 8)).astype(np.float32)
        # each agent its own rule for the most surprising action
        best = np.stack([np.where(z[:, 0, 0] > 0, 2, 5), np.where(z[:, 1, 1] > 0, 4, 0)], -1)
        err = 0.1 + 0.05 * np.arange(7)[None, None, :] + np.zeros((n, 2, 7))
        np.put_along_axis(err, best[..., None], 1.0, -1)
        return z, h, best, err

    @jax.jit
    def train(p, s, z, h, a, target):
        (_, per_agent), g = jax.value_and_grad(
            lambda p: wm.self_model_loss(cfg, p, z, h, a, target), has_aux=True
        )(p)

        def adam(g, s, p):
            u, s = opt.update(g, s, p)
            return optax.apply_updates(p, u), s

        p, s = jax.vmap(adam)(g, s, p)
        return p, s, per_agent

    st = wm.init_learner(cfg, jax.random.PRNGKey(0))
    p, s = st.self_model, st.self_opt
    for _ in range(STEPS):
        z, h, _, err = toy(256)
        a = rng.integers(0, 7, (256, 2))  # actions actually taken: random
        target = np.take_along_axis(err, a[..., None], -1)[..., 0] + 0.05 * rng.normal(size=(256, 2))
        p, s, per_agent = train(p, s, z, h, a.astype(np.int32), target.astype(np.float32))
    z, h, best, err = toy(2000)
    q = np.asarray(jax.jit(jax.vmap(lambda zz, hh: wm.predict_curiosity(cfg, p, zz, hh)))(z, h))
    # judged away from each rule's decision boundary (|z| > 0.25), where the target is a
    # step the MLP can only approximate
    clear = np.stack([np.abs(z[:, 0, 0]) > 0.25, np.abs(z[:, 1, 1]) > 0.25], -1)
    hit = np.argmax(q, -1) == best
    acc = np.array([hit[clear[:, i], i].mean() for i in range(2)])
    mse = np.square(q - err).mean()
    blind = np.square(err.mean(0) - err).mean()  # best input-blind prediction: mean per action
    print("argmax accuracy per agent", acc, "mse", mse, "input-blind mse", blind)
    assert np.all(acc > 0.97), acc
    assert mse < 0.5 * blind, (mse, blind)


# ----------------------------------------------------------------------------------------
# The learner update
# ----------------------------------------------------------------------------------------

# latents="stored": most tests here plant the latents the MDN-RNN trains on (Batch.latents);
# the default, "reencode", has tests of its own below.
SMALL = LearnerConfig(
    latents="stored",
    image=8,
    n_agents=2,
    latent=4,
    vae_channels=(8, 16, 16, 16),
    dec_channels=(16, 8, 8, 8),
    rnn_hidden=16,
    mixtures=3,
    self_hidden=16,
    batch=4,
    seq_len=3,
)


def _frames(rng, shape, size):
    """A coloured square on a checkered background per frame: uint8 shape + [size, size, 3]."""
    yy, xx = np.mgrid[:size, :size]
    checker = ((yy // 2 + xx // 2) % 2)[..., None] * np.array([50, 50, 60]) + np.array([40, 60, 170])
    out = np.broadcast_to(checker, shape + (size, size, 3)).copy()
    cy, cx = rng.integers(0, size - 3, (2,) + shape)
    colour = rng.integers(0, 256, shape + (3,))
    for idx in np.ndindex(*shape):
        out[idx][cy[idx] : cy[idx] + 3, cx[idx] : cx[idx] + 3] = colour[idx]
    return out.astype(np.uint8)


def _batch(cfg, seed):
    rng = np.random.default_rng(seed)
    shp = (cfg.batch, cfg.seq_len + 1, cfg.n_agents)
    return wm.Batch(
        frames=_frames(rng, shp, cfg.image),
        latents=rng.normal(size=shp + (cfg.latent,)).astype(np.float32),
        actions=rng.integers(0, 7, shp).astype(np.int32),
        carry=tuple(rng.normal(size=(cfg.batch, cfg.seq_len + 1, cfg.rnn_hidden)).astype(np.float32) * 0.5 for _ in range(2)),
    )


@pytest.fixture(scope="module")
def update():
    return jax.jit(functools.partial(wm.learner_update, SMALL))


@pytest.mark.slow
def test_learner_update_vmapped_over_runs_equals_separate_updates(update):
    keys = jax.random.split(jax.random.PRNGKey(0), 3)
    states = [wm.init_learner(SMALL, k) for k in keys]
    batches = [_batch(SMALL, i) for i in range(3)]
    ukeys = jax.random.split(jax.random.PRNGKey(1), 3)
    separate = [update(s, b, k) for s, b, k in zip(states, batches, ukeys)]

    stack = lambda xs: jax.tree.map(lambda *a: jnp.stack(a), *xs)  # noqa: E731
    vstate, vmetrics = jax.jit(jax.vmap(functools.partial(wm.learner_update, SMALL)))(
        stack(states), stack(batches), ukeys
    )
    for r, (s, m) in enumerate(separate):
        got = jax.tree.map(lambda x: x[r], (vstate, vmetrics))
        for a, b in zip(jax.tree.leaves(got), jax.tree.leaves((s, m))):
            np.testing.assert_allclose(a, b, rtol=2e-4, atol=2e-5)
    # and the runs really differ from each other
    assert not np.allclose(separate[0][1]["nll"], separate[1][1]["nll"])


def test_learner_update_trains_all_three_models(update):
    cfg = SMALL
    rng = np.random.default_rng(5)
    b = _batch(cfg, 7)
    # latents from an action-dependent process so the MDN has something to learn
    effects = rng.uniform(-1, 1, (cfg.n_agents, 7, cfg.latent)).astype(np.float32)
    z = b.latents.copy()
    for t in range(cfg.seq_len):
        z[:, t + 1] = 0.5 * z[:, t] + effects[np.arange(cfg.n_agents)[None], b.actions[:, t]]
    b = b._replace(latents=z)
    st = wm.init_learner(cfg, jax.random.PRNGKey(3))
    first = None
    for i in range(100):
        st, m = update(st, b, jax.random.PRNGKey(i))
        first = first if first is not None else {k: np.asarray(v).astype(float) for k, v in m.items()}
    last = {k: np.asarray(v).astype(float) for k, v in m.items()}
    print(first, last)
    assert int(st.step) == 100
    assert last["recon"] < 0.7 * first["recon"]
    assert last["nll"] < first["nll"] - 5.0
    assert last["self_loss"] < 0.5 * first["self_loss"]
    assert all(np.isfinite(v).all() for v in last.values())


def test_learner_update_starts_bptt_from_the_stored_carry(update):
    st = wm.init_learner(SMALL, jax.random.PRNGKey(0))
    b = _batch(SMALL, 1)
    key = jax.random.PRNGKey(2)
    _, m = update(st, b, key)
    # carries stored for later steps are not used: truncated BPTT starts at step 0
    later = tuple(c.copy() for c in b.carry)
    for c in later:
        c[:, 1:] += 5.0
    _, m_later = update(st, b._replace(carry=later), key)
    np.testing.assert_allclose(m_later["nll"], m["nll"], rtol=1e-6)
    first = tuple(c.copy() for c in b.carry)
    for c in first:
        c[:, 0] += 1.0
    _, m_first = update(st, b._replace(carry=first), key)
    assert abs(float(m_first["nll"]) - float(m["nll"])) > 1e-3


@pytest.mark.parametrize("z_mode", ["sample", pytest.param("mean", marks=pytest.mark.slow)])
def test_reencode_mode_trains_the_mdn_on_fresh_encodings(z_mode):
    """latents=reencode: the MDN-RNN trains on exactly the current encoder's latents of the
    sampled frames, not the stored ones: the posterior means (z=mean), or samples of the
    posterior drawn with the update's own noise, the third key of `split(key, 3)` (z=sample)."""
    cfg = dataclasses.replace(SMALL, latents="reencode", z=z_mode)
    st = wm.init_learner(cfg, jax.random.PRNGKey(0))
    b = _batch(cfg, 2)
    key = jax.random.PRNGKey(1)
    garbage = b._replace(latents=np.full_like(b.latents, np.nan))
    st2, m = jax.jit(functools.partial(wm.learner_update, cfg))(st, garbage, key)
    # the stored latents are ignored
    assert all(np.isfinite(np.asarray(v)).all() for v in m.values())
    mu, logvar = (np.asarray(x) for x in jax.jit(lambda p, f: wm.encode(cfg, p, f))(st.vae, b.frames))
    eps = np.asarray(jax.random.normal(jax.random.split(key, 3)[2], mu.shape))
    z = mu + np.exp(0.5 * logvar) * eps if z_mode == "sample" else mu
    carry = jax.tree.map(lambda x: x[:, 0], b.carry)
    nll_of = jax.jit(lambda p, z: wm.mdn_loss(cfg, p, carry, z, b.actions)[0])
    np.testing.assert_allclose(m["nll"], nll_of(st.rnn, z), rtol=1e-5)
    if z_mode == "sample":  # and it is a sample, not the mean
        assert abs(float(m["nll"]) - float(nll_of(st.rnn, mu))) > 1e-3


def test_authors_layers_normalise_each_training_batch_by_its_own_statistics():
    """vae_layers=authors: the update's VAE batch and then its re-encoded frames are each
    normalised by their own moments, which are folded into the running averages in that order;
    the MDN-RNN trains on the latents so encoded."""
    cfg = dataclasses.replace(SMALL, latents="reencode", vae_layers="authors")
    st = wm.init_learner(cfg, jax.random.PRNGKey(0))
    b = _batch(cfg, 2)
    key = jax.random.PRNGKey(1)
    st2, m = jax.jit(functools.partial(wm.learner_update, cfg))(st, b, key)

    k_frame, k_vae, k_z = jax.random.split(key, 3)
    t_pick = jax.random.randint(k_frame, (cfg.batch,), 0, cfg.seq_len + 1)
    picked = b.frames[np.arange(cfg.batch), np.asarray(t_pick)]
    _, (_, _, posterior, after_vae) = wm.vae_loss_and_posterior(cfg, st.vae, picked, k_vae, st.vae_stats)
    z, after_reencode = wm.reencoded_latents(cfg, st.vae, b.frames, t_pick, posterior, k_z, after_vae)
    for got, want in zip(jax.tree.leaves(st2.vae_stats), jax.tree.leaves(after_reencode)):
        np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=1e-5, atol=1e-6)
    # the decoder runs in the VAE's update only; the encoder's averages moved twice
    assert not np.allclose(np.asarray(after_vae["down_norm_0"]["mean"]), np.asarray(after_reencode["down_norm_0"]["mean"]))
    np.testing.assert_array_equal(np.asarray(after_vae["up_norm_0"]["mean"]), np.asarray(after_reencode["up_norm_0"]["mean"]))
    carry = jax.tree.map(lambda x: x[:, 0], b.carry)
    np.testing.assert_allclose(m["nll"], wm.mdn_loss(cfg, st.rnn, carry, z, b.actions)[0], rtol=1e-5)


@pytest.mark.parametrize("z_mode", ["sample", "mean"])
def test_reencoding_reuses_the_vae_updates_posterior_of_its_frame(z_mode):
    """`reencoded_latents` encodes only the frames the VAE's update did not (all but t_pick of
    each sequence) and takes t_pick's posterior from the update: the result is `latent` of
    every frame, noise included, in time order, wherever t_pick falls (first, middle, last)."""
    cfg = dataclasses.replace(SMALL, z=z_mode)
    st = wm.init_learner(cfg, jax.random.PRNGKey(0))
    b = _batch(cfg, 3)
    frames = np.asarray(b.frames)
    t_pick = np.resize([0, cfg.seq_len // 2, cfg.seq_len], cfg.batch)
    posterior = wm.encode(cfg, st.vae, frames[np.arange(cfg.batch), t_pick])
    key = jax.random.PRNGKey(7)
    reencoded = jax.jit(lambda *a: wm.reencoded_latents(cfg, *a)[0])
    got = np.asarray(reencoded(st.vae, frames, t_pick, posterior, key))
    want = wm.latent(cfg, st.vae, frames, key)
    np.testing.assert_allclose(got, np.asarray(want), rtol=1e-5, atol=1e-6)
    # and the picked frames' values really come from `posterior` (same program: bitwise elsewhere)
    moved = np.asarray(reencoded(st.vae, frames, t_pick, (posterior[0] + 100.0, posterior[1]), key))
    for i, t in enumerate(t_pick):
        np.testing.assert_allclose(moved[i, t] - got[i, t], 100.0, rtol=1e-5)
        assert np.array_equal(np.delete(moved[i], t, axis=0), np.delete(got[i], t, axis=0))


def test_curiosity_scale_sets_the_self_models_targets(update):
    """The self-models learn to predict curiosity, so their targets follow `curiosity`: the
    same update with curiosity=sum has targets (the recorded mean curiosity) `latent` times
    those of curiosity=mean."""
    summed = dataclasses.replace(SMALL, curiosity="sum")
    assert SMALL.curiosity == "mean"
    st = wm.init_learner(SMALL, jax.random.PRNGKey(0))
    b, key = _batch(SMALL, 3), jax.random.PRNGKey(4)
    _, m_mean = update(st, b, key)
    _, m_sum = jax.jit(functools.partial(wm.learner_update, summed))(st, b, key)
    np.testing.assert_allclose(m_sum["curiosity"], SMALL.latent * m_mean["curiosity"], rtol=1e-5)
    np.testing.assert_allclose(m_sum["nll"], m_mean["nll"], rtol=1e-6)  # nothing else differs
    assert float(m_mean["curiosity"]) > 0


def test_sampled_latents_are_draws_from_the_posterior():
    """`latent` with z=sample: a reparameterised draw of q(z|o) = N(mu, sigma^2). Over N = 4,000
    keys, per dimension (24: 3 frames x 2 agents x 4), the z-score of the sample mean around
    mu and that of the sample variance around sigma^2 (exactly chi-square, N dof) stay within
    6: each fails with probability < 7e-9 for random keys, all 48 together < 1e-6. The same key
    gives the same draw, different keys different draws, and z=mean gives mu."""
    cfg = SMALL
    frames = _frames(np.random.default_rng(0), (3, cfg.n_agents), cfg.image)
    st = wm.init_learner(cfg, jax.random.PRNGKey(5))
    mu, logvar = (np.asarray(x, np.float64) for x in wm.encode(cfg, st.vae, frames))
    sigma = np.exp(0.5 * logvar)
    n = 4000
    keys = jax.random.split(jax.random.PRNGKey(6), n)
    draws = np.asarray(jax.jit(jax.vmap(lambda k: wm.latent(cfg, st.vae, frames, k)))(keys), np.float64)
    assert draws.shape == (n,) + mu.shape
    z_mean = (draws.mean(0) - mu) / (sigma / np.sqrt(n))
    chi2 = np.sum(np.square((draws - mu) / sigma), axis=0)  # ~ chi-square with n dof
    z_var = (chi2 - n) / np.sqrt(2 * n)
    print(f"max |z| of the mean {np.abs(z_mean).max():.2f}, of the variance {np.abs(z_var).max():.2f}; "
          f"sigma in [{sigma.min():.3f}, {sigma.max():.3f}]")
    assert np.abs(z_mean).max() < 6 and np.abs(z_var).max() < 6
    assert np.all(draws[0] != draws[1])  # different keys, different draws (every element)
    # the same key, the same draw (to float rounding: eager here, jitted and vmapped above)
    np.testing.assert_allclose(np.asarray(wm.latent(cfg, st.vae, frames, keys[0])), draws[0], rtol=1e-5, atol=1e-6)
    mean_cfg = dataclasses.replace(cfg, z="mean")
    np.testing.assert_allclose(np.asarray(wm.latent(mean_cfg, st.vae, frames, keys[0])), mu, rtol=1e-6, atol=1e-7)


def test_curiosity_spread_is_what_sampling_adds_to_the_curiositys_expectation():
    """`latent_and_spread`: over N = 4,000 posterior draws, the mean curiosity against a fixed
    prediction is ||mu - prediction||^2 plus the spread, reduced as curiosity reduces (mean or
    sum over the dimensions); the spread is NumPy's sigma^2 reduced so, the latent is `latent`'s
    draw for the same key, and z=mean has no spread. The z-score of the sample mean (its
    standard error from the sample's own spread) stays within 6 for each of the 6 latents."""
    frames = _frames(np.random.default_rng(1), (3, SMALL.n_agents), SMALL.image)
    st = wm.init_learner(SMALL, jax.random.PRNGKey(7))
    mu, logvar = (np.asarray(x, np.float64) for x in wm.encode(SMALL, st.vae, frames))
    var = np.exp(logvar)
    rng = np.random.default_rng(2)
    shape = mu.shape + (2,)  # a two-component mixture whose mean is the prediction
    mix = Mixture(jnp.full(shape, np.log(0.5), jnp.float32), jnp.asarray(mu[..., None] + rng.normal(size=shape), jnp.float32),
                  jnp.zeros(shape, jnp.float32))
    prediction = np.asarray(wm.mixture_mean(mix), np.float64)
    keys = jax.random.split(jax.random.PRNGKey(8), 4000)
    for reduce, cfg in ((np.mean, SMALL), (np.sum, dataclasses.replace(SMALL, curiosity="sum"))):
        def draw(k, cfg=cfg):
            z, spread = wm.latent_and_spread(cfg, st.vae, frames, k)
            return z, spread, wm.curiosity(cfg, z, mix)

        z, spread, cur = (np.asarray(x, np.float64) for x in jax.jit(jax.vmap(draw))(keys))
        np.testing.assert_allclose(spread[0], reduce(var, axis=-1), rtol=1e-5)
        np.testing.assert_array_equal(spread[0], spread[1])  # sigma^2 does not depend on the draw
        np.testing.assert_allclose(z[0], np.asarray(wm.latent(cfg, st.vae, frames, keys[0])), rtol=1e-5, atol=1e-6)
        expected = reduce(np.square(mu - prediction), axis=-1) + spread[0]
        z_score = (cur.mean(0) - expected) / (cur.std(0) / np.sqrt(len(keys)))
        assert np.abs(z_score).max() < 6, z_score
    z, spread = wm.latent_and_spread(dataclasses.replace(SMALL, z="mean"), st.vae, frames, keys[0])
    np.testing.assert_allclose(np.asarray(z), mu, rtol=1e-6, atol=1e-7)
    assert np.all(np.asarray(spread) == 0) and spread.shape == mu.shape[:-1]


def test_rnn_sequence_equals_repeated_single_steps():
    cfg = SMALL
    st = wm.init_learner(cfg, jax.random.PRNGKey(4))
    rng = np.random.default_rng(4)
    z = rng.normal(size=(5, 2, cfg.latent)).astype(np.float32)
    a = rng.integers(0, 7, (5, 2)).astype(np.int32)
    carry0 = wm.initial_carry(cfg)

    @jax.jit
    def both(p):
        seq = wm.rnn_sequence(cfg, p, carry0, z, a)
        carry, mixes, hs = carry0, [], []
        for t in range(5):  # reference: the acting-time step, one at a time
            hs.append(carry[1])
            carry, mix = wm.rnn_step(cfg, p, carry, z[t], a[t])
            mixes.append(mix)
        return seq, (carry, jax.tree.map(lambda *x: jnp.stack(x), *mixes), jnp.stack(hs))

    seq, ref = both(st.rnn)
    for x, y in zip(jax.tree.leaves(seq), jax.tree.leaves(ref)):
        np.testing.assert_allclose(x, y, rtol=1e-5, atol=1e-6)


def test_adam_follows_optax_adam():
    """The learner's Adam (written so XLA cannot reassociate it) is Adam: over 50 steps of a
    noisy quadratic its parameters track optax.adam's to float rounding."""
    target = jnp.linspace(-3.0, 3.0, 24).reshape(4, 6)
    params = {"w": jnp.zeros((4, 6)), "b": jnp.ones((6,))}
    ours, ref = wm.adam(1e-2), optax.adam(1e-2)
    p_ours, p_ref = params, params
    s_ours, s_ref = ours.init(params), ref.init(params)
    loss = lambda p, k: jnp.sum(jnp.square(p["w"] + p["b"] - target + 0.1 * jax.random.normal(k, (4, 6))))  # noqa: E731
    for i in range(50):
        k = jax.random.PRNGKey(i)
        u, s_ours = ours.update(jax.grad(loss)(p_ours, k), s_ours, p_ours)
        p_ours = optax.apply_updates(p_ours, u)
        u, s_ref = ref.update(jax.grad(loss)(p_ref, k), s_ref, p_ref)
        p_ref = optax.apply_updates(p_ref, u)
    for name in params:
        np.testing.assert_allclose(p_ours[name], p_ref[name], rtol=2e-5, atol=2e-6)
    assert not np.allclose(p_ours["w"], 0.0)  # it moved
    assert int(s_ours.count) == 50


# ----------------------------------------------------------------------------------------
# The acting loop's latents (mjx_curio/run.py)
# ----------------------------------------------------------------------------------------

RUN_LEARNER = LearnerConfig(image=8, n_agents=1, latent=4, vae_channels=(8, 8, 8, 8), dec_channels=(8, 8, 8, 8),
                            rnn_hidden=8, mixtures=2, self_hidden=8, batch=2, seq_len=2)


def _run_cfg(**learner):
    from mjx_curio.run import RunConfig

    return RunConfig(n_agents=1, image=8, buffer=8, learner=dataclasses.replace(RUN_LEARNER, **learner))


def _posterior_draw(cfg, vae, frames, key):
    """mu + sigma * eps with eps drawn from `key`: the expected z=sample latent, computed apart."""
    mu, logvar = (np.asarray(x) for x in wm.encode(cfg, vae, frames))
    return mu + np.exp(0.5 * logvar) * np.asarray(jax.random.normal(key, mu.shape)), mu


@pytest.mark.slow
def test_a_run_starts_from_a_posterior_sample_drawn_from_its_seed():
    """init_run with z=sample: the first views' latent is a posterior draw whose noise is the
    run key's fourth split (the first three are the arena's, the networks' and the run's
    stream, as before the draw existed); the same key gives the same run."""
    from mjx_curio import policies
    from mjx_curio import run as run_lib

    policy = policies.PolicyParams(jnp.int32(0), jnp.float32(0.2), jnp.float32(1.5), jnp.float32(1.0))
    key = run_lib.key_for_seed(3)
    init = jax.jit(run_lib.init_run, static_argnums=0)
    cfg = _run_cfg()
    s = init(cfg, key, policy)
    expected, mu = _posterior_draw(cfg.learner, s.learner.vae, s.frames, jax.random.split(key, 4)[3])
    np.testing.assert_allclose(np.asarray(s.z), expected, rtol=1e-5, atol=1e-6)
    assert np.all(np.abs(np.asarray(s.z) - mu) > 0)
    np.testing.assert_array_equal(np.asarray(init(cfg, key, policy).z), np.asarray(s.z))
    np.testing.assert_array_equal(np.asarray(s.key), np.asarray(jax.random.split(key, 3)[2]))


@pytest.mark.slow
def test_acting_and_learning_use_posterior_samples_from_the_run_key():
    """act and learn with z=sample: the latent of the new view (the next step's self-model and
    memory input, and this step's curiosity target) is a posterior draw with the noise of the
    step key's third split; learn re-encodes the current view with the updated VAE and the
    fourth split; the curiosity is the mean squared error over the latent dimensions, and its
    spread the mean posterior variance of the new view."""
    from mjx_curio import policies
    from mjx_curio import run as run_lib

    cfg = _run_cfg()
    lc = cfg.learner
    policy = policies.PolicyParams(jnp.int32(0), jnp.float32(0.2), jnp.float32(1.5), jnp.float32(1.0))
    s = jax.jit(run_lib.init_run, static_argnums=0)(cfg, run_lib.key_for_seed(4), policy)
    act = jax.jit(lambda s: run_lib.act(cfg, s))
    for _ in range(4):  # enough replay for one learner update (seq_len + 1 steps)
        before = s
        s, m = act(s)
    expected, _ = _posterior_draw(lc, s.learner.vae, s.frames, jax.random.split(before.key, 3)[2])
    np.testing.assert_allclose(np.asarray(s.z), expected, rtol=1e-5, atol=1e-6)
    _, mix = wm.rnn_step(lc, before.learner.rnn, before.carry, before.z, m["action"])
    mean_sq = np.mean(np.square(expected - np.asarray(wm.mixture_mean(mix))), axis=-1)
    np.testing.assert_allclose(np.asarray(m["curiosity"]), mean_sq, rtol=1e-4, atol=1e-6)
    _, logvar = wm.encode(lc, s.learner.vae, s.frames)
    np.testing.assert_allclose(np.asarray(m["curiosity_spread"]), np.mean(np.exp(np.asarray(logvar)), axis=-1),
                               rtol=1e-5)

    learned, lm = jax.jit(lambda s: run_lib.learn(cfg, s))(s)
    assert int(lm["updated"]) == 1
    expected, _ = _posterior_draw(lc, learned.learner.vae, s.frames, jax.random.split(s.key, 4)[3])
    np.testing.assert_allclose(np.asarray(learned.z), expected, rtol=1e-5, atol=1e-6)
