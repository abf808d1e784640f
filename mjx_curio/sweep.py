"""python -m mjx_curio.sweep key=value ... : many curious-agent runs as one compiled program.

    python -m mjx_curio.sweep policies=eps,boltzmann,ucb seeds=8

runs 3 x 8 = 24 runs of the paper side by side and leaves a directory (default runs/<time>/):
    manifest.json        full config, the runs in order, package versions, device, git commit,
                         the metrics schema
    progress.json        steps done, newest checkpoint, halted runs (rewritten atomically)
    metrics/<name>.npy   one array per metric, [runs, windows, ...]; metrics/steps.npy gives
                         the step at the end of each window (see metrics.py)
    checkpoints/state/<step>, checkpoints/replay/<step>   orbax checkpoints (see checkpoint.py)

The grid: every policy in `policies` x every seed, and for each policy every value of its own
setting (eps for eps, temperature for boltzmann, ucb_c for ucb), so
`policies=boltzmann temperature=0.5,1,1.5,2,2.5 seeds=8` is the paper's temperature sweep on 8
seeds. Everything is checked before any work starts or anything is written.
"""

from __future__ import annotations

import dataclasses
import datetime
import functools
import itertools
import math
import os
import pathlib
import platform
import subprocess
import sys
import time

import numpy as np

import mjx_curio
from mjx_curio import cli
from mjx_curio.cli import Key, as_bool, as_choice, as_float, as_int, as_str
from mjx_curio.config import POLICY_IDS, ConfigError, LearnerConfig, check_int

PROG = "mjx_curio.sweep"
SUMMARY = "Run a grid of curious-agent runs (paper 'A Multi-Agent World Model with Self-Driven Curiosity') as one program."
FORMAT = "mjx_curio.sweep/1"
POLICY_SETTING = {"eps": "eps", "boltzmann": "temperature", "ucb": "ucb_c"}

KEYS = (
    Key("preset", "none", "a paper experiment from experiments/presets.toml (its keys are defaults here), or none", as_str),
    Key("policies", ("eps", "boltzmann", "ucb"), "exploration policies: eps, boltzmann, ucb", as_choice(tuple(POLICY_IDS)), many=True),
    Key("seeds", 8, "seeds per setting (seeds first_seed .. first_seed + seeds - 1)", as_int(1)),
    Key("first_seed", 0, "first seed", as_int(0)),
    Key("steps", 80_000, "agent steps per run (the paper: 80,000)", as_int(1)),
    Key("agents", 2, "cube agents per arena: 1 or 2", as_int(1, 2)),
    Key("walls", "same", "wall textures: same (one on all walls) or different (one per wall)", as_choice(("same", "different"))),
    Key("image", 64, "camera image side in pixels: a power of two in [8, 256]", as_int(8, 256)),
    Key("batch", 16, "replay sequences per learner update", as_int(1)),
    Key("seq_len", 16, "transitions per replay sequence (truncated BPTT length)", as_int(2)),
    Key("update_every", 4, "agent steps between learner updates", as_int(1)),
    Key("buffer", 10_000, "replay capacity in agent steps", as_int(3)),
    Key("eps", (0.2,), "epsilon-greedy: probability of a random action, in [0, 1] (a list sweeps it)", as_float(0.0, 1.0), many=True),
    Key("temperature", (1.5,), "Boltzmann temperature > 0 (a list sweeps it, e.g. 0.5,1,1.5,2,2.5)", as_float(0.0, lo_open=True), many=True),
    Key("ucb_c", (1.0,), "UCB exploration constant c > 0 (a list sweeps it)", as_float(0.0, lo_open=True), many=True),
    Key("lr", 1e-3, "Adam learning rate of all three models", as_float(0.0, lo_open=True)),
    Key("latents", "stored", "MDN-RNN training latents: stored (as acted) or reencode (current VAE)", as_choice(("stored", "reencode"))),
    Key("jitter", 0.0, "objects start up to this many metres from the paper's layout, seeded, in [0, 0.4]", as_float(0.0, 0.4)),
    Key("metrics_every", 20, "agent steps per metrics window (the paper samples every 20)", as_int(1)),
    Key("chunk", 100, "agent steps per compiled chunk between host syncs", as_int(1)),
    Key("out", "", "sweep directory (default: a new runs/<date-time>)", as_str),
    Key("checkpoint_every", 5_000, "agent steps between checkpoints (a multiple of chunk)", as_int(1)),
    Key("keep_last", 2, "newest checkpoints kept", as_int(1)),
    Key("keep_every", 20_000, "also keep every checkpoint at a multiple of this step (0: none)", as_int(0)),
    Key("keep_steps", (500, 5_000), "also checkpoint and keep at these steps (early reconstructions)", as_int(1), many=True),
    Key("save_replay", True, "save replay buffers with checkpoints (needed for an exact resume)", as_bool),
    Key("resume", False, "continue the sweep in `out` from its newest complete checkpoint", as_bool),
    Key("runs_loop", "auto", "how runs share the program: map (one by one), vmap (batched), auto (map on CPU)",
        as_choice(("auto", "map", "vmap"))),
    Key("distributed", "auto", "jax.distributed.initialize() first: true, false, auto (when a cluster is detected)",
        as_choice(("auto", "true", "false"))),
    Key("compile_cache", "~/.cache/mjx_curio/xla", "persistent XLA compilation cache directory, or none", as_str),
    Key("progress", True, "show a progress line", as_bool),
)

