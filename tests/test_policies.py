"""Controllers: the statistics of each policy, one shared program, bad settings rejected."""

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from mjx_curio import policies
from mjx_curio.config import POLICY_IDS, ConfigError, PolicyConfig

N_DRAWS = 40_000
CHI2_CRIT_6DOF = 22.458  # chi-square, 6 degrees of freedom, p = 0.001
Q = np.array([0.3, -0.2, 1.1, 0.9, 0.0, 0.5, 1.0], np.float32)  # argmax = 2


@pytest.fixture(scope="module")
def draw():
    """Many independent single-agent selections in one compiled call; every setting traced."""

    @jax.jit
    def draw(policy_id, q, counts, t, eps, temperature, c, key):
        keys = jax.random.split(key, N_DRAWS)
        return jax.vmap(lambda k: policies.select(policy_id, q, k, counts, t, eps, temperature, c))(keys)

    counts = jnp.ones((7,), jnp.int32)

    def run(policy_id, eps=0.2, temperature=1.5, c=1.0, q=Q, seed=0):
        out = draw(policy_id, jnp.asarray(q), counts, 7, eps, temperature, c, jax.random.PRNGKey(seed))
        return np.bincount(np.asarray(out), minlength=7)

    return run


@pytest.mark.parametrize("eps", [0.2, 0.6])
def test_epsilon_greedy_frequencies(draw, eps):
    freq = draw(POLICY_IDS["eps"], eps=eps, seed=int(eps * 10))
    p_best = 1 - eps + eps / 7
    sd = np.sqrt(N_DRAWS * p_best * (1 - p_best))
    assert abs(freq[2] - N_DRAWS * p_best) < 4.5 * sd, (freq, p_best)
    # every other action has probability eps / 7
    p_other = eps / 7
    sd_o = np.sqrt(N_DRAWS * p_other * (1 - p_other))
    for a in [0, 1, 3, 4, 5, 6]:
        assert abs(freq[a] - N_DRAWS * p_other) < 4.5 * sd_o, (a, freq)


def test_epsilon_zero_is_greedy_and_one_is_uniform(draw):
    assert draw(POLICY_IDS["eps"], eps=0.0)[2] == N_DRAWS
    freq = draw(POLICY_IDS["eps"], eps=1.0, seed=3)
    expected = N_DRAWS / 7
    assert np.sum((freq - expected) ** 2 / expected) < CHI2_CRIT_6DOF


@pytest.mark.parametrize("temperature", [0.5, 1.5])
def test_boltzmann_frequencies_match_softmax(draw, temperature):
    freq = draw(POLICY_IDS["boltzmann"], temperature=temperature, seed=7)
    p = np.exp(Q / temperature)
    p /= p.sum()
    expected = N_DRAWS * p
    chi2 = np.sum((freq - expected) ** 2 / expected)
    assert chi2 < CHI2_CRIT_6DOF, (chi2, freq, expected)
    # and the test can fail: the same draws are far from a different temperature's softmax
    p_wrong = np.exp(Q / (temperature * 2))
    p_wrong /= p_wrong.sum()
    assert np.sum((freq - N_DRAWS * p_wrong) ** 2 / (N_DRAWS * p_wrong)) > 10 * CHI2_CRIT_6DOF


def _ucb_numpy(q, steps, c):
    counts = np.zeros(7, np.int64)
    seq = []
    for t in range(steps):
        untried = np.flatnonzero(counts == 0)
        if untried.size:
            a = int(untried[0])
        else:
            a = int(np.argmax(q + c * np.sqrt(np.log(t) / counts)))
        counts[a] += 1
        seq.append(a)
    return seq


