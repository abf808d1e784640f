"""Where one run-step's time goes: `python -m mjx_curio.bench what=profile` (bench.py's CLI).

One run of the sweep's workload (`LearnerConfig()` and `RunConfig()` defaults unless the bench
keys say otherwise: 2 agents, 64 x 64, batch 16, seq_len 16, an update every 4 steps) split into
its components, each a separately jitted function on the real shapes:

    acting, every step        physics (Arena.step), rendering (Arena.render, every agent's view),
                              encoding (world_model.latent of the agents' frames), memory
                              (rnn_step), self-models (predict_curiosity)
    learning, every           replay sampling (replay.sample), VAE update, MDN-RNN BPTT,
    update_every steps        self-model update (each forward + backward + Adam, the same maths
                              as learner_update's part), re-encoding (latents=reencode only)
    re-encoding's layers      its encoder pass stage by stage (nets.VAE.encode_stage): each
                              convolution, then the head, each alone on the stage before's
                              output; shown under re-encoding, not added to the sum
    for reference             the whole learner_update, and a whole run-step: the sweep's own
                              compiled program (program.SweepProgram) on one run, a chunk of
                              update_every steps, divided by update_every

Encoding runs 1 + 1/update_every times per run-step: once per step for the new view, and once
more after each update (run.learn re-encodes the current view with the updated VAE).

For each: compile seconds, the best of `repeats` blocks of `iters` calls after a warm-up
(bench._time), XLA's cost analysis of the compiled program (flops, bytes accessed), ms per
run-step (learner parts divided by update_every), GFLOP/s and % of the machine's peak. The
peak is measured in the same process as the best of a few `peak_n`^3 float32 matmuls
("achievable"); a theoretical figure (cores x clock x FLOP/cycle from lscpu's flags) is given
as well, labelled as such.

XLA's cost analysis counts a while loop's body ONCE, whatever its trip count (checked on this
jax, 0.10.x). Every `lax.scan` becomes such a loop: the MDN-RNN's time loop, the sweep's step
loop. So each program's FLOPs are XLA's count plus the matmul and convolution FLOPs of the scan
iterations it left out, counted from the program's jaxpr (`scan_extra_flops`). A while_loop of
unknown trip count (MJX's constraint solver) is counted once by both (`unknown_loops`): those
FLOPs are a lower bound. Bytes accessed are XLA's alone (loop bodies once).

`parts` picks components: physics and run_step compile MJX's step (a minute or more each on a
2-core CPU); without run_step the other parts start from a freshly reset run.

`runs` > 1 profiles that many runs together, each component over a runs axis the way the sweep
traverses it (`runs_loop`: vmap batches the runs, as on a GPU; map runs them one by one, as on
a CPU), each run with its own copy of the inputs and weights; the whole run-step is the sweep's
program on that many runs (the main job's policies in turn). A call then covers every run, and
the per-run-step figures divide by the runs: this is where a batched accelerator's time goes
at the main job's 24 runs, which one run alone would not show (small kernels that a batch of
24 fills).
"""

from __future__ import annotations

import math
import os
import re
import subprocess
import time
from functools import partial

import jax
import jax.extend.core as jcore
import jax.numpy as jnp
import numpy as np
import optax

from mjx_curio import nets
from mjx_curio import world_model as wm

# (name, when it runs) in table order; "act": every step, "learn": every update_every steps,
# "detail": a part's pieces, each timed alone (not summed), "ref": a whole for reference.
COMPONENTS = (
    ("physics", "act"),
    ("rendering", "act"),
    ("encoding", "act"),
    ("memory", "act"),
    ("self_models", "act"),
    ("replay_sample", "learn"),
    ("vae_update", "learn"),
    ("mdn_rnn_bptt", "learn"),
    ("self_model_update", "learn"),
    ("reencode", "learn"),
    ("reencode_layers", "detail"),
    ("learner_update", "ref"),
    ("run_step", "ref"),
)


