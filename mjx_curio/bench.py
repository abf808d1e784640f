"""Throughput figures on this machine: `python -m mjx_curio.bench what=env|learner|sweep|profile|convs key=value ...`

    python -m mjx_curio.bench what=env runs=24 agents=2 image=64
    python -m mjx_curio.bench what=learner
    python -m mjx_curio.bench --help

Each `what` is one function here taking the parsed keys and returning a dict of figures
(`BENCHES`); `main` prints a readable summary of that dict and then the dict as one JSON line.

what=env: `runs` worlds vmapped, each step = physics (`Arena.step`) + every agent's view
(`Arena.render`), inside one jitted `lax.scan` over `steps` steps with random actions, as the
training loop runs it. Reports the setup time (loading the scene, compiling reset and the
renderer), the compile time of the stepping chunk, steady-state world-steps/s (best of `repeats`
chunks), a breakdown into physics-only and render-only milliseconds per batched step, and the
peak resident memory. Target: >= 500 world-steps/s for 24 worlds x 2 agents at 64 x 64 with
rendering, compiling in <= 60 s.

what=learner: the VAE update (forward + backward + Adam on `vae_batch` frames) in images/s,
and one full `learner_update` (VAE + MDN-RNN + self-models) for one run. Reference: the
authors' PyTorch VAE update, batch 32 of 64 x 64, runs at about 234 images/s on this machine
class (docs/paper_setup.md).

what=sweep: the sweep's own program on `runs` runs (2 agents, 64 x 64, batch 16, an update
every 4 steps, replay 10,000 by default): aggregate run-steps/s (a run-step = every agent of one
run acts once; agent-steps/s counts each agent), compile time and peak memory. Target: >= 35
aggregate agent-steps/s for 24 runs (ten times the authors' own code, about 3.5 agent steps per
second for one multi-agent run; docs/paper_setup.md) with peak memory under 16 GiB. Both
figures are printed, and the verdict for each reading: 35 agent-steps/s, and the stricter 35
run-steps/s (70 agent-steps/s with two agents). With `checkpoint=sync|async|both` it then times
writing a checkpoint of those runs (every replay filled first), waited for and in the background:
how long the write holds the steps and how much it adds to the chunk beside it.

what=profile: one run-step of one run at the sweep's defaults split by component (physics,
rendering, encoding, memory, self-models, replay sampling, VAE update, MDN-RNN BPTT, self-model
update, re-encoding), each jitted alone on the real shapes: ms per call and per run-step, XLA's
FLOPs and bytes, GFLOP/s and % of the machine's peak (a float32 matmul of `peak_n`, measured in
the same process), next to the whole learner_update and the sweep's own run-step
(mjx_curio/profile.py; docs/cost_model.md). With `runs=24 runs_loop=vmap` every part runs over
the main job's 24 runs batched, as an accelerator runs them.

what=convs: each encoder convolution with a kernel per run (what vmap makes of per-run weights),
forward on the re-encoding's frames and backward on the VAE update's, in three forms:
the package's batched matmuls, XLA's grouped convolution and a taps-summed matmul; ms, FLOPs,
bytes and each form's deviation from the per-run convolution (mjx_curio/conv_forms.py).

Every timing is the best of `repeats` blocks after one untimed warm-up call, each block ended
by block_until_ready. Inputs are random: speed does not depend on the values.
"""

from __future__ import annotations

import dataclasses
import json
import os
import pathlib
import resource
import sys
import time

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)
import jax
import jax.numpy as jnp
import mujoco
import optax

from mjx_curio import arena as arena_lib
from mjx_curio import conv_forms
from mjx_curio import host_devices
from mjx_curio import profile as profile_lib
from mjx_curio import world_model as wm
from mjx_curio.cli import Key, as_choice, as_int, as_str, main_guard
from mjx_curio.config import LATENT_MODES, VAE_LAYERS, AutoOr, ConfigError, Int, LearnerConfig

