"""The authors' memory and its batch pairing (mjx_curio/analysis/authors_memory.py): the pairing
against the authors' list arithmetic done with Python lists, the memory on planted latents whose
successor only the action decides, and the whole on the tiny sweep's replay buffers."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from mjx_curio import analysis as an
from mjx_curio.analysis import authors_memory as am


def test_the_authors_pairing_is_their_flatten_then_cut():
    # The authors' update: views flattened transition by transition, then cut into blocks per agent.
    obs_t = [(f"t{t}a0", f"t{t}a1") for t in range(16)]  # a sampled batch: per transition, each agent's view
    flat = [item for sublist in obs_t for item in sublist]
    blocks = [flat[i * 16:(i + 1) * 16] for i in range(2)]
    trans, agent = am.authors_pairing(16, 2)
    assert [[f"t{t}a{a}" for t, a in zip(trans[i], agent[i])] for i in range(2)] == blocks
    assert blocks[0][:4] == ["t0a0", "t0a1", "t1a0", "t1a1"] and blocks[1][0] == "t8a0"
    # One agent: the block is the batch, in order, as the matched pairing has it.
    for a, b in zip(am.authors_pairing(16, 1), am.matched_pairing(16, 1)):
        np.testing.assert_array_equal(a, b)
    trans, agent = am.matched_pairing(4, 2)
    assert trans.tolist() == [[0, 1, 2, 3]] * 2 and agent.tolist() == [[0] * 4, [1] * 4]
    with pytest.raises(ValueError, match="pairing='shuffled': choose one of authors, matched"):
        am.pairing("shuffled", 16, 2)


def test_only_the_matched_pairing_learns_what_the_action_decides():
    # Planted: each agent's next latent is a fixed vector of the action it took, the views' posteriors
    # nearly exact. A memory given each transition's own actions learns it; the authors' pairing
    # hands it other transitions' actions, so it can learn only the mean, and logs the spread of
    # those vectors over the actions.
    rng = np.random.default_rng(0)
    n, n_actions, latent = 400, 7, 4
    effect = rng.normal(size=(n_actions, latent)).astype(np.float32)
    actions = rng.integers(0, n_actions, size=(n, 2))
    mu = np.zeros((n, 2, latent), np.float32)
    mu[1:] = effect[actions[:-1]]
    sigma = np.full_like(mu, 0.01)
    spread = float(effect[actions[:-1]].var(axis=0).mean())  # what predicting the mean leaves
    params = am.init_memory(jax.random.PRNGKey(0), latent, n_actions, 2)
    logged = {}
    for name in am.PAIRINGS:
        train = am._trainer(1500, 16, 2, n_actions, name)
        logged[name] = np.asarray(train(params, jax.random.PRNGKey(1), jnp.asarray(mu), jnp.asarray(sigma),
                                        jnp.asarray(actions), jnp.arange(n - 1), jnp.arange(1, n)))
    late = {k: v[-300:].mean() for k, v in logged.items()}
    assert logged["authors"].shape == (1500, 2)
    assert late["matched"] < 0.05 * spread
    assert late["authors"] == pytest.approx(spread, rel=0.25)


def test_logged_curiosity_on_the_tiny_sweeps(tiny_sweep, tiny_single_sweep):
    sweep = an.load(tiny_sweep)
    out = am.logged_curiosity(sweep, 0, updates=40)
    assert out["logged"].shape == (40, 2) and np.isfinite(out["logged"]).all()
    # The floor is the buffer's mean posterior variance, from the run's own encoder.
    step = sweep.replay_steps()[-1]
    rp = sweep.restore_replay(step, keys=("frames", "size"))
    frames = rp["frames"][0, :int(rp["size"][0])]
    from mjx_curio import world_model as wm
    _, logvar = wm.encode(sweep.learner_config(), sweep.params(step, 0)["vae"], frames)
    assert out["floor"] == pytest.approx(float(np.exp(np.asarray(logvar, np.float64)).mean()), rel=1e-4)
    # Same seed, same numbers (one program); one agent's two pairings are one pairing.
    np.testing.assert_array_equal(am.logged_curiosity(sweep, 0, updates=40)["logged"], out["logged"])
    single = an.load(tiny_single_sweep)
    a, b = (am.logged_curiosity(single, 0, updates=30, pairing_name=p)["logged"] for p in am.PAIRINGS)
    assert a.shape == (30, 1)
    np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError, match="updates=0"):
        am.logged_curiosity(sweep, 0, updates=0)
    with pytest.raises(ValueError, match="pairing_name='both': choose one of authors, matched"):
        am.logged_curiosity(sweep, 0, pairing_name="both")