def test_ucb_tries_every_action_first_then_follows_the_formula():
    select = jax.jit(policies.select)
    update = jax.jit(policies.update_counts)
    q = np.array([0.9, 0.1, 0.5, 0.45, 0.2, 0.85, 0.3], np.float32)
    c = 0.3
    counts = jnp.zeros((7,), jnp.int32)
    key = jax.random.PRNGKey(0)
    seq = []
    for t in range(60):  # t = steps taken so far
        a = int(select(POLICY_IDS["ucb"], q, key, counts, t, 0.2, 1.5, c))
        counts = update(counts, a)
        seq.append(a)
    assert seq[:7] == list(range(7))  # untried first, lowest index first, despite q
    assert seq == _ucb_numpy(q, 60, c)
    assert len(set(seq[7:])) > 1  # the bonus really makes it revisit other actions
    np.testing.assert_array_equal(np.asarray(counts), np.bincount(seq, minlength=7))


def test_ucb_prefers_untried_over_high_value_actions():
    counts = jnp.array([5, 5, 0, 5, 0, 5, 5], jnp.int32)
    q = jnp.array([9.0, 9, -9, 9, -9, 9, 9])
    a = jax.jit(policies.ucb)(q, counts, 30, 1.0)
    assert int(a) == 2


def test_runs_with_different_policies_share_one_vmapped_program():
    """A sweep axis over runs: every run's policy and settings are data, not code."""
    q = jnp.asarray(np.random.default_rng(0).normal(size=(3, 2, 7)), jnp.float32)  # [runs, agents, A]
    counts = jnp.ones((3, 2, 7), jnp.int32)
    params = jax.tree.map(
        lambda *x: jnp.stack(x),
        *[policies.policy_params(PolicyConfig(policy=p)) for p in ("eps", "boltzmann", "ucb")],
    )
    keys = jax.random.split(jax.random.PRNGKey(1), 3)
    batched = jax.jit(jax.vmap(policies.select_agents, in_axes=(0, 0, 0, 0, None)))(params, q, keys, counts, 10)
    one = jax.jit(policies.select_agents)
    for r in range(3):
        p = jax.tree.map(lambda x: x[r], params)
        np.testing.assert_array_equal(batched[r], one(p, q[r], keys[r], counts[r], 10))
    # UCB with equal counts is argmax q for each agent
    np.testing.assert_array_equal(batched[2], np.argmax(np.asarray(q[2]), -1))


def test_update_counts_per_agent():
    counts = jnp.zeros((2, 7), jnp.int32)
    counts = policies.update_counts_agents(counts, jnp.array([3, 6]))
    counts = policies.update_counts_agents(counts, jnp.array([3, 0]))
    np.testing.assert_array_equal(counts, [[0, 0, 0, 2, 0, 0, 0], [1, 0, 0, 0, 0, 0, 1]])


@pytest.mark.parametrize(
    "kw, knob",
    [
        (dict(policy_id=3), "policy_id"),
        (dict(policy_id=-1), "policy_id"),
        (dict(policy_id=1.0), "policy_id"),
        (dict(eps=1.5), "eps"),
        (dict(eps=-0.1), "eps"),
        (dict(temperature=0.0), "temperature"),
        (dict(temperature=-1.0), "temperature"),
        (dict(c=0.0), "ucb_c"),
        (dict(c=float("nan")), "ucb_c"),
    ],
)
def test_make_policy_params_rejects_bad_values(kw, knob):
    args = dict(policy_id=0, eps=0.2, temperature=1.5, c=1.0) | kw
    with pytest.raises(ConfigError, match=knob):
        policies.make_policy_params(**args)


@pytest.mark.parametrize(
    "kw, knob",
    [
        (dict(policy="greedy"), "policy"),
        (dict(eps=2.0), "eps"),
        (dict(temperature=0.0), "temperature"),
        (dict(ucb_c=-1.0), "ucb_c"),
    ],
)
def test_policy_config_rejects_bad_values(kw, knob):
    with pytest.raises(ConfigError, match=knob):
        PolicyConfig(**kw)


def test_policy_ids_and_params():
    assert POLICY_IDS == {"eps": 0, "boltzmann": 1, "ucb": 2}
    p = policies.policy_params(PolicyConfig(policy="boltzmann", temperature=0.7))
    assert int(p.policy_id) == 1 and np.isclose(float(p.temperature), 0.7)