PROG = "mjx_curio.bench"
SUMMARY = ("Throughput figures: what=env (physics + rendering), learner (VAE / learner updates), sweep (whole runs), "
           "profile (one run-step by component) or convs (the encoder's convolutions with a kernel per run).")


def _time(fn, args, iters: int, repeats: int):
    """(seconds of the first call, best seconds per call over `repeats` blocks of `iters`)."""
    t0 = time.perf_counter()
    jax.block_until_ready(fn(*args))
    first = time.perf_counter() - t0
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(iters):
            out = fn(*args)
        jax.block_until_ready(out)
        best = min(best, (time.perf_counter() - t0) / iters)
    return first, best


def _peak_rss_mib() -> float:
    return round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1)  # KiB on Linux


def _platform() -> dict:
    return {
        "backend": jax.default_backend(),
        "devices": jax.device_count(),
        "cpus": os.cpu_count(),
        "cpu_model": profile_lib.cpu_model(),  # lscpu's model name
        # Other processes competing for the cores slow every figure down; this says whether
        # they were there (1-minute load average, taken at the end).
        "load_avg": round(os.getloadavg()[0], 2),
        "jax": jax.__version__,
        "mujoco": mujoco.__version__,
    }


# ----------------------------------------------------------------------------------- env


def bench_env(args: dict) -> dict:
    """World-steps/s of `runs` vmapped worlds, physics plus every agent's rendered view."""
    runs, steps, repeats = args["runs"], args["steps"], args["repeats"]
    t_setup = time.perf_counter()
    arena = arena_lib.make(args["walls"], args["agents"], args["image"])
    n_actions = len(arena_lib.ACTIONS)

    def step_all(states, key):
        actions = jax.random.randint(key, (runs, arena.n_agents), 0, n_actions)
        return jax.vmap(arena.step)(states, actions)

    render_all = jax.vmap(arena.render)
    render_jit = jax.jit(render_all)

    # One program times both the full step and physics alone: `with_render` is a traced
    # flag and lax.cond runs only the taken branch, so the breakdown costs no second MJX
    # compile (each one is tens of seconds here). The frames are carried, as the training
    # loop carries them to the learner, so the rendering cannot be optimised away.
    @jax.jit
    def chunk(states, frames, key, with_render):
        def body(carry, k):
            states, frames = carry
            states = step_all(states, k)
            frames = jax.lax.cond(with_render, render_all, lambda _: frames, states)
            return (states, frames), None

        (states, frames), _ = jax.lax.scan(body, (states, frames), jax.random.split(key, steps))
        return states, frames

    key = jax.random.key(args["seed"])
    # States must come out of a compiled function: an eagerly built mjx.Data has other static
    # metadata in its pytree and would not match the compiled chunk.
    states = jax.jit(jax.vmap(arena.reset))(jax.random.split(key, runs))
    frames = render_jit(states)
    jax.block_until_ready(frames)
    on, off = jnp.asarray(True), jnp.asarray(False)
    setup_s = time.perf_counter() - t_setup

    t0, c0 = time.perf_counter(), time.process_time()
    compiled = chunk.lower(states, frames, key, on).compile()
    # CPU seconds too: on a shared machine the wall time of a compile says more about the
    # neighbours than about the program.
    compile_s, compile_cpu_s = time.perf_counter() - t0, time.process_time() - c0

    def timed(flag):
        # Each chunk continues the same worlds from where the last one left them.
        nonlocal states, frames, key
        best = float("inf")
        for i in range(repeats + 1):
            key, sub = jax.random.split(key)
            t0 = time.perf_counter()
            states, frames = jax.block_until_ready(compiled(states, frames, sub, flag))
            if i > 0:  # the first chunk warms up and is not counted
                best = min(best, time.perf_counter() - t0)
        return best / steps

    full = timed(on)
    physics = timed(off)
    # Rendering alone, called on one batch of states (inside a scan XLA would hoist the
    # rendering of an unchanging state out of the loop).
    _, render = _time(render_jit, (states,), max(1, min(steps, 50)), repeats)
    return {
        "what": "env",
        "runs": runs,
        "agents": arena.n_agents,
        "image": arena.image,
        "walls": arena.walls,
        "steps": steps,
        "repeats": repeats,
        "setup_s": round(setup_s, 2),
        "compile_s": round(compile_s, 2),
        "compile_cpu_s": round(compile_cpu_s, 2),
        "world_steps_per_s": round(runs / full, 1),
        "batched_step_ms": round(full * 1e3, 2),
        "physics_ms": round(physics * 1e3, 2),
        "render_ms": round(render * 1e3, 2),
        "peak_rss_mib": _peak_rss_mib(),
        **_platform(),
    }


