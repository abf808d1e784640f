"""Throughput of the learner on this machine: plain functions returning dicts.

`python -m mjx_curio.bench what=learner` calls these. Inputs are random (speed does not
depend on the pixel values); every timing is the best of `repeats` blocks of `iters`
calls after one compile-and-run call, measured with block_until_ready.

Reference (FACTS.md): the paper's PyTorch VAE update, batch 32 of 64x64 with Adam, runs
at about 234 images/s on this machine class.
"""

from __future__ import annotations

import dataclasses
import time

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)
import jax
import jax.numpy as jnp
import optax

from mjx_curio import world_model as wm
from mjx_curio.config import LearnerConfig


def _time(fn, args, iters: int, repeats: int):
    """(compile+first call seconds, best seconds per call); fn returns (carry..., out)."""
    t0 = time.perf_counter()
    out = fn(*args)
    jax.block_until_ready(out)
    first = time.perf_counter() - t0
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(iters):
            out = fn(*args)
        jax.block_until_ready(out)
        best = min(best, (time.perf_counter() - t0) / iters)
    return first, best


def bench_vae(image: int = 64, batch: int = 32, iters: int = 10, repeats: int = 3, seed: int = 0) -> dict:
    """VAE update throughput: forward + backward + Adam on `batch` frames of image x image."""
    cfg = LearnerConfig(image=image, n_agents=1)
    key = jax.random.PRNGKey(seed)
    state = wm.init_learner(cfg, key)
    opt = wm.optimizer(cfg)
    frames = jax.random.randint(key, (batch, 1, image, image, 3), 0, 256).astype(jnp.uint8)

    @jax.jit
    def step(params, opt_state, k):
        (loss, _), g = jax.value_and_grad(lambda p: wm.vae_loss(cfg, p, frames, k), has_aux=True)(params)
        u, opt_state = opt.update(g, opt_state, params)
        return optax.apply_updates(params, u), opt_state, loss

    # Donation-free loop on fixed inputs: each timed call starts from the same params,
    # which costs exactly what a training step costs.
    first, best = _time(step, (state.vae, state.vae_opt, key), iters, repeats)
    return {
        "what": "vae_update",
        "image": image,
        "batch": batch,
        "compile_s": round(first, 3),
        "step_ms": round(best * 1e3, 2),
        "images_per_s": round(batch / best, 1),
        "backend": jax.default_backend(),
    }


def bench_learner_update(
    image: int = 64,
    n_agents: int = 2,
    batch: int = 16,
    seq_len: int = 16,
    latents: str = "stored",
    iters: int = 5,
    repeats: int = 3,
    seed: int = 0,
) -> dict:
    """Time of one full `learner_update` (VAE + MDN-RNN + self-models) for one run."""
    cfg = LearnerConfig(image=image, n_agents=n_agents, batch=batch, seq_len=seq_len, latents=latents)
    key = jax.random.PRNGKey(seed)
    state = wm.init_learner(cfg, key)
    ks = jax.random.split(key, 4)
    shp = (batch, seq_len + 1, n_agents)
    data = wm.Batch(
        frames=jax.random.randint(ks[0], shp + (image, image, 3), 0, 256).astype(jnp.uint8),
        latents=jax.random.normal(ks[1], shp + (cfg.latent,)),
        actions=jax.random.randint(ks[2], shp, 0, cfg.n_actions),
        carry=(jnp.zeros((batch, seq_len + 1, cfg.rnn_hidden)),) * 2,
    )
    update = jax.jit(wm.learner_update, static_argnums=0)
    first, best = _time(lambda s, b, k: update(cfg, s, b, k), (state, data, ks[3]), iters, repeats)
    return {
        "what": "learner_update",
        "image": image,
        "n_agents": n_agents,
        "batch": batch,
        "seq_len": seq_len,
        "latents": latents,
        "compile_s": round(first, 3),
        "update_ms": round(best * 1e3, 2),
        "updates_per_s": round(1.0 / best, 2),
        "backend": jax.default_backend(),
        "config": dataclasses.asdict(cfg),
    }


if __name__ == "__main__":
    print(bench_vae())
    print(bench_learner_update())