# Keys that may differ when resuming: they change bookkeeping, not the runs' results.
RESUME_FREE = {"preset", "out", "resume", "steps", "progress", "compile_cache", "distributed", "chunk", "checkpoint_every",
               "keep_last", "keep_every", "keep_steps", "save_replay"}


@dataclasses.dataclass(frozen=True)
class RunSpec:
    policy: str
    seed: int
    eps: float
    temperature: float
    ucb_c: float

    @property
    def name(self) -> str:
        setting = POLICY_SETTING[self.policy]
        return f"{self.policy}-{setting}{getattr(self, setting):g}-seed{self.seed}"


@dataclasses.dataclass(frozen=True)
class Plan:
    values: dict
    runs: tuple
    out: pathlib.Path
    resume: bool  # continue an existing sweep directory
    learner: LearnerConfig


def grid(values: dict) -> tuple:
    runs = []
    for policy in values["policies"]:
        settings = values[POLICY_SETTING[policy]]
        for setting, seed in itertools.product(settings, range(values["first_seed"], values["first_seed"] + values["seeds"])):
            kw = {"eps": values["eps"][0], "temperature": values["temperature"][0], "ucb_c": values["ucb_c"][0]}
            kw[POLICY_SETTING[policy]] = setting
            runs.append(RunSpec(policy, seed, **kw))
    if len(set(runs)) != len(runs):
        raise ConfigError("the grid holds the same run twice: a list key repeats a value (policies, eps, temperature or ucb_c)")
    return tuple(runs)