# ------------------------------------------------------------------------------- learner


def bench_vae(image: int = 64, batch: int = 32, iters: int = 10, repeats: int = 3, seed: int = 0,
              vae_layers: str = "hs") -> dict:
    """VAE update throughput: forward + backward + Adam on `batch` frames of image x image."""
    cfg = LearnerConfig(image=image, n_agents=1, vae_layers=vae_layers)
    key = jax.random.PRNGKey(seed)
    state = wm.init_learner(cfg, key)
    opt = wm.optimizer(cfg)
    frames = jax.random.randint(key, (batch, 1, image, image, 3), 0, 256).astype(jnp.uint8)

    @jax.jit
    def step(params, opt_state, k):
        (loss, _), g = jax.value_and_grad(lambda p: wm.vae_loss(cfg, p, frames, k, state.vae_stats), has_aux=True)(params)
        u, opt_state = opt.update(g, opt_state, params)
        return optax.apply_updates(params, u), opt_state, loss

    # Every timed call starts from the same parameters, which costs exactly what a
    # training step costs.
    first, best = _time(step, (state.vae, state.vae_opt, key), iters, repeats)
    return {
        "image": image,
        "batch": batch,
        "vae_layers": vae_layers,
        "compile_s": round(first, 3),
        "step_ms": round(best * 1e3, 2),
        "images_per_s": round(batch / best, 1),
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
    vae_layers: str = "hs",
) -> dict:
    """Time of one full `learner_update` (VAE + MDN-RNN + self-models) for one run."""
    cfg = LearnerConfig(image=image, n_agents=n_agents, batch=batch, seq_len=seq_len, latents=latents,
                        vae_layers=vae_layers)
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
        "image": image,
        "n_agents": n_agents,
        "batch": batch,
        "seq_len": seq_len,
        "latents": latents,
        "compile_s": round(first, 3),
        "update_ms": round(best * 1e3, 2),
        "updates_per_s": round(1.0 / best, 2),
        "config": dataclasses.asdict(cfg),
    }


def bench_learner(args: dict) -> dict:
    """The VAE update alone and one full learner update."""
    vae = bench_vae(args["image"], args["vae_batch"], args["iters"], args["repeats"], args["seed"], args["vae_layers"])
    update = bench_learner_update(
        args["image"], args["agents"], args["batch"], args["seq_len"], args["latents"],
        args["iters"], args["repeats"], args["seed"], args["vae_layers"],
    )
    return {"what": "learner", "vae_update": vae, "learner_update": update, "peak_rss_mib": _peak_rss_mib(), **_platform()}