# --------------------------------------------------------------------------- FLOP counts


def cost(compiled) -> dict:
    """XLA's cost analysis of a compiled program: flops, bytes accessed, transcendentals. jax
    0.10 returns a dict (older versions: a list of one dict per program)."""
    ca = compiled.cost_analysis()
    if isinstance(ca, (list, tuple)):
        ca = ca[0] if ca else {}
    ca = ca or {}
    return {
        "xla_flops": float(ca.get("flops", 0.0)),
        "xla_bytes": float(ca.get("bytes accessed", 0.0)),
        "transcendentals": float(ca.get("transcendentals", 0.0)),
    }


def _sub_jaxprs(value):
    if isinstance(value, jcore.ClosedJaxpr):
        yield value.jaxpr
    elif isinstance(value, jcore.Jaxpr):
        yield value
    elif isinstance(value, (tuple, list)):
        for v in value:
            yield from _sub_jaxprs(v)


def jaxpr_flops(jaxpr, expand: bool = True) -> tuple[float, bool]:
    """(FLOPs of the matmuls (dot_general) and convolutions of a jaxpr, 2 per multiply-add, with
    every scan body counted `length` times (once if not `expand`), the costlier branch of a cond
    and every other sub-jaxpr (jit, custom_vjp, while bodies) once; whether it holds a
    while_loop, whose trip count is unknown). Convolutions count every kernel tap, padding
    included."""
    total, unknown = 0.0, False
    for eqn in jaxpr.eqns:
        name = eqn.primitive.name
        if name == "dot_general":
            (lc, _), _ = eqn.params["dimension_numbers"]
            k = math.prod(eqn.invars[0].aval.shape[d] for d in lc)
            total += 2.0 * math.prod(eqn.outvars[0].aval.shape) * k
        elif name == "conv_general_dilated":
            rhs = eqn.invars[1].aval.shape
            out_feature = rhs[eqn.params["dimension_numbers"].rhs_spec[0]]
            total += 2.0 * math.prod(eqn.outvars[0].aval.shape) * math.prod(rhs) / out_feature
        elif name == "scan":
            f, u = jaxpr_flops(eqn.params["jaxpr"].jaxpr, expand)
            total, unknown = total + (eqn.params["length"] if expand else 1) * f, unknown or u
        elif name == "cond":
            counts = [jaxpr_flops(b.jaxpr, expand) for b in eqn.params["branches"]]
            total, unknown = total + max(f for f, _ in counts), unknown or any(u for _, u in counts)
        else:
            unknown = unknown or name == "while"
            for value in eqn.params.values():
                for sub in _sub_jaxprs(value):
                    f, u = jaxpr_flops(sub, expand)
                    total, unknown = total + f, unknown or u
    return total, unknown


def counts(compiled, jaxpr) -> dict:
    """XLA's counts of a compiled program, and the FLOPs it missed in scan loops (XLA counts a
    loop body once): `flops` = XLA's flops + the jaxpr's matmul/conv FLOPs with scans expanded
    - the same counted once. `unknown_loops`: a while_loop of unknown trip count, counted once
    by both (MJX's solver): a lower bound."""
    c = cost(compiled)
    expanded, unknown = jaxpr_flops(jaxpr, True)
    once, _ = jaxpr_flops(jaxpr, False)
    c["scan_extra_flops"] = expanded - once
    c["unknown_loops"] = unknown
    c["flops"] = c["xla_flops"] + c["scan_extra_flops"]
    return c


# --------------------------------------------------------------------------------- peak


def _lscpu() -> dict:
    try:
        text = subprocess.run(["lscpu"], capture_output=True, text=True, timeout=10).stdout
    except (OSError, subprocess.SubprocessError):
        return {}
    out = {}
    for line in text.splitlines():
        name, sep, value = line.partition(":")
        if sep:
            out[name.strip()] = value.strip()
    return out