def plan(values: dict, now: datetime.datetime | None = None) -> Plan:
    """Every check of the command line and of `out`, without side effects."""
    v = dict(values)
    if v["distributed"] != "false":
        _process_env()
    steps, chunk = v["steps"], v["chunk"]
    for name in ("update_every", "metrics_every"):
        if chunk % v[name]:
            raise ConfigError(f"chunk={chunk} must be a multiple of {name}={v[name]}")
    if v["metrics_every"] % v["update_every"]:
        raise ConfigError(f"metrics_every={v['metrics_every']} must be a multiple of update_every={v['update_every']}")
    if steps % chunk:
        raise ConfigError(f"steps={steps} must be a multiple of chunk={chunk} (e.g. steps={math.ceil(steps / chunk) * chunk})")
    if v["checkpoint_every"] % chunk:
        raise ConfigError(f"checkpoint_every={v['checkpoint_every']} must be a multiple of chunk={chunk}")
    if v["keep_every"] and v["keep_every"] % v["checkpoint_every"]:
        raise ConfigError(f"keep_every={v['keep_every']} must be 0 or a multiple of checkpoint_every={v['checkpoint_every']}")
    for s in v["keep_steps"]:
        if s % chunk:
            raise ConfigError(f"keep_steps={s} must be a multiple of chunk={chunk}")
    if v["image"] & (v["image"] - 1):
        raise ConfigError(f"image={v['image']} is not allowed; allowed: a power of two in [8, 256]")
    check_int("buffer", v["buffer"], v["seq_len"] + 2)
    learner = LearnerConfig(image=v["image"], n_agents=v["agents"], batch=v["batch"], seq_len=v["seq_len"],
                            latents=v["latents"], lr=v["lr"])
    runs = grid(v)

    if v["resume"] and not v["out"]:
        raise ConfigError("resume=true needs out=<the sweep directory to continue>")
    if v["out"]:
        out = pathlib.Path(os.path.expanduser(v["out"]))
    else:
        now = now or datetime.datetime.now()
        out = pathlib.Path("runs") / now.strftime("%Y%m%d-%H%M%S")
        while out.exists():
            out = out.with_name(out.name + "x")
    manifest = out / "manifest.json"
    if v["resume"]:
        if not manifest.is_file():
            raise ConfigError(f"resume=true but out={out} holds no sweep (no manifest.json)")
        defaults = config_of({k.name: k.default for k in KEYS})
        saved = {**defaults, **read_manifest(out)["config"]}  # a key newer than the sweep: its default
        given = config_of(v)
        diff = [k for k in saved if k not in RESUME_FREE and _norm(saved[k]) != _norm(given.get(k, defaults.get(k)))]
        if diff:
            detail = "; ".join(f"{k}: saved {saved[k]!r}, given {given.get(k)!r}" for k in diff)
            raise ConfigError(f"resume=true: out={out} was made with another config ({detail}); "
                              "resume with the same values, or start a new sweep in another out")
        done = read_progress(out).get("steps_done", 0)
        if steps < done:
            raise ConfigError(f"steps={steps} is less than the {done} steps out={out} has already done")
        return Plan(v, runs, out, True, learner)
    if manifest.exists():
        raise ConfigError(f"out={out} already holds a sweep; pass resume=true to continue it, or choose another out")
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise ConfigError(f"out={out} exists and is not an empty directory; choose another out")
    return Plan(v, runs, out, False, learner)


def config_of(values: dict) -> dict:
    return {k: list(x) if isinstance(x, tuple) else x for k, x in values.items()}


def _norm(x):
    return list(x) if isinstance(x, (tuple, list)) else x


def read_manifest(out: pathlib.Path) -> dict:
    import json

    return json.loads((pathlib.Path(out) / "manifest.json").read_text())


def read_progress(out: pathlib.Path) -> dict:
    import json

    p = pathlib.Path(out) / "progress.json"
    return json.loads(p.read_text()) if p.is_file() else {}


# ---------------------------------------------------------------------------------- execution


PRESETS = pathlib.Path(__file__).resolve().parents[1] / "experiments" / "presets.toml"


def load_presets(path: pathlib.Path = PRESETS) -> dict:
    import tomllib

    if not path.is_file():
        raise ConfigError(f"preset needs {path} (part of the repository checkout)")
    return tomllib.loads(path.read_text())


def apply_preset(argv: list) -> list:
    """argv with the preset's keys put in front of it (the command line's own keys win)."""
    given = {a.partition("=")[0]: a.partition("=")[2] for a in argv if "=" in a}
    name = given.get("preset", "none")
    if name == "none":
        return argv
    presets = load_presets()
    if name not in presets:
        raise ConfigError(f"preset={name!r} is not allowed; choose one of: none, {', '.join(presets)}")
    items = [f"{k}={v}" for k, v in presets[name].items() if k != "about" and k not in given]
    if "out" not in given:
        items.append(f"out=runs/paper/{name}")
    return items + list(argv)


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        argv = apply_preset(argv)
    except ConfigError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    values = cli.main_guard(argv, PROG, SUMMARY, KEYS)
    if values is None:
        if any(a in ("-h", "--help", "help") for a in argv) and PRESETS.is_file():
            print("\npresets (python -m mjx_curio.sweep preset=<name>):")
            for name, preset in load_presets().items():
                print(f"  {name:<30} {preset.get('about', '')}")
        return 0
    try:
        p = plan(values)
    except ConfigError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    return execute(p)