def bench_sweep(args: dict) -> dict:
    """The sweep's own compiled program (sweep.SweepProgram) on `runs` runs of the paper's
    workload: each chunk of `steps` agent steps renders, encodes, remembers, predicts, acts and
    steps physics every step and trains every `update_every` steps, exactly as
    `python -m mjx_curio.sweep` runs. Aggregate speed = runs x steps / seconds per chunk."""
    if args["fidelity"] == "both":  # one after the other in this process: the cost of faithfulness
        paper = bench_sweep({**args, "fidelity": "paper"})
        legacy = bench_sweep({**args, "fidelity": "legacy"})
        return {"what": "sweep", "paper": paper, "legacy": legacy,
                "paper_over_legacy_speed": round(paper["run_steps_per_s"] / legacy["run_steps_per_s"], 3),
                "run_steps_per_s": paper["run_steps_per_s"], "agent_steps_per_s": paper["agent_steps_per_s"],
                "peak_rss_mib": _peak_rss_mib(), **_platform()}
    from mjx_curio import config as config_lib
    from mjx_curio import run as run_lib
    from mjx_curio.program import SweepProgram

    devices = jax.devices()
    loop = profile_lib.runs_loop(args)
    old = args["fidelity"] == "legacy"
    settings = {"latents": args["latents"], "vae_layers": args["vae_layers"],
                **(config_lib.legacy_settings(LearnerConfig) if old else {})}
    learner = LearnerConfig(image=args["image"], n_agents=args["agents"], batch=args["batch"], seq_len=args["seq_len"],
                            **settings)
    cfg = run_lib.RunConfig(n_agents=args["agents"], image=args["image"], buffer=args["buffer"],
                            update_every=args["update_every"], metrics_every=args["update_every"], runs_loop=loop,
                            learner=learner, **(config_lib.legacy_settings(run_lib.RunConfig) if old else {}))
    runs = profile_lib.main_job_runs(args["runs"], args["seed"])
    n_pad = host_devices.padding(len(runs), len(devices))
    program = SweepProgram(cfg, runs, n_pad, args["steps"])
    t0 = time.perf_counter()
    states = program.init()
    jax.block_until_ready(states)
    init_s = time.perf_counter() - t0
    t0, c0 = time.perf_counter(), time.process_time()
    program.compile(states)
    compile_s, compile_cpu_s = time.perf_counter() - t0, time.process_time() - c0
    # One chunk to warm up, not timed: it also fills the replay, and the learner trains only once
    # a whole sequence is there (with a chunk shorter than that, the first one never trains).
    states, _ = program.chunk(states)
    jax.block_until_ready(states)
    best = float("inf")
    for _ in range(args["repeats"]):
        t0 = time.perf_counter()
        states, _ = program.chunk(states)
        jax.block_until_ready(states)
        best = min(best, time.perf_counter() - t0)
    run_steps = len(runs) * args["steps"] / best
    written = {} if args["checkpoint"] == "none" else {"checkpoint": _time_checkpoints(program, states, best, args)}
    return {
        "what": "sweep",
        "fidelity": args["fidelity"],
        "runs": len(runs),
        "agents": args["agents"],
        "image": args["image"],
        "batch": args["batch"],
        "update_every": args["update_every"],
        "buffer": args["buffer"],
        "runs_loop": loop,
        "steps_per_chunk": args["steps"],
        "init_s": round(init_s, 1),
        "compile_s": round(compile_s, 1),
        "compile_cpu_s": round(compile_cpu_s, 1),
        "chunk_s": round(best, 2),
        "run_steps_per_s": round(run_steps, 1),  # one step of one run: every agent acts once
        "agent_steps_per_s": round(run_steps * args["agents"], 1),
        "ms_per_run_step": round(1e3 / run_steps * 1, 2),
        **written,
        "peak_rss_mib": _peak_rss_mib(),
        **_platform(),
    }


