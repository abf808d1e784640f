"""Reconstructions: real views and what a run's VAE makes of them at its checkpoints (figs 7, 13).

`reconstructions(sweep, run, steps)` restores the run's VAE from each checkpoint (JAX, imported
when called) and returns a `Reconstructions`; `figures.plot_reconstructions` draws it.
`reconstruction_quality(sweep)` puts the figures' "sharper over training" in numbers: each run's
VAE at each checkpoint on views from the other runs' replay buffers, its squared error and how
far its edges are from the real ones (`edge_error`). Imports `sweeps` and no other module of this package.
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

    def f(params, stats, frames):  # stats: the VAE's running averages (sweep.params' "vae_stats")
        mu, _ = wm.encode(cfg, params, frames, stats)
        return wm.decode(cfg, params, mu, stats)

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
        p = sweep.params(s, r.index)
        decoded[s] = np.clip(np.asarray(_autoencoder(cfg)(p["vae"], p["vae_stats"], frames)), 0.0, 1.0)
    return Reconstructions(r, steps, frames, sources, decoded)


# ---------------------------------------------------------------------------- reconstruction quality


def edge_error(decoded, real) -> float:
    """How far the edges of reconstructions `decoded` are from those of the `real` images (float
    [N, H, W, C], same scale): the summed absolute difference of their neighbouring-pixel
    differences (both directions, every channel) over the real images' summed absolute
    differences. 0: every edge as in the real image; about 1: a blur that keeps no edge; above 1:
    edges where the real image has none (noise, artefacts)."""
    d, r = np.asarray(decoded, np.float64), np.asarray(real, np.float64)
    miss = sum(np.abs(np.diff(d, axis=ax) - np.diff(r, axis=ax)).sum() for ax in (-3, -2))
    total = sum(np.abs(np.diff(r, axis=ax)).sum() for ax in (-3, -2))
    return float(miss / total) if total > 0 else float("nan")


@dataclasses.dataclass
class ReconstructionQuality:
    """How well each run's VAE, restored from several checkpoints, reconstructs views it never
    trained on: the other runs' replay frames (figs 7 and 13 in numbers, a value per run)."""

    steps: list[int]  # checkpoints whose VAEs were measured
    replay_step: int  # the checkpoint whose replay buffers gave the frames
    frames_per_run: int  # slots taken from each run's buffer (every agent's view of each)
    error: np.ndarray  # [runs, steps]: mean over the held-out frames of the summed squared pixel
    #                    error (pixels in [0, 1]: the VAE loss's reconstruction term per image)
    edge_error: np.ndarray  # [runs, steps]: `edge_error` of the reconstructions (0: every edge kept)
    error_by_source: np.ndarray  # [runs, runs, steps]: `error` on the frames of one other run at a
    #                              time ([i, j]: run i's VAE on run j's frames; NaN where i == j)


def heldout_slots(size: int, n: int) -> np.ndarray:
    """`n` slots evenly spread over a buffer's `size` written slots (all of them if fewer)."""
    if size <= 0:
        return np.zeros(0, int)
    return np.unique(np.linspace(0, size - 1, min(n, size)).round().astype(int))


def reconstruction_quality(sweep: Sweep, steps: Sequence[int] | None = None, frames_per_run: int = 32) -> ReconstructionQuality:
    """Every run's VAE at each checkpoint in `steps` (default: all) encodes and decodes (the
    latent mean) the frames of every *other* run's replay buffer at the newest checkpoint,
    `frames_per_run` slots a run spread evenly over its buffer, every agent's view of each: the
    same arena seen from places its own run never stored. Per run and step, the mean summed
    squared error and the `edge_error` of the reconstructions, and the error on each other run's
    frames apart (which tells a VAE that generalises worse from views that are harder)."""
    replay_steps = sweep.replay_steps()
    if not replay_steps:
        raise SweepError(f"{sweep.path} has no replay buffers in its checkpoints (save_replay=false?)")
    if frames_per_run < 1:
        raise ValueError(f"frames_per_run={frames_per_run} must be at least 1")
    replay_step = replay_steps[-1]
    all_steps = sweep.checkpoint_steps()
    steps = all_steps if steps is None else list(dict.fromkeys(sweep.check_step(s) for s in steps))
    replay = sweep.restore_replay(replay_step, keys=("frames", "size"))
    runs = sweep.n_runs
    sizes = np.broadcast_to(np.asarray(replay["size"]).reshape(-1), (len(replay["frames"]),))
    per_run = []
    for i in range(runs):
        slots = heldout_slots(int(sizes[i]), frames_per_run)
        f = np.asarray(replay["frames"][i][slots])  # [slots, agents, H, W, 3]
        per_run.append(f.reshape((-1,) + f.shape[-3:]))
    cfg = sweep.learner_config()
    error = np.full((runs, len(steps)), np.nan)
    edges = np.full((runs, len(steps)), np.nan)
    by_source = np.full((runs, runs, len(steps)), np.nan)
    for k, s in enumerate(steps):  # steps outside: the sweep caches two checkpoints, not all
        for i in range(runs):
            sources = [j for j in range(runs) if j != i]
            frames = np.concatenate([per_run[j] for j in sources]) if sources else np.zeros((0,))
            if not len(frames):
                continue
            real = frames.astype(np.float64) / 255.0
            p = sweep.params(s, i)
            decoded = np.asarray(_autoencoder(cfg)(p["vae"], p["vae_stats"], frames), np.float64)
            per_frame = np.square(decoded - real).sum(axis=(1, 2, 3))
            error[i, k] = per_frame.mean()
            edges[i, k] = edge_error(decoded, real)
            bounds = np.cumsum([0] + [len(per_run[j]) for j in sources])
            for j, a, b in zip(sources, bounds[:-1], bounds[1:]):
                by_source[i, j, k] = per_frame[a:b].mean() if b > a else np.nan
    return ReconstructionQuality(steps, replay_step, frames_per_run, error, edges, by_source)
