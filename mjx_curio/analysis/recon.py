"""Reconstructions: real views and what a run's VAE makes of them at its checkpoints (figs 7, 13).

`reconstructions(sweep, run, steps)` restores the run's VAE from each checkpoint (JAX, imported
when called) and returns a `Reconstructions`; `figures.plot_reconstructions` draws it. Imports
`sweeps` and no other module of this package.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Sequence

import numpy as np

from mjx_curio.analysis.sweeps import Run, Sweep, SweepError


# ---------------------------------------------------------------------------- reconstructions


@dataclasses.dataclass
class Reconstructions:
    """Real views and what a run's VAE makes of them at several checkpoints (figs 7, 13)."""

    run: Run
    steps: list[int]  # checkpoints whose VAE decoded the frames
    frames: np.ndarray  # uint8 [N, H, W, 3], the real views
    sources: list[tuple[int, int, int]]  # (checkpoint step, run index, agent) each frame comes from
    decoded: dict[int, np.ndarray]  # step -> float [N, H, W, 3] in [0, 1]


@functools.lru_cache(maxsize=None)
def _autoencoder(cfg):
    import jax

    from mjx_curio import world_model as wm

    def f(params, frames):
        mu, _ = wm.encode(cfg, params, frames)
        return wm.decode(cfg, params, mu)

    return jax.jit(f)


def reconstructions(sweep: Sweep, run: int | str = 0, steps: Sequence[int] | None = None, n_frames: int = 8) -> Reconstructions:
    """Encode real views with run `run`'s VAE restored from each checkpoint in `steps` (default:
    the earliest and the latest) and decode the latent means.

    The real views are the views the agents had at those checkpoints, as the checkpoints store
    them (`RunState.frames`: every agent's current view, exactly what the VAE was fed at that
    step): first run `run`'s own, then other runs' (same arena, other places), up to `n_frames`.
    """
    r = sweep.run(run)
    all_steps = sweep.checkpoint_steps()
    if not all_steps:
        raise SweepError(f"{sweep.path} has no checkpoints in {sweep.checkpoints_dir / 'state'}")
    steps = [all_steps[0], all_steps[-1]] if steps is None else [sweep.check_step(s) for s in steps]
    steps = list(dict.fromkeys(steps))
    own, others = [], []
    for s in steps:
        frames = sweep.restore_raw(s)["frames"]  # [runs(+pad), agents, H, W, 3]
        for i in range(sweep.n_runs):
            for a in range(sweep.n_agents):
                (own if i == r.index else others).append(((s, i, a), frames[i, a]))
    # Other runs' views interleaved across runs, so a few columns show several runs.
    others.sort(key=lambda x: (x[0][1] % max(1, sweep.n_runs), x[0][0], x[0][2]))
    chosen = (own + others)[:n_frames]
    sources = [c[0] for c in chosen]
    frames = np.stack([c[1] for c in chosen]).astype(np.uint8)
    cfg = sweep.learner_config()
    decoded = {}
    for s in steps:
        vae = sweep.params(s, r.index)["vae"]
        decoded[s] = np.clip(np.asarray(_autoencoder(cfg)(vae, frames)), 0.0, 1.0)
    return Reconstructions(r, steps, frames, sources, decoded)