def _time_checkpoints(program, states, chunk_s: float, args: dict) -> dict:
    """What writing a checkpoint of `states` (every run's state and replay, as the sweep saves
    them) adds to the steps: per mode, one after the other, the checkpoint is started, the next
    chunk runs, and the write is waited for. `held_s`: until `save` returned (the whole write
    when synchronous); `added_s`: the save and that chunk, less a chunk alone (`chunk_s`);
    `write_s`: until the checkpoint was complete on disk. Each mode writes into a fresh
    temporary directory under `checkpoint_dir`, removed afterwards. The bytes depend on how
    full the replay is: zeros compress to almost nothing, so a buffer the timed chunks filled
    (buffer <= steps x (repeats + 1)) is what a long run writes; a buffer they did not fill is
    filled first by repeating the steps they wrote (`_fill_replay`)."""
    import shutil
    import tempfile

    from mjx_curio import checkpoint as ckpt_lib

    modes = ("sync", "async") if args["checkpoint"] == "both" else (args["checkpoint"],)
    states = _fill_replay(states)
    raw = sum(x.nbytes for x in jax.tree.leaves(states))
    result = {"raw_mb": round(raw / 1e6, 1)}
    for mode in modes:
        directory = tempfile.mkdtemp(prefix="mjx_curio_bench_checkpoint_", dir=args["checkpoint_dir"] or None)
        try:
            ckpts = ckpt_lib.Checkpoints(pathlib.Path(directory), asynchronous=mode == "async")
            t0 = time.perf_counter()
            ckpts.save(1, states)
            held = time.perf_counter() - t0
            states, _ = program.chunk(states)
            jax.block_until_ready(states)
            with_chunk = time.perf_counter() - t0
            ckpts.wait()
            write = time.perf_counter() - t0
            ckpts.close()
            disk = sum(f.stat().st_size for f in pathlib.Path(directory).rglob("*") if f.is_file())
        finally:
            shutil.rmtree(directory, ignore_errors=True)
        result[mode] = {"held_s": round(held, 2), "added_s": round(with_chunk - chunk_s, 2),
                        "write_s": round(write, 2), "disk_mb": round(disk / 1e6, 1)}
    return result


def _fill_replay(states):
    """Every run's replay full: slot i gets a copy of written slot i mod size (a full buffer is
    left as it is). A checkpoint then carries a full buffer's bytes, compressed about as real
    frames are (the copies lie a whole filled stretch apart, farther than a fast compressor looks
    back)."""
    from mjx_curio import run as run_lib

    def fill(replay):
        def one(r):
            take = lambda x: jnp.take(x, jnp.arange(r.capacity) % jnp.maximum(r.size, 1), axis=0)  # noqa: E731
            full = jax.tree.map(take, (r.frames, r.latents, r.actions, r.carry))
            return r._replace(frames=full[0], latents=full[1], actions=full[2], carry=full[3],
                              index=jnp.where(r.size == r.capacity, r.index, 0),
                              size=jnp.full_like(r.size, r.capacity))
        return jax.vmap(one)(replay)

    state, replay = run_lib.split_replay(states)
    return run_lib.with_replay(state, jax.jit(fill)(replay))


def bench_profile(args: dict) -> dict:
    """One run-step by component (mjx_curio/profile.py)."""
    return {**profile_lib.profile(args, _time), "peak_rss_mib": _peak_rss_mib(), **_platform()}


def bench_convs(args: dict) -> dict:
    """The encoder's convolutions with a kernel per run, in three forms (mjx_curio/conv_forms.py)."""
    return {**conv_forms.bench(args, _time), "peak_rss_mib": _peak_rss_mib(), **_platform()}


# ---------------------------------------------------------------------------------- main

BENCHES = {"env": bench_env, "learner": bench_learner, "sweep": bench_sweep, "profile": bench_profile,
           "convs": bench_convs}
TABLES = {"profile": profile_lib.table, "convs": conv_forms.table}  # printed as tables, the rest as name: value