def execute(p: Plan) -> int:
    v = p.values
    _setup_jax(v)
    import jax

    from mjx_curio import checkpoint as ckpt_lib
    from mjx_curio import metrics as metrics_lib
    from mjx_curio import run as run_lib

    devices = jax.devices()
    lead = jax.process_index() == 0
    runs_loop = v["runs_loop"] if v["runs_loop"] != "auto" else ("map" if devices[0].platform == "cpu" else "vmap")
    cfg = run_lib.RunConfig(walls=v["walls"], n_agents=v["agents"], image=v["image"], jitter=v["jitter"],
                            buffer=v["buffer"], update_every=v["update_every"], metrics_every=v["metrics_every"],
                            runs_loop=runs_loop, learner=p.learner)
    n_runs = len(p.runs)
    n_pad = -n_runs % len(devices)  # copies of run 0 so every device holds as many runs
    program = SweepProgram(cfg, p.runs, n_pad, v["chunk"])

    n_windows = v["steps"] // v["metrics_every"]
    ckpts_dir = p.out / "checkpoints"
    if not p.resume:
        if lead:
            p.out.mkdir(parents=True, exist_ok=True)
            metrics_lib.write_json_atomic(p.out / "manifest.json", manifest(p, cfg, devices, n_pad, n_windows))
            store = metrics_lib.MetricsStore(p.out / "metrics", n_runs, n_windows, v["agents"], create=True)
            metrics_lib.write_steps(p.out / "metrics", n_windows, v["metrics_every"])
    else:
        saved = read_manifest(p.out)
        if saved.get("padded_runs", 0) != n_pad:
            print(f"error: resume=true on {len(devices)} device(s) needs {n_pad} padding run(s); the sweep was "
                  f"saved with {saved.get('padded_runs', 0)}: resume it on {saved['device']['count']} device(s)",
                  file=sys.stderr)
            return 2
        if lead:
            store = _grow_metrics(p.out, n_runs, n_windows, v, metrics_lib)
            if saved["config"]["steps"] != v["steps"]:
                saved["config"]["steps"] = v["steps"]
                saved["metrics"]["windows"] = n_windows
                metrics_lib.write_json_atomic(p.out / "manifest.json", saved)
    ckpts = ckpt_lib.Checkpoints(ckpts_dir, save_replay=v["save_replay"], keep_last=v["keep_last"],
                                 keep_every=v["keep_every"] or None, keep_steps=tuple(v["keep_steps"]))

    start, states = 0, None
    if p.resume:
        ckpt_lib.remove_tmp_dirs(ckpts_dir)
        step = ckpts.latest_complete()
        if step is not None:
            dropped = ckpts.drop_after(step)
            if dropped and lead:
                print(f"resume: checkpoints {dropped} were incomplete (the sweep stopped while writing); "
                      f"they are removed and will be written again", file=sys.stderr)
            t0 = time.perf_counter()
            states = ckpts.restore(step, program.abstract(), with_replay=v["save_replay"])
            start = step
            if lead:
                print(f"resume: restored step {step} from {ckpts_dir} in {time.perf_counter() - t0:.1f} s", file=sys.stderr)
        elif lead:
            print(f"resume: {p.out} has no complete checkpoint yet; starting from step 0", file=sys.stderr)
    if states is None:
        t0 = time.perf_counter()
        states = program.init()
        jax.block_until_ready(states)
        if lead:
            print(f"initialised {n_runs} runs in {time.perf_counter() - t0:.1f} s (includes compiling)", file=sys.stderr)

    progress = Progress(start, v["steps"], n_runs, enabled=v["progress"] and lead)
    halted_seen = set(read_progress(p.out).get("halted", {}) if p.resume else ())
    halted_info = dict(read_progress(p.out).get("halted", {})) if p.resume else {}
    step = start
    checkpoint_steps = set(v["keep_steps"])
    while step < v["steps"]:
        states = _inject_fault(states, step)
        states, m = program.chunk(states)
        # Gathers are collectives: every process takes part, whatever it then writes.
        m = {k: _host(x)[:n_runs] for k, x in m.items()}
        halted = np.asarray(_host(states.halted))[:n_runs]
        halted_at = np.asarray(_host(states.halted_step))[:n_runs]
        w0 = step // v["metrics_every"]
        step += v["chunk"]
        if lead:
            store.write(w0, m)
            store.flush()
            for r in np.flatnonzero(halted):
                if str(r) not in halted_seen:
                    halted_seen.add(str(r))
                    halted_info[str(r)] = int(halted_at[r])
                    progress.message(f"run {r} ({p.runs[r].name}): a loss became non-finite (NaN or inf) in the learner "
                                     f"update at step {int(halted_at[r])}; the update was discarded and the run is halted, "
                                     f"frozen at its last good state, which its checkpoints keep. The other runs go on.")
        if step % v["checkpoint_every"] == 0 or step == v["steps"] or step in checkpoint_steps:
            ckpts.save(step, states)
            if lead:
                metrics_lib.write_json_atomic(p.out / "progress.json", {
                    "steps_done": step, "steps": v["steps"], "windows_done": step // v["metrics_every"],
                    "checkpoint": step, "halted": halted_info,
                    "updated": datetime.datetime.now().isoformat(timespec="seconds")})
        progress.update(step)
    ckpts.close()
    progress.done()
    if lead:
        print(f"sweep done: {n_runs} runs x {v['steps']} steps in {p.out}\n"
              f"  manifest    {p.out / 'manifest.json'}\n  metrics     {p.out / 'metrics'}/*.npy\n"
              f"  checkpoints {ckpts_dir}/state/<step> (newest {step})", file=sys.stderr)
        if halted_info:
            print(f"{len(halted_info)} run(s) halted on a non-finite loss: "
                  + ", ".join(f"{p.runs[int(r)].name} at step {s}" for r, s in halted_info.items()), file=sys.stderr)
            return 1
    return 0


