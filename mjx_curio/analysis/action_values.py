"""What a run's self-models predict for each action at the states the run visited.

Every policy chooses from the predicted curiosity q of the seven actions that an agent's
self-model gives (paper 3.2.1), and how far apart those predictions lie decides what a policy can
make of them: the Boltzmann policy samples softmax(q / T), nearly uniform where the spread of q is
small against T. The metrics record only the prediction for the action taken, so
`action_values(sweep, run)` restores a run's self-models from a checkpoint that kept its replay
buffer (the newest) and evaluates them on every state in that buffer: the (z_t, h_t) each agent
acted on in its last `buffer` steps, as they were when it acted. Imports `sweeps` and no other
module of this package; JAX is imported when called.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from mjx_curio.analysis.sweeps import Run, Sweep, SweepError


@dataclasses.dataclass
class ActionValues:
    """A run's self-models' predicted curiosity of every action, on the states of its replay."""

    run: Run
    step: int  # the checkpoint whose self-models predicted (and whose replay held the states)
    actions: tuple[str, ...]  # the action names, in q's last axis
    q: np.ndarray  # float [states, agents, actions]: predicted curiosity (squared latent distance)
    taken: np.ndarray  # int [states, agents]: the action each agent took in that state

    def spread(self) -> np.ndarray:
        """[states, agents]: the largest minus the smallest prediction over the actions."""
        return self.q.max(axis=-1) - self.q.min(axis=-1)

    def boltzmann(self, temperature: float) -> np.ndarray:
        """[states, agents, actions]: the Boltzmann policy's probabilities softmax(q / T) there."""
        if not temperature > 0:
            raise ValueError(f"temperature={temperature!r}: want a number above 0")
        x = self.q / temperature
        e = np.exp(x - x.max(axis=-1, keepdims=True))
        return e / e.sum(axis=-1, keepdims=True)

    def favoured_probability(self, temperatures) -> np.ndarray:
        """[len(temperatures)]: how greedy softmax(q / T) is on these states at each T, as the
        probability of each state's most favoured action, mean over states and agents (1 /
        n_actions for a uniform choice, 1 for argmax)."""
        return np.array([self.boltzmann(t).max(axis=-1).mean() for t in np.atleast_1d(temperatures)])


@functools.lru_cache(maxsize=None)
def _predict(cfg):
    import jax

    from mjx_curio import world_model as wm

    # states [N]: z [N, agents, Z], h [N, hidden] -> [N, agents, actions]
    return jax.jit(jax.vmap(lambda params, z, h: wm.predict_curiosity(cfg, params, z, h), in_axes=(None, 0, 0)))


def replay_step(sweep: Sweep, step: int | None = None) -> int:
    """`step` (default: the newest checkpoint that kept the replay buffers), checked to be a
    checkpoint that kept them."""
    steps = sweep.replay_steps()
    if not steps:
        raise SweepError(f"{sweep.path} has no replay buffers in {sweep.checkpoints_dir / 'replay'} "
                         "(the sweep ran with save_replay=false, or has no checkpoint yet)")
    step = steps[-1] if step is None else int(step)
    if step not in steps:
        sweep.restore_replay(step)  # raises SweepError, naming the steps that kept them
    return step


def action_values(sweep: Sweep, run: int | str = 0, step: int | None = None) -> ActionValues:
    """Run `run`'s self-models restored from checkpoint `step` (default: the newest that kept its
    replay buffer), evaluated on every state in that buffer (its valid slots, oldest not first:
    the buffer is a ring)."""
    r = sweep.run(run)
    step = replay_step(sweep, step)
    replay = sweep.restore_replay(step)
    size = int(replay["size"][r.index])
    z = replay["latents"][r.index, :size]  # [N, agents, Z]
    h = replay["carry"]["1"][r.index, :size]  # [N, hidden]: the LSTM's h (carry is (c, h))
    params = sweep.params(step, r.index)["self_model"]
    q = np.asarray(_predict(sweep.learner_config())(params, z, h), np.float64)
    return ActionValues(r, step, tuple(sweep.actions), q, replay["actions"][r.index, :size])