KEYS = [
    Key("what", "env", "what to time: " + " | ".join(BENCHES), as_choice(tuple(BENCHES))),
    Key("runs", "auto", "env: worlds stepped together (vmapped); sweep: runs; profile: runs profiled together (each"
        " part over a runs axis, as runs_loop traverses it); convs: runs, each its own kernel; auto: 24 (env, sweep,"
        " convs), 1 (profile)", AutoOr(Int(1))),
    Key("agents", 2, "agents per world: 1 | 2", as_int(1, 2)),
    Key("image", 64, "side of each agent's view in pixels (learner: a power of two in [8, 256])", as_int(1)),
    Key("walls", "same", "env: wall variant: " + " | ".join(arena_lib.WALLS), as_choice(arena_lib.WALLS)),
    Key("steps", 200, "env, sweep: steps per timed chunk", as_int(1)),
    Key("repeats", 3, "timed blocks; the best is reported", as_int(1)),
    Key("iters", 5, "learner, profile, convs: calls per timed block", as_int(1)),
    Key("vae_batch", 32, "learner: frames per VAE update", as_int(1)),
    Key("batch", 16, "learner, sweep, profile, convs: sequences per learner update", as_int(1)),
    Key("seq_len", 16, "learner, sweep, profile, convs: transitions per sequence", as_int(2)),
    Key("latents", LearnerConfig().latents, "learner, sweep, profile: " + " | ".join(LATENT_MODES)
        + " (sweep with fidelity=legacy: stored, as before the paper-faithful defaults)", as_choice(LATENT_MODES)),
    Key("vae_layers", LearnerConfig().vae_layers, "learner, sweep, profile: the VAE's layers, " + " | ".join(VAE_LAYERS),
        as_choice(VAE_LAYERS)),
    Key("update_every", 4, "sweep, profile: agent steps between learner updates", as_int(1)),
    Key("buffer", 10_000, "sweep, profile: replay capacity per run", as_int(3)),
    Key("parts", tuple(name for name, _ in profile_lib.COMPONENTS), "profile: components to profile",
        as_choice(tuple(name for name, _ in profile_lib.COMPONENTS)), many=True),
    Key("peak_n", "auto", "profile: side of the float32 matmul that measures the achievable peak; auto: 2048 on a"
        " CPU, 8192 on an accelerator (a 2048 matmul takes tens of microseconds there, too short to time)",
        AutoOr(Int(16))),
    Key("runs_loop", "auto", "sweep, profile: map | vmap | auto (map on CPU)", as_choice(("auto", "map", "vmap"))),
    Key("host_devices", "auto", "sweep: CPU devices the runs are spread over, auto (as the sweep chooses: one per "
        "physical core, at most one per run, padding at most a tenth) or a number; the other benches time one "
        "program on one device", AutoOr(Int(1))),
    Key("fidelity", "paper", "sweep: paper (the defaults) | legacy (the settings before the paper-faithful defaults: "
        "square camera, mean latents, summed curiosity, unit pair friction, free bits) | both, one after the other",
        as_choice(("paper", "legacy", "both"))),
    Key("checkpoint", "none", "sweep: after the timed chunks, time writing a checkpoint: none | sync (the sweep "
        "waits for the write) | async (written in the background) | both, one after the other",
        as_choice(("none", "sync", "async", "both"))),
    Key("checkpoint_dir", "", "sweep with checkpoint: where the temporary checkpoint directories go (default: the "
        "system's temporary directory)", as_str),
    Key("seed", 0, "random seed", as_int(0)),
]


# The benches each key changes; the others ignore it, so a key given for another is a mistake in
# the command (keys not listed here apply to every bench).
APPLIES_TO = {
    "runs": ("env", "sweep", "profile", "convs"),
    "walls": ("env",),
    "steps": ("env", "sweep"),
    "iters": ("learner", "profile", "convs"),
    "vae_batch": ("learner",),
    "batch": ("learner", "sweep", "profile", "convs"),
    "seq_len": ("learner", "sweep", "profile", "convs"),
    "latents": ("learner", "sweep", "profile"),
    "vae_layers": ("learner", "sweep", "profile"),
    "update_every": ("sweep", "profile"),
    "buffer": ("sweep", "profile"),
    "parts": ("profile",),
    "peak_n": ("profile",),
    "runs_loop": ("sweep", "profile"),
    "host_devices": ("sweep",),
    "fidelity": ("sweep",),
    "checkpoint": ("sweep",),
    "checkpoint_dir": ("sweep",),
}


def _check_applies(given: set, args: dict) -> None:
    """Every key the command gave changes the bench it runs."""
    what = args["what"]
    for name in sorted(given):
        if what not in APPLIES_TO.get(name, (what,)):
            raise ConfigError(f"{name} does not apply to what={what}: only to what={' | '.join(APPLIES_TO[name])}; "
                              f"drop {name}=, or choose one of those")
    if "checkpoint_dir" in given and args["checkpoint"] == "none":
        raise ConfigError("checkpoint_dir applies only when a checkpoint is timed: checkpoint=sync | async | both")