class SweepProgram:
    """The compiled init and chunk functions of a sweep, sharded over every visible device."""

    def __init__(self, cfg, runs: tuple, n_pad: int, chunk: int):
        import jax

        from mjx_curio import policies
        from mjx_curio import run as run_lib

        self.cfg, self.chunk_steps = cfg, chunk
        self._init, self._chunk, self.sharding = _compiled(cfg, chunk, tuple(jax.devices()))
        padded = list(runs) + [runs[0]] * n_pad
        keys = np.stack([run_lib.key_for_seed(r.seed) for r in padded])
        pol = [policies.make_policy_params(POLICY_IDS[r.policy], r.eps, r.temperature, r.ucb_c) for r in padded]
        pol = jax.tree.map(lambda *x: np.stack([np.asarray(a) for a in x]), *pol)
        self.inputs = jax.tree.map(self._global, (keys, pol))

    def _global(self, x: np.ndarray):
        import jax

        return jax.make_array_from_callback(x.shape, self.sharding, lambda idx: x[idx])

    def init(self):
        return self._init(*self.inputs)

    def abstract(self):
        import jax

        shapes = jax.eval_shape(self._init, *self.inputs)
        return jax.tree.map(lambda s: jax.ShapeDtypeStruct(s.shape, s.dtype, sharding=self.sharding), shapes)

    def chunk(self, states):
        return self._chunk(states)


@functools.lru_cache(maxsize=8)
def _compiled(cfg, chunk: int, devices: tuple):
    """(init, chunk, sharding) for a config, one set per process: a second sweep with the same
    program in the same process (a resume, a test) reuses the traces and executables."""
    import jax
    from jax.sharding import NamedSharding
    from jax.sharding import PartitionSpec as P

    from mjx_curio import run as run_lib

    # The arena (MJX model arrays, contact tables) is built here, outside the sharded trace:
    # built inside it on a multi-process mesh, its arrays spanned the other processes' devices
    # and could not be closed over.
    cfg.arena  # noqa: B018
    mesh = jax.make_mesh((len(devices),), ("runs",), devices=devices)
    spec = P("runs")
    # Each device advances its own runs and nothing crosses devices, so shard_map's check of
    # which values vary across the mesh has nothing to guard (and it rejects the runs loop's
    # zero-initialised carry).
    init = jax.shard_map(lambda k, q: run_lib.init_runs(cfg, k, q), mesh=mesh,
                         in_specs=(spec, spec), out_specs=spec, check_vma=False)
    chunk_fn = jax.shard_map(lambda s: run_lib.sweep_chunk(cfg, s, chunk), mesh=mesh,
                             in_specs=(spec,), out_specs=(spec, spec), check_vma=False)
    return jax.jit(init), jax.jit(chunk_fn, donate_argnums=0), NamedSharding(mesh, spec)


