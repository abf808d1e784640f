"""Controllers (paper 3.2.1): epsilon-greedy, Boltzmann and UCB over predicted curiosities.

Every policy is a pure function of one agent's q [n_actions]. `select` dispatches on a
*traced* policy id with `lax.switch`, and the policy's settings are traced arrays too, so
runs with different policies and settings share one compiled, vmapped program (under vmap
`lax.switch` evaluates all three branches and selects; each is a handful of flops).

Ties in argmax go to the lowest action index (jnp.argmax).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from mjx_curio.config import POLICY_IDS, ConfigError, PolicyConfig, check_float

EPS, BOLTZMANN, UCB = POLICY_IDS["eps"], POLICY_IDS["boltzmann"], POLICY_IDS["ucb"]


class PolicyParams(NamedTuple):
    """A run's controller settings as arrays (add a leading runs axis for a sweep)."""

    policy_id: jax.Array  # int32 scalar, see config.POLICY_IDS
    eps: jax.Array  # f32
    temperature: jax.Array  # f32
    c: jax.Array  # f32


def policy_params(cfg: PolicyConfig) -> PolicyParams:
    return make_policy_params(cfg.policy_id, cfg.eps, cfg.temperature, cfg.ucb_c)


def make_policy_params(policy_id, eps, temperature, c) -> PolicyParams:
    """Host-side constructor with the same checks as `PolicyConfig` (ConfigError on bad values)."""
    ok = not isinstance(policy_id, bool) and hasattr(policy_id, "__index__")
    if not ok or int(policy_id) not in POLICY_IDS.values():
        raise ConfigError(
            f"policy_id={policy_id!r} is not allowed; choose one of: "
            + ", ".join(f"{v} ({k})" for k, v in POLICY_IDS.items())
        )
    eps = check_float("eps", eps, 0.0, 1.0)
    temperature = check_float("temperature", temperature, 0.0, lo_open=True)
    c = check_float("ucb_c", c, 0.0, lo_open=True)
    return PolicyParams(
        jnp.asarray(int(policy_id), jnp.int32),
        jnp.asarray(eps, jnp.float32),
        jnp.asarray(temperature, jnp.float32),
        jnp.asarray(c, jnp.float32),
    )


# ----------------------------------------------------------------------------------------
# The three policies, one agent each
# ----------------------------------------------------------------------------------------


def epsilon_greedy(q, key, eps):
    """argmax q with probability 1 - eps, else a uniformly random action (may be the argmax)."""
    k_explore, k_action = jax.random.split(key)
    random_action = jax.random.randint(k_action, (), 0, q.shape[-1])
    explore = jax.random.uniform(k_explore) < eps
    return jnp.where(explore, random_action, jnp.argmax(q)).astype(jnp.int32)


def boltzmann(q, key, temperature):
    """Sample a ~ softmax(q / T)."""
    return jax.random.categorical(key, q / temperature).astype(jnp.int32)


def ucb_scores(q, counts, t, c):
    """q + c * sqrt(ln t / N(a)); +inf for untried actions (N = 0)."""
    n = counts.astype(q.dtype)
    bonus = c * jnp.sqrt(jnp.log(jnp.maximum(t, 1).astype(q.dtype)) / jnp.maximum(n, 1.0))
    return jnp.where(counts > 0, q + bonus, jnp.inf)


def ucb(q, counts, t, c):
    """Untried actions first (lowest index first), then argmax of the UCB score.

    counts int [n_actions]: times each action was taken; t: steps taken so far.
    Deterministic: uses no key.
    """
    return jnp.argmax(ucb_scores(q, counts, t, c)).astype(jnp.int32)


def select(policy_id, q, key, counts, t, eps, temperature, c):
    """One agent's action. policy_id, eps, temperature, c may be traced; q [n_actions]."""
    branches = (
        lambda: epsilon_greedy(q, key, eps),
        lambda: boltzmann(q, key, temperature),
        lambda: ucb(q, counts, t, c),
    )
    return jax.lax.switch(jnp.asarray(policy_id, jnp.int32), branches)


def select_agents(params: PolicyParams, q, key, counts, t):
    """Every agent's action: q [n_agents, n_actions], counts [n_agents, n_actions] -> [n_agents].

    Each agent gets its own key; all agents of a run share the run's policy settings.
    """
    keys = jax.random.split(key, q.shape[0])
    return jax.vmap(lambda qq, kk, cc: select(params.policy_id, qq, kk, cc, t, params.eps, params.temperature, params.c))(
        q, keys, counts
    )


def update_counts(counts, action):
    """UCB's N(a): one agent counts [n_actions] += one_hot(action); vmap for agents."""
    return counts + jax.nn.one_hot(action, counts.shape[-1], dtype=counts.dtype)


def update_counts_agents(counts, actions):
    """counts [n_agents, n_actions], actions [n_agents]."""
    return jax.vmap(update_counts)(counts, actions)