def _validate(args: dict) -> None:
    """Checks that need more than one key, done before any work starts."""
    if args["what"] == "env":
        arena_lib.validate(args["walls"], args["agents"], args["image"])
    elif args["what"] in ("sweep", "profile"):
        arena_lib.validate("same", args["agents"], args["image"])
        LearnerConfig(image=args["image"], n_agents=args["agents"], batch=args["batch"], seq_len=args["seq_len"], latents=args["latents"])
        if args["what"] == "sweep" and args["steps"] % args["update_every"]:
            raise ConfigError(f"steps={args['steps']} must be a multiple of update_every={args['update_every']}")
        if args["buffer"] < args["seq_len"] + 2:
            raise ConfigError(f"buffer={args['buffer']} must be at least seq_len + 2 = {args['seq_len'] + 2}")
        where = args["checkpoint_dir"]
        if where and not (os.path.isdir(where) and os.access(where, os.W_OK | os.X_OK)):
            raise ConfigError(f"checkpoint_dir={where} must be a directory you can write")
    elif args["what"] in ("learner", "convs"):
        LearnerConfig(image=args["image"], n_agents=args["agents"], batch=args["batch"], seq_len=args["seq_len"], latents=args["latents"])
        LearnerConfig(image=args["image"], n_agents=1, batch=args["vae_batch"])


def _spread_over_cores(args: dict) -> None:
    """The CPU device count, fixed before JAX starts: as the sweep would choose it for
    what=sweep (host_devices.py), one device for the single-program benches."""
    requested = args["host_devices"]  # auto but for what=sweep (APPLIES_TO)
    count = host_devices.choose(requested, args["runs"]) if args["what"] == "sweep" else 1
    host_devices.apply(count, requested)


def summary(result: dict, indent: str = "") -> str:
    """The result dict as aligned `name: value` lines, nested dicts as indented sections."""
    lines = []
    for name, value in result.items():
        if isinstance(value, dict) and name != "config":
            lines.append(f"{indent}{name}:")
            lines.append(summary(value, indent + "  "))
        elif name != "config":
            lines.append(f"{indent}{name:<20} {value}")
    return "\n".join(lines)


def main(argv=None) -> dict | None:
    argv = list(sys.argv[1:] if argv is None else argv)
    args = main_guard(argv, PROG, SUMMARY, KEYS)
    if args is None:
        return None
    given = {item.partition("=")[0] for item in argv}  # main_guard has checked every item is key=value
    if args["runs"] == "auto":  # the main job's 24 runs; the profile's one run, as it always had
        args["runs"] = 1 if args["what"] == "profile" else 24
    try:
        _check_applies(given, args)
        _validate(args)
        _spread_over_cores(args)
    except ConfigError as err:
        print(f"error: {err}", file=sys.stderr)
        raise SystemExit(2) from None
    result = BENCHES[args["what"]](args)
    if result["what"] in TABLES:
        print(TABLES[result["what"]](result))
    else:
        print(summary(result))
    if result["what"] == "env" and (args["runs"], args["agents"], args["image"]) == (24, 2, 64):
        ok = result["world_steps_per_s"] >= 500 and result["compile_s"] <= 60
        print(f"target: >= 500 world-steps/s and compile <= 60 s: {'met' if ok else 'NOT met'}")
    if result["what"] == "sweep" and (args["runs"], args["agents"], args["image"], args["batch"], args["update_every"]) == (24, 2, 64, 16, 4):
        mem = result["peak_rss_mib"] < 16 * 1024
        for unit in ("agent_steps_per_s", "run_steps_per_s"):
            ok = result[unit] >= 35 and mem
            print(f"target: >= 35 aggregate {unit} with peak memory < 16 GiB: {'met' if ok else 'NOT met'}")
    print(json.dumps(result), flush=True)
    return result


if __name__ == "__main__":
    main()