# Fault injection for tests/test_sweep.py: "nan-latents:<run>:<step>" fills run <run>'s stored
# replay latents with NaN when the sweep reaches <step>, so its next MDN-RNN loss is NaN.
FAULT_ENV = "MJX_CURIO_FAULT"


def _inject_fault(states, step: int):
    spec = os.environ.get(FAULT_ENV, "")
    if not spec:
        return states
    kind, run, at = spec.split(":")
    if kind != "nan-latents" or int(at) != step:
        return states
    import jax.numpy as jnp

    latents = states.replay.latents
    poisoned = jnp.where((jnp.arange(latents.shape[0]) == int(run))[:, None, None, None], jnp.nan, latents)
    return states._replace(replay=states.replay._replace(latents=poisoned))


def _host(x) -> np.ndarray:
    """A (possibly multi-process) global array as a NumPy array on every process."""
    if getattr(x, "is_fully_addressable", True):
        return np.asarray(x)
    from jax.experimental import multihost_utils

    return np.asarray(multihost_utils.process_allgather(x, tiled=True))


def _grow_metrics(out, n_runs, n_windows, v, metrics_lib):
    """Open the metrics of a resumed sweep, growing the files when `steps` was raised."""
    mdir = pathlib.Path(out) / "metrics"
    for name, spec in metrics_lib.SCHEMA.items():
        path = mdir / f"{name}.npy"
        old = np.load(path, mmap_mode="r")
        if old.shape[1] < n_windows:
            tmp = path.with_name(path.name + ".grow.npy")
            new = np.lib.format.open_memmap(tmp, mode="w+", dtype=old.dtype, shape=(old.shape[0], n_windows) + old.shape[2:])
            new[...] = metrics_lib.fill_value(spec.dtype)
            new[:, : old.shape[1]] = old
            new.flush()
            del new, old
            os.replace(tmp, path)
    metrics_lib.write_steps(mdir, n_windows, v["metrics_every"])
    return metrics_lib.MetricsStore(mdir, n_runs, n_windows, v["agents"], create=False)


def _setup_jax(v: dict) -> None:
    import jax

    if v["distributed"] == "true" or (v["distributed"] == "auto" and _cluster_detected()):
        # Coordinator, process count and id from the environment: SLURM's or Open MPI's, which
        # JAX reads itself, or plain JAX_COORDINATOR_ADDRESS, JAX_NUM_PROCESSES, JAX_PROCESS_ID.
        count, index = _process_env()
        jax.distributed.initialize(num_processes=count, process_id=index)
    cache = v["compile_cache"]
    if cache.lower() != "none":
        path = pathlib.Path(os.path.expanduser(cache))
        path.mkdir(parents=True, exist_ok=True)
        jax.config.update("jax_compilation_cache_dir", str(path))


def _process_env() -> tuple[int | None, int | None]:
    """JAX_NUM_PROCESSES and JAX_PROCESS_ID from the environment (None where unset)."""
    env = os.environ
    count, index = env.get("JAX_NUM_PROCESSES") or None, env.get("JAX_PROCESS_ID") or None
    if count is not None and not (count.isdigit() and int(count) >= 1):
        raise ConfigError(f"JAX_NUM_PROCESSES={count!r} must be a positive integer (the number of processes)")
    if index is not None and not (index.isdigit() and (count is None or int(index) < int(count))):
        raise ConfigError(f"JAX_PROCESS_ID={index!r} must be an integer from 0 to JAX_NUM_PROCESSES - 1"
                          f"{f' = {int(count) - 1}' if count else ''}")
    return (int(count) if count else None), (int(index) if index else None)


def _cluster_detected() -> bool:
    env = os.environ
    if env.get("JAX_COORDINATOR_ADDRESS"):
        return True
    if int(env.get("SLURM_NTASKS", "1") or 1) > 1 and env.get("SLURM_JOB_ID"):
        return True
    return int(env.get("OMPI_COMM_WORLD_SIZE", "1") or 1) > 1