def cpu_model() -> str:
    return _lscpu().get("Model name", "unknown")


def theoretical_peak() -> dict:
    """A theoretical float32 peak from lscpu: cores x clock x FLOP/cycle, the last from the
    vector flags assuming two FMA pipes per core (AVX-512: 2 x 16 lanes x 2; AVX2 + FMA:
    2 x 8 x 2; AVX: 8 + 8; else SSE 4 + 4). The clock is lscpu's "CPU max MHz", or the current
    "cpu MHz" of /proc/cpuinfo (under a hypervisor usually the base clock: no turbo). An
    estimate: the number of FMA pipes is not in lscpu, and the sustained clock under load is
    unknown."""
    info = _lscpu()
    flags = set(info.get("Flags", "").split())
    try:
        cores = int(info.get("Core(s) per socket", "0")) * int(info.get("Socket(s)", "1"))
    except ValueError:
        cores = 0
    cores = cores or (os.cpu_count() or 1)
    mhz, source = 0.0, ""
    for name in ("CPU max MHz", "CPU MHz"):
        if info.get(name):
            mhz, source = float(info[name]), f"lscpu {name}"
            break
    if not mhz:
        try:
            with open("/proc/cpuinfo") as f:
                m = re.search(r"^cpu MHz\s*:\s*([0-9.]+)", f.read(), re.M)
            if m:
                mhz, source = float(m.group(1)), "/proc/cpuinfo cpu MHz"
        except OSError:
            pass
    if "avx512f" in flags:
        per_cycle, isa = 64, "AVX-512 FMA"
    elif "avx2" in flags and "fma" in flags:
        per_cycle, isa = 32, "AVX2 FMA"
    elif "avx" in flags:
        per_cycle, isa = 16, "AVX"
    else:
        per_cycle, isa = 8, "SSE"
    gflops = cores * mhz / 1e3 * per_cycle if mhz else float("nan")
    return {
        "theoretical_gflops": round(gflops, 1),
        "cores": cores,
        "ghz": round(mhz / 1e3, 3),
        "clock_from": source or "unknown",
        "flop_per_cycle": per_cycle,
        "isa": isa + " (2 pipes assumed)",
    }


def matmul_peak(n: int, repeats: int, dtype=jnp.float32) -> float:
    """Achievable GFLOP/s in `dtype`: the best of `repeats` n x n @ n x n matmuls after a warm-up."""
    a, b = (jnp.asarray(x, dtype) for x in np.random.default_rng(1).standard_normal((2, n, n), np.float32))
    f = jax.jit(jnp.matmul).lower(a, b).compile()
    jax.block_until_ready(f(a, b))
    best = float("inf")
    for _ in range(max(repeats, 3)):
        t0 = time.perf_counter()
        jax.block_until_ready(f(a, b))
        best = min(best, time.perf_counter() - t0)
    return 2.0 * n**3 / best / 1e9


# ------------------------------------------------------------------------------ profile


