"""How much of a step's curiosity nothing could foresee: the sampling noise of the latent.

With `z=sample` (the paper's z ~ q(z|o), the authors' code) a step's curiosity is

    c = mean_d (z_d - m_d)^2,   z = mu + sigma * eps,   eps ~ N(0, I)

(`world_model.curiosity`; the sum over d with `curiosity=sum`), where m is the MDN-RNN's
expectation for the next latent and (mu, sigma) the encoder's posterior of the next view. The
eps drawn at that step is unknown when the agent acts, so no self-model, however good, predicts
that part. Per latent dimension, with a = mu - m, (a + sigma eps)^2 has mean a^2 + sigma^2 and
variance 4 a^2 sigma^2 + 2 sigma^4, and the dimensions are independent:

    E[c] = mean_d (a_d^2 + sigma_d^2),   Var[c] = sum_d (4 a_d^2 sigma_d^2 + 2 sigma_d^4) / D^2

(without the 1/D and 1/D^2 for `curiosity=sum`; 0 for `z=mean`). Of E[c], mean_d sigma_d^2 comes
from the noise alone: a latent dimension the VAE leaves unused (its posterior the prior, sigma = 1,
mu = 0, which the MDN-RNN predicts exactly) still adds 1/D to the curiosity and 2/D^2 to its
variance at every step. Within windows of steps, the
variance of c is then the mean noise Var[c] plus the variance of E[c] across steps, and for any
predictor f that knows only what the agent knew when it acted, corr(f, c) <= sd(E[c]) / sd(c) =
sqrt(1 - noise share): the ceiling a per-step test of the self-model can reach.

`curiosity_noise(sweep, run)` restores a run's networks from the checkpoint that kept its replay
buffer (the newest) and evaluates this on every pair of consecutive steps in that buffer, from the
inputs the agents acted on (memory carry, latent, action) and the next step's views, with the
checkpoint's networks (the buffer spans the last `capacity` steps, so its oldest inputs were made
by earlier networks). Imports `sweeps` and `action_values` and no other module of this package;
JAX is imported when called.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from mjx_curio.analysis.action_values import replay_step
from mjx_curio.analysis.sweeps import Run, Sweep, SweepError


@dataclasses.dataclass
class CuriosityNoise:
    """Per pair of consecutive steps in a run's replay buffer, oldest first, and agent."""

    run: Run
    step: int  # the checkpoint whose networks evaluated the buffer it kept
    expected: np.ndarray  # float [steps, agents]: E[c] over the latent's sampling noise
    noise_var: np.ndarray  # float [steps, agents]: Var[c] over that noise
    spread: np.ndarray  # float [steps, agents]: mean_d sigma_d^2 (sum for curiosity=sum), E[c]'s part from the noise
    predicted: np.ndarray  # float [steps, agents]: the self-model's prediction for the action taken
    taken: np.ndarray  # int [steps, agents]: the action taken

    def _windows(self, x: np.ndarray, window: int) -> np.ndarray:
        """[steps, agents] -> [windows, window, agents], the last incomplete window dropped."""
        if not (isinstance(window, (int, np.integer)) and window >= 2):
            raise ValueError(f"window={window!r}: want a whole number of steps >= 2")
        n = (x.shape[0] // window) * window
        if n == 0:
            raise ValueError(f"window={window}: longer than the {x.shape[0]} steps evaluated")
        return x[:n].reshape((n // window, window) + x.shape[1:])

    def within_var(self, x: np.ndarray, window: int = 20) -> np.ndarray:
        """[agents]: the mean over windows of x's variance over the window's steps."""
        return self._windows(x, window).var(axis=1).mean(axis=0)

    def within_corr(self, x: np.ndarray, y: np.ndarray, window: int = 20) -> np.ndarray:
        """[agents]: the pooled within-window correlation of x and y ([steps, agents] each): the
        Pearson correlation after each window's means are taken out."""
        xw, yw = self._windows(x, window), self._windows(y, window)
        xd, yd = xw - xw.mean(axis=1, keepdims=True), yw - yw.mean(axis=1, keepdims=True)
        return (xd * yd).sum(axis=(0, 1)) / np.sqrt((xd**2).sum(axis=(0, 1)) * (yd**2).sum(axis=(0, 1)))

    def noise_share(self, window: int = 20) -> np.ndarray:
        """[agents]: the share of the within-window variance of the curiosity that is sampling
        noise, mean Var[c] / (mean Var[c] + within-window variance of E[c])."""
        noise = self._windows(self.noise_var, window).mean(axis=(0, 1))
        return noise / (noise + self.within_var(self.expected, window))

    def ceiling(self, window: int = 20) -> np.ndarray:
        """[agents]: the highest within-window correlation with the curiosity obtained that a
        predictor of what the agent knew can reach, sqrt(1 - noise share)."""
        return np.sqrt(1.0 - self.noise_share(window))

    def action_means(self) -> np.ndarray:
        """[steps, agents]: each step's E[c] predicted by its action's mean E[c] over the buffer
        (the same agent's steps; fitted on the whole buffer, so as good as counting gets)."""
        out = np.empty_like(self.expected)
        for agent in range(self.expected.shape[1]):
            a, e = self.taken[:, agent], self.expected[:, agent]
            means = np.bincount(a, weights=e) / np.maximum(np.bincount(a), 1)
            out[:, agent] = means[a]
        return out

    def tracking(self, window: int = 20) -> dict:
        """Within-window correlations [agents]: "self" of the self-model's prediction with E[c],
        "actions" of the action means with E[c], and "ceiling"."""
        return {"self": self.within_corr(self.predicted, self.expected, window),
                "actions": self.within_corr(self.action_means(), self.expected, window),
                "ceiling": self.ceiling(window)}


@functools.lru_cache(maxsize=None)
def _evaluate(cfg):
    import jax
    import jax.numpy as jnp

    from mjx_curio import world_model as wm

    mean = cfg.curiosity == "mean"

    def one(params, c, h, z, a, next_frames):  # one step: z [agents, Z], a [agents], frames [agents, H, W, 3]
        _, mix = wm.rnn_step(cfg, params["rnn"], (c, h), z, a)
        mu, logvar = wm.encode(cfg, params["vae"], next_frames, params["vae_stats"])
        sq = jnp.square(mu - wm.mixture_mean(mix))
        var = jnp.exp(logvar) if cfg.z == "sample" else jnp.zeros_like(logvar)
        spread, noise = jnp.sum(var, -1), jnp.sum(4 * sq * var + 2 * var**2, -1)
        expected = jnp.sum(sq, -1) + spread
        d = cfg.latent
        if mean:
            expected, noise, spread = expected / d, noise / d**2, spread / d
        q = wm.predict_curiosity(cfg, params["self_model"], z, h)
        return expected, noise, spread, jnp.take_along_axis(q, a[:, None], axis=1)[:, 0]

    return jax.jit(jax.vmap(one, in_axes=(None, 0, 0, 0, 0, 0)))


def curiosity_noise(sweep: Sweep, run: int | str = 0, step: int | None = None, chunk: int = 500,
                    zero_state: bool = False) -> CuriosityNoise:
    """Run `run`'s networks restored from checkpoint `step` (default: the newest that kept its
    replay buffer), evaluated on every pair of consecutive steps in that buffer, in time order (the
    buffer is a ring), `chunk` steps at a time. `zero_state`: the memory (and the self-models'
    view of it) starts each step from a zero carry instead of the one the agents acted with, as
    the authors' code computes the curiosity it logs (README, Fidelity): the same steps without
    their history."""
    if not (isinstance(chunk, (int, np.integer)) and chunk >= 1):
        raise ValueError(f"chunk={chunk!r}: want a whole number of steps >= 1")
    r = sweep.run(run)
    step = replay_step(sweep, step)
    rp = sweep.restore_replay(step, keys=("frames", "latents", "carry", "actions", "index", "size"))
    i = r.index
    size, head, cap = int(rp["size"][i]), int(rp["index"][i]), rp["actions"].shape[1]
    if size < 2:
        raise SweepError(f"{sweep.path}: run {r.name}'s replay buffer at step {step} holds {size} step(s); want 2 or more")
    order = (head - size + np.arange(size)) % cap  # oldest first
    now, nxt = order[:-1], order[1:]
    params = sweep.params(step, i)
    f = _evaluate(sweep.learner_config())
    c, h = rp["carry"]["0"][i], rp["carry"]["1"][i]
    if zero_state:
        c, h = np.zeros_like(c), np.zeros_like(h)
    z, a, frames = rp["latents"][i], rp["actions"][i], rp["frames"][i]
    n = len(now)
    pad = -n % chunk  # every chunk the same shape: one compilation
    now_p, nxt_p = np.concatenate([now, np.repeat(now[-1:], pad)]), np.concatenate([nxt, np.repeat(nxt[-1:], pad)])
    parts = [f(params, c[s], h[s], z[s], a[s], frames[nx])
             for s, nx in ((now_p[k:k + chunk], nxt_p[k:k + chunk]) for k in range(0, n + pad, chunk))]
    expected, noise, spread, predicted = (np.concatenate([np.asarray(p[j], np.float64) for p in parts])[:n]
                                          for j in range(4))
    return CuriosityNoise(r, step, expected, noise, spread, predicted, np.asarray(a[now]))


@functools.lru_cache(maxsize=None)
def _variances(cfg):
    import jax
    import jax.numpy as jnp

    from mjx_curio import world_model as wm

    return jax.jit(lambda vae, stats, frames: jnp.exp(wm.encode(cfg, vae, frames, stats)[1]))


def posterior_spread(sweep: Sweep, run: int | str = 0, steps=None, every: int = 10, step: int | None = None) -> dict:
    """{checkpoint step: mean over views and agents of the posterior's mean_d sigma_d^2} for run
    `run`'s VAE at each of `steps` (default: every kept checkpoint), on every `every`-th view of the
    replay buffer kept at `step` (default: the newest): one set of views, so that only the encoder
    differs. The part of the mean curiosity that the sampling noise alone adds, over training."""
    reduce = np.mean if sweep.learner_config().curiosity == "mean" else np.sum
    return {k: float(reduce(v)) for k, v in posterior_dims(sweep, run, steps, every, step).items()}


def posterior_dims(sweep: Sweep, run: int | str = 0, steps=None, every: int = 10, step: int | None = None) -> dict:
    """{checkpoint step: float [latent]}: each latent dimension's posterior variance sigma_d^2,
    mean over the views and agents of `posterior_spread` (the same arguments). A dimension near 1
    is one the VAE has all but stopped using: its posterior is nearly the prior, whatever the view."""
    if not (isinstance(every, (int, np.integer)) and every >= 1):
        raise ValueError(f"every={every!r}: want a whole number of views >= 1")
    r = sweep.run(run)
    step = replay_step(sweep, step)
    rp = sweep.restore_replay(step, keys=("frames", "size"))
    frames = rp["frames"][r.index, :int(rp["size"][r.index]):every]
    cfg = sweep.learner_config()
    f = _variances(cfg)
    steps = sweep.checkpoint_steps() if steps is None else [sweep.check_step(s) for s in steps]
    params = {int(s): sweep.params(s, r.index) for s in steps}
    return {s: np.asarray(f(p["vae"], p["vae_stats"], frames), np.float64).reshape(-1, cfg.latent).mean(0)
            for s, p in params.items()}