def manifest(p: Plan, cfg, devices, n_pad: int, n_windows: int) -> dict:
    from mjx_curio import metrics as metrics_lib
    from mjx_curio.arena import ACTIONS, OBJECTS

    return {
        "format": FORMAT,
        "created": datetime.datetime.now().isoformat(timespec="seconds"),
        "command": " ".join(["python -m", PROG] + [f"{k}={_fmt(x)}" for k, x in p.values.items()]),
        "config": config_of(p.values),
        "run_config": _plain(dataclasses.asdict(cfg)),
        "runs": [dict(index=i, name=r.name, **dataclasses.asdict(r)) for i, r in enumerate(p.runs)],
        "padded_runs": n_pad,
        "n_agents": cfg.n_agents,
        "agent_names": ["green", "purple"][: cfg.n_agents],
        "actions": list(ACTIONS),
        "objects": list(OBJECTS),
        "view_targets": list(metrics_lib.VIEW_TARGETS),
        "metrics": {"every": cfg.metrics_every, "windows": n_windows, "steps_file": "metrics/steps.npy",
                    "schema": metrics_lib.schema_doc()},
        "checkpoints": {"state": "checkpoints/state/<step>", "replay": "checkpoints/replay/<step>"},
        "versions": _versions(),
        "device": {"platform": devices[0].platform, "kind": devices[0].device_kind, "count": len(devices),
                   "processes": _process_count(), "host": platform.node(), "cpu": _cpu_name()},
        "git": _git(),
    }


def _fmt(x):
    return ",".join(map(str, x)) if isinstance(x, tuple) else x


def _plain(x):
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    if isinstance(x, (tuple, list)):
        return [_plain(v) for v in x]
    return x


def _versions() -> dict:
    from importlib import metadata

    out = {"python": platform.python_version(), "mjx_curio": mjx_curio.__version__}
    for pkg in ("jax", "jaxlib", "mujoco", "mujoco-mjx", "flax", "optax", "orbax-checkpoint", "numpy"):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = None
    return out


def _process_count() -> int:
    import jax

    return jax.process_count()


def _cpu_name() -> str:
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor()


def _git() -> dict:
    here = pathlib.Path(__file__).resolve().parent
    try:
        commit = subprocess.run(["git", "-C", str(here), "rev-parse", "HEAD"], capture_output=True, text=True, timeout=10)
        dirty = subprocess.run(["git", "-C", str(here), "status", "--porcelain", "--", "."], capture_output=True,
                               text=True, timeout=10)
        if commit.returncode == 0:
            return {"commit": commit.stdout.strip(), "dirty": bool(dirty.stdout.strip())}
    except (OSError, subprocess.TimeoutExpired):
        pass
    return {"commit": None, "dirty": None}


class Progress:
    """One line: steps done of total, aggregate run-steps per second, time left. The rate is
    measured from the end of the first chunk, which also pays for compiling."""

    def __init__(self, start: int, total: int, n_runs: int, enabled: bool):
        self.start, self.total, self.n_runs, self.enabled = start, total, n_runs, enabled
        self.t0 = time.perf_counter()
        self.base = None  # (time, step) when the first chunk finished
        self.tty = sys.stderr.isatty()
        self.last = 0.0

    def rate(self, step: int, now: float) -> float:
        t, s = self.base if self.base and step > self.base[1] else (self.t0, self.start)
        return (step - s) * self.n_runs / (now - t) if now > t else 0.0

    def update(self, step: int) -> None:
        now = time.perf_counter()
        if self.base is None:
            self.base = (now, step)
        if not self.enabled or (self.tty and now - self.last < 0.5 and step < self.total):
            return
        self.last = now
        rate = self.rate(step, now)
        left = (self.total - step) * self.n_runs / rate if rate > 0 else float("nan")
        width = 30
        filled = int(width * step / self.total)
        line = (f"[{'#' * filled}{'.' * (width - filled)}] step {step:,}/{self.total:,}  "
                f"{rate:,.1f} run-steps/s ({self.n_runs} runs)  elapsed {_hms(now - self.t0)}  left {_hms(left)}")
        print(("\r" + line) if self.tty else line, end="" if self.tty else "\n", file=sys.stderr, flush=True)

    def message(self, text: str) -> None:
        if self.enabled and self.tty:
            print(file=sys.stderr)
        print(text, file=sys.stderr, flush=True)

    def done(self) -> None:
        if self.enabled and self.tty:
            print(file=sys.stderr)


def _hms(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "?"
    s = int(round(seconds))
    return f"{s // 3600}:{s % 3600 // 60:02d}:{s % 60:02d}"


if __name__ == "__main__":
    raise SystemExit(main())