def main_job_runs(n_runs: int, seed: int) -> tuple:
    """n_runs runs as the main job has them: its three policies in turn, each at its default
    setting, the seed rising after every three (plan.RunSpec)."""
    from mjx_curio.plan import RunSpec

    policies = ("eps", "boltzmann", "ucb")
    return tuple(RunSpec(policies[i % 3], seed + i // 3, 0.2, 1.5, 1.0) for i in range(n_runs))


def runs_loop(args: dict) -> str:
    """The runs loop the profile uses: the key's, or for auto the sweep's choice (map on a CPU,
    vmap on an accelerator)."""
    if args["runs_loop"] != "auto":
        return args["runs_loop"]
    return "map" if jax.devices()[0].platform == "cpu" else "vmap"


def over_runs(fn, n_runs: int, loop: str):
    """fn over a leading runs axis of each argument, as the sweep's runs loop traverses it;
    fn itself for one run (no runs axis)."""
    if n_runs == 1:
        return fn
    if loop == "vmap":
        return jax.vmap(fn)
    return lambda *xs: jax.lax.map(lambda x: fn(*x), xs)


def copies(n_runs: int, *trees) -> tuple:
    """Each tree with a leading axis of n_runs copies (one run's inputs for every run; a key
    split into n_runs keys); the trees as they are for one run."""
    if n_runs == 1:
        return trees

    def copy(x):
        if jnp.issubdtype(x.dtype, jax.dtypes.prng_key):
            return jax.random.split(x, n_runs)
        return jnp.broadcast_to(x, (n_runs,) + x.shape)

    return tuple(jax.tree.map(copy, t) for t in trees)


def _configs(args: dict, loop: str = "map"):
    from mjx_curio import run as run_lib
    from mjx_curio.config import LearnerConfig

    lc = LearnerConfig(image=args["image"], n_agents=args["agents"], batch=args["batch"], seq_len=args["seq_len"],
                       latents=args["latents"], vae_layers=args["vae_layers"])
    rc = run_lib.RunConfig(n_agents=args["agents"], image=args["image"], buffer=args["buffer"],
                           update_every=args["update_every"], metrics_every=args["update_every"], runs_loop=loop,
                           learner=lc)
    return lc, rc


def profile(args: dict, time_fn) -> dict:
    """The per-component profile of one run-step (module docstring); `args` are bench.py's
    keys, `parts` the components to profile (all by default). `time_fn` is bench._time."""
    from mjx_curio import replay as replay_lib
    from mjx_curio.program import SweepProgram

    iters, repeats, ue, parts = args["iters"], args["repeats"], args["update_every"], set(args["parts"])
    n_runs, loop = args["runs"], runs_loop(args)
    lc, rc = _configs(args, loop)
    arena = rc.arena
    opt = wm.optimizer(lc)
    n, b, t1 = lc.n_agents, lc.batch, lc.seq_len + 1
    key = jax.random.key(args["seed"])
    ks = jax.random.split(key, 10)
    # The nets' inputs are drawn by NumPy: their values do not change the parts' speed, and each of
    # JAX's random draws would compile a program first (seconds in all on a 2-core CPU).
    rng = np.random.default_rng(args["seed"])
    rows: dict = {}

    def timed(fn, fn_args, per_step):
        """(the row of fn over the runs: time, compile time, counts; that program compiled for
        fn_args, which carry the runs axis)"""
        t0, c0 = time.perf_counter(), time.process_time()
        traced = jax.jit(over_runs(fn, n_runs, loop)).trace(*fn_args)
        compiled = traced.lower().compile()
        compile_s, compile_cpu_s = time.perf_counter() - t0, time.process_time() - c0
        _, best = time_fn(compiled, fn_args, iters, repeats)
        return {"ms_per_call": best * 1e3, "calls_per_run_step": per_step, "compile_s": round(compile_s, 2),
                "compile_cpu_s": round(compile_cpu_s, 2), **counts(compiled, traced.jaxpr.jaxpr)}, compiled

    def measure(name, fn, fn_args, per_step):
        """Time fn on every run, each with its own copy of one run's fn_args."""
        if name in parts:
            rows[name] = timed(fn, copies(n_runs, *fn_args), per_step)[0]

    if "run_step" in parts:
        # The whole run-step: the sweep's own program on the runs (the main job's policies in
        # turn, each at its default), a chunk = one update period.
        program = SweepProgram(rc, main_job_runs(n_runs, args["seed"]), -n_runs % len(jax.devices()), ue)
        states = jax.block_until_ready(program.init())
        t0, c0 = time.perf_counter(), time.process_time()
        traced = program._jitted_chunk.trace(states)  # the sweep's jitted chunk, compiled once, here
        chunk = traced.lower().compile()
        compile_s, compile_cpu_s = time.perf_counter() - t0, time.process_time() - c0
        # Warm up until the replay holds a whole sequence, so the timed chunks do train (before
        # that run.learn's lax.cond skips the update), and one chunk more. The chunk donates
        # its input, so each call continues from the last one's output.
        for _ in range(-(-(lc.seq_len + 2) // ue) + 1):
            states, _ = chunk(states)
        jax.block_until_ready(states)
        best = float("inf")
        for _ in range(repeats):
            t0 = time.perf_counter()
            for _ in range(iters):
                states, _ = chunk(states)
            jax.block_until_ready(states)
            best = min(best, (time.perf_counter() - t0) / iters)
        # one call = a chunk of ue steps, so a run-step is 1/ue of a call
        rows["run_step"] = {"ms_per_call": best * 1e3, "calls_per_run_step": 1.0 / ue,
                            "compile_s": round(compile_s, 2), "compile_cpu_s": round(compile_cpu_s, 2),
                            **counts(chunk, traced.jaxpr.jaxpr)}
        s = jax.tree.map(lambda x: x[0], states)  # the first run, after a few real steps
        env, learner, frames, z, carry, buffer = s.env, s.learner, s.frames, s.z, s.carry, s.replay
        del states, s  # the parts take copies of the first run: free the sweep's buffers first
    else:  # a fresh run's pieces (no MJX step to compile); the nets' inputs random, their speed
        # does not depend on the values
        env = jax.jit(arena.reset)(ks[0]) if parts & {"physics", "rendering"} else None
        # one program: run eagerly, each initialiser would compile its own
        learner, carry, buffer = jax.jit(lambda k: (wm.init_learner(lc, k), wm.initial_carry(lc),
                                                    replay_lib.init_for(lc, rc.buffer)))(ks[0])
        frames = jnp.asarray(rng.integers(0, 256, (n, lc.image, lc.image, 3), np.uint8))
        z = jnp.asarray(rng.standard_normal((n, lc.latent), np.float32))

    shp = (b, t1, n)
    batch = jax.tree.map(jnp.asarray, wm.Batch(
        frames=rng.integers(0, 256, shp + (lc.image, lc.image, 3), np.uint8),
        latents=rng.standard_normal(shp + (lc.latent,), np.float32),
        actions=rng.integers(0, lc.n_actions, shp, np.int32),
        carry=(np.zeros((b, t1, lc.rnn_hidden), np.float32),) * 2,
    ))
    actions = jnp.asarray(rng.integers(0, lc.n_actions, (n,), np.int32))
    carry0 = (jnp.zeros((b, lc.rnn_hidden)),) * 2  # the sample's stored LSTM state at its start
    # the re-encoding's frame per sequence whose posterior the VAE update computed, and that posterior
    t_pick = jnp.asarray(rng.integers(0, t1, (b,), np.int32))
    posterior = (jnp.zeros((b, n, lc.latent)),) * 2

    # --- acting, every step
    measure("physics", arena.step, (env, actions), 1.0)
    measure("rendering", arena.render, (env,), 1.0)
    stats = learner.vae_stats  # batch normalisation's running averages (vae_layers=authors), else ()
    measure("encoding", lambda p, f, k: wm.latent(lc, p, f, k, stats), (learner.vae, frames, ks[3]), 1.0 + 1.0 / ue)
    measure("memory", lambda p, c, z, a: wm.rnn_step(lc, p, c, z, a), (learner.rnn, carry, z, actions), 1.0)
    measure("self_models", lambda p, z, h: wm.predict_curiosity(lc, p, z, h), (learner.self_model, z, carry[1]), 1.0)

    # --- learning, every update_every steps, on a replay sample of the real shapes
    buffer = buffer._replace(size=jnp.asarray(buffer.capacity, jnp.int32))  # full: every start valid
    measure("replay_sample", lambda r, k: replay_lib.sample(r, k, b, lc.seq_len), (buffer, ks[4]), 1.0 / ue)

    def adam(g, st, p):
        u, st = opt.update(g, st, p)
        return optax.apply_updates(p, u), st

    def vae_update(p, st, frames, k):  # learner_update's VAE part: one frame per sequence and agent
        k_frame, k_vae = jax.random.split(k)
        f = frames[jnp.arange(b), jax.random.randint(k_frame, (b,), 0, t1)]
        (loss, _), g = jax.value_and_grad(lambda p: wm.vae_loss(lc, p, f, k_vae, stats), has_aux=True)(p)
        return adam(g, st, p), loss

    measure("vae_update", vae_update, (learner.vae, learner.vae_opt, batch.frames, ks[8]), 1.0 / ue)
    # learner_update's re-encoding: the frames of the sample but the one per sequence and agent
    # whose posterior the VAE update just computed (world_model.reencoded_latents)
    reencode_per_step = 1.0 / ue if lc.latents == "reencode" else 0.0
    measure("reencode", lambda p, f, t, q, k: wm.reencoded_latents(lc, p, f, t, q, k, stats)[0],
            (learner.vae, batch.frames, t_pick, posterior, ks[9]), reencode_per_step)
    layers: dict = {}
    if "reencode_layers" in parts:
        # the re-encoding's encoder pass stage by stage, each on the previous stage's output
        x = batch.frames[:, 1:].reshape((-1,) + batch.frames.shape[3:])  # B x T x n_agents frames
        vae, x = copies(n_runs, (learner.vae, stats), x)
        for stage, name in enumerate(encoder_stage_names(lc)):
            layers[name], stage_fn = timed(partial(encoder_stage, lc, stage), (vae, x), reencode_per_step)
            x = stage_fn(vae, x)  # the next stage's input, by the program just timed

    def mdn_update(p, st, carry0, z, a):  # learner_update's MDN-RNN part (on the stored latents)
        (nll, (mix, h_in)), g = jax.value_and_grad(lambda p: wm.mdn_loss(lc, p, carry0, z, a), has_aux=True)(p)
        return adam(g, st, p), nll, mix, h_in

    mdn_args = (learner.rnn, learner.rnn_opt, carry0, batch.latents, batch.actions)
    measure("mdn_rnn_bptt", mdn_update, mdn_args, 1.0 / ue)

    def self_update(p, st, z, mix, h_in, actions):  # learner_update's self-model part
        cur = wm.curiosity(lc, z[:, 1:], mix)
        n_tr = b * (t1 - 1)
        (loss, _), g = jax.value_and_grad(
            lambda p: wm.self_model_loss(lc, p, z[:, :-1].reshape(n_tr, n, lc.latent),
                                         h_in.reshape(n_tr, lc.rnn_hidden), actions[:, :-1].reshape(n_tr, n),
                                         cur.reshape(n_tr, n)),
            has_aux=True)(p)
        return jax.vmap(adam)(g, st, p), loss

    if "self_model_update" in parts:
        # its inputs: the MDN-RNN's mixtures and hidden states on this batch (stop-gradient there)
        mix, h_in = jax.jit(lambda p, c, z, a: wm.mdn_loss(lc, p, c, z, a)[1])(
            learner.rnn, carry0, batch.latents, batch.actions)
        measure("self_model_update", self_update,
                (learner.self_model, learner.self_opt, batch.latents, mix, h_in, batch.actions), 1.0 / ue)
    measure("learner_update", lambda st, bt, k: wm.learner_update(lc, st, bt, k), (learner, batch, key), 1.0 / ue)

    peak_n = args["peak_n"] if args["peak_n"] != "auto" else (2048 if jax.devices()[0].platform == "cpu" else 8192)
    peak = matmul_peak(peak_n, repeats)
    # The same matmul in bfloat16: whether XLA's CPU backend runs it faster than float32 here
    # (native bf16 instructions), which would make bf16 learner arithmetic worth testing.
    peak_bf16 = matmul_peak(peak_n, repeats, jnp.bfloat16)
    theory = theoretical_peak()
    names = [name for name, _ in COMPONENTS if name in rows]
    summed = [name for name, when in COMPONENTS if when in ("act", "learn") and name in rows]
    for row in (*rows.values(), *layers.values()):
        # a call covers every run; a run-step is one step of one run
        row["runs_per_call"] = n_runs
        row["ms_per_run_step"] = row["ms_per_call"] * row["calls_per_run_step"] / n_runs
    sum_ms = sum(rows[p]["ms_per_run_step"] for p in summed)
    whole_ms = rows["run_step"]["ms_per_run_step"] if "run_step" in rows else None
    for row in (*rows.values(), *layers.values()):
        row["share_pct"] = 100.0 * row["ms_per_run_step"] / (whole_ms or sum_ms or 1.0)
        row["gflops_per_s"] = row["flops"] / (row["ms_per_call"] * 1e6)
        row["pct_of_peak"] = 100.0 * row["gflops_per_s"] / peak
        row["flops_per_run_step"] = row["flops"] * row["calls_per_run_step"] / n_runs
        row["bytes_per_run_step"] = row["xla_bytes"] * row["calls_per_run_step"] / n_runs
    return {
        "what": "profile",
        "runs": n_runs,
        "runs_loop": loop,
        "agents": n,
        "image": lc.image,
        "batch": b,
        "seq_len": lc.seq_len,
        "update_every": ue,
        "buffer": rc.buffer,
        "latents": lc.latents,
        "z": lc.z,
        "curiosity": lc.curiosity,
        "iters": iters,
        "repeats": repeats,
        "cpu_model": cpu_model(),
        "device_kind": jax.devices()[0].device_kind,
        "matmul_precision": str(jax.config.jax_default_matmul_precision or "default"),
        "peak_matmul_n": peak_n,
        "peak_matmul_gflops": round(peak, 1),
        "peak_matmul_bf16_gflops": round(peak_bf16, 1),
        **theory,
        "run_step_ms": None if whole_ms is None else round(whole_ms, 3),
        "run_steps_per_s": None if whole_ms is None else round(1e3 / whole_ms, 2),
        "sum_of_parts_ms": round(sum_ms, 3),
        "components": {name: _rounded(rows[name]) for name in names},
        "reencode_layers": {name: _rounded(row) for name, row in layers.items()},
    }


def _rounded(row: dict) -> dict:
    return {k: (round(v, 6) if isinstance(v, float) else v) for k, v in row.items()}


def encoder_stage_names(lc) -> list[str]:
    """The encoder's stages (nets.VAE.encode_stage) as the profile names them, with each output's
    shape: conv1_31x31x32 ... at 64 x 64, then the mean and log-variance head."""
    sizes = nets.encoder_sizes(lc.image, len(lc.vae_channels), lc.vae_layers)
    return [f"conv{i + 1}_{s}x{s}x{c}" for i, (s, c) in enumerate(zip(sizes, lc.vae_channels))] + ["head"]


def encoder_stage(lc, stage: int, vae, x):
    """Stage `stage` of the encoder on a batch x (uint8 frames for stage 0, else the stage before's
    output), as the re-encoding runs it (batch normalisation, if any, by the batch's statistics);
    `vae`: (params, running averages)."""
    return wm.apply_vae(lc, *vae, stage, x, method=nets.VAE.encode_stage, train=True)[0]


def peak_note(result: dict) -> str:
    """What %peak is relative to: the matmul measured now, and on a CPU the theoretical figure."""
    measured = (f"%peak: of {result['peak_matmul_gflops']} GFLOP/s achievable ({result['peak_matmul_n']}^3 float32"
                f" matmul at matmul precision {result['matmul_precision']}, best of {max(result['repeats'], 3)},"
                f" measured now on {result['device_kind']}).")
    bf16 = f"The same matmul in bfloat16: {result['peak_matmul_bf16_gflops']} GFLOP/s."
    if result.get("backend", "cpu") != "cpu":
        # lscpu's figure would be the host's; an accelerator's default precision may be TF32
        return f"{measured} {bf16} Host CPU: {result['cpu_model']}."
    return (f"{measured} Theoretical {result['theoretical_gflops']} GFLOP/s = {result['cores']} cores x"
            f" {result['ghz']} GHz ({result['clock_from']}) x {result['flop_per_cycle']} FLOP/cycle ({result['isa']}):"
            f" an estimate. {bf16} CPU: {result['cpu_model']}.")


def table(result: dict) -> str:
    """The profile as a readable table, then what its columns mean and the peak."""
    head = (f"{'component':<23}{'ms/call':>9}{'calls/step':>11}{'ms/step':>9}{'share%':>8}{'GFLOP/call':>12}"
            f"{'MB/call':>9}{'GFLOP/s':>9}{'%peak':>7}")
    rule = "-" * len(head)
    lines = [head, rule]
    comps = result["components"]

    def line(name, row):
        mark = "~" if row["unknown_loops"] else ("*" if row["scan_extra_flops"] > 0 else " ")
        lines.append(f"{name:<23}{row['ms_per_call']:>9.3f}{row['calls_per_run_step']:>11.3g}"
                     f"{row['ms_per_run_step']:>9.3f}{row['share_pct']:>8.1f}{row['flops'] / 1e9:>11.4f}{mark}"
                     f"{row['xla_bytes'] / 1e6:>9.2f}{row['gflops_per_s']:>9.2f}{row['pct_of_peak']:>7.1f}")

    for name, when in COMPONENTS:
        if when in ("act", "learn") and name in comps:
            line(name, comps[name])
        if name == "reencode_layers":  # after reencode: its encoder pass stage by stage, not summed
            for stage, row in result.get("reencode_layers", {}).items():
                line(f"  {stage}", row)
    lines.append(rule)
    whole = result["run_step_ms"]
    share = f"{100 * result['sum_of_parts_ms'] / whole:>8.1f}" if whole else ""
    lines.append(f"{'sum of the parts':<23}{'':>9}{'':>11}{result['sum_of_parts_ms']:>9.3f}{share}")
    for name, label in (("learner_update", "learner_update (whole)"), ("run_step", "run-step (whole)")):
        if name in comps:
            line(label, comps[name])
    runs = result["runs"]
    if result["run_steps_per_s"] is not None:
        lines.append(f"whole run-step: {result['run_steps_per_s']} run-steps/s over {runs} run(s)")
    lines += [
        "",
        "calls/step: calls per run-step (a run-step: every agent of one run acts once). Learner parts run once every"
        " update_every steps; encoding runs every step and once more after each update (run.learn re-encodes the"
        " current view); reencode counts only with latents=reencode. run-step (whole): one call is a chunk of"
        " update_every steps of the sweep's own program.",
        f"runs: {runs}, runs_loop={result['runs_loop']}: each call covers every run (ms/call, GFLOP/call, MB/call);"
        f" ms/step = ms/call x calls/step / runs.",
        "share%: of the whole run-step (of the sum of the parts when run_step is not profiled).",
        "Indented under reencode (parts=reencode_layers): the re-encoding's encoder pass, one program per"
        " convolution (with its ReLU; the first also scales the frames) and the head, each on the stage before's"
        " output; timed alone, not in the sum.",
        "GFLOP/call: XLA's cost analysis, plus the matmul/conv FLOPs of the scan iterations it leaves out (it"
        " counts a loop body once): * = corrected so; ~ = also holds a while_loop of unknown trip count (MJX's"
        " solver), counted once: a lower bound. MB/call: XLA's bytes accessed (loop bodies once).",
        peak_note(result),
    ]
    return "\n".join(lines)
