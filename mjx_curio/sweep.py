"""python -m mjx_curio.sweep key=value ... : many curious-agent runs as one compiled program.

    python -m mjx_curio.sweep policies=eps,boltzmann,ucb seeds=8

runs 3 x 8 = 24 runs of the paper side by side and leaves a directory (default runs/<time>/):
    manifest.json        every setting, the runs in order, package versions, device, git commit,
                         the metrics schema
    progress.json        steps done, newest checkpoint, halted runs (rewritten atomically)
    metrics/<name>.npy   one array per metric, [runs, windows, ...]; metrics/steps.npy gives
                         the step at the end of each window (see metrics.py)
    checkpoints/state/<step>, checkpoints/replay/<step>   orbax checkpoints (see checkpoint.py)

The stages: plan (plan.py: every check, no side effects) -> lock the directory (dirlock.py) ->
build the program (program.py) -> advance it chunk by chunk, writing metrics and checkpoints ->
report. Ctrl-C or SIGTERM ends it cleanly: the chunk under way finishes, a checkpoint is written,
and the message names it and the command that resumes.
"""

from __future__ import annotations

import datetime
import os
import pathlib
import signal
import sys
import time

import numpy as np

from mjx_curio import cli, dirlock, presets
from mjx_curio.config import ConfigError
from mjx_curio.plan import KEYS, RESUME_FREE, Plan, grid, plan, read_manifest, read_progress, resume_command  # noqa: F401
from mjx_curio.presets import apply_preset, load_presets  # noqa: F401

PROG = "mjx_curio.sweep"
SUMMARY = "Run a grid of curious-agent runs (paper 'A Multi-Agent World Model with Self-Driven Curiosity') as one program."


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if cli.wants_help(argv):
        print(cli.usage(PROG, SUMMARY, KEYS))
        print("\n" + presets.describe())
        return 0
    try:
        values = cli.parse(apply_preset(argv), KEYS)
        p = plan(values)
    except ConfigError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    return execute(p)


def execute(p: Plan) -> int:
    from mjx_curio import distributed

    try:
        _spread_over_cores(p)
        # Joining a cluster can fail (no coordinator); it does before out is made or locked.
        distributed.setup_jax(p.values["distributed"], p.values["compile_cache"])
    except ConfigError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    lead = distributed.rank_from_env() == 0
    lock = None
    if lead:
        try:
            p.out.mkdir(parents=True, exist_ok=True)
            lock = dirlock.DirLock(p.out)
        except ConfigError as err:
            print(f"error: {err}", file=sys.stderr)
            return 2
        except OSError as err:
            print(f"error: out={p.out} cannot be created or locked: {err.strerror or err}; "
                  "choose a directory you can write", file=sys.stderr)
            return 2
    stop = _StopSignals()
    try:
        return _execute(p, stop)
    except KeyboardInterrupt:  # a second Ctrl-C: stop now, without a checkpoint
        _stopped_message(p, "a second Ctrl-C (no checkpoint written for the chunk under way)")
        return 130
    finally:
        stop.restore()
        if lock is not None:
            lock.release()


class _StopSignals:
    """Ctrl-C (SIGINT) and SIGTERM, what a cluster scheduler sends before it kills a job, ask the
    sweep to stop after the chunk under way; a second Ctrl-C stops it at once."""

    def __init__(self):
        self.signum = None
        self.saved = {}
        if _main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                self.saved[sig] = signal.signal(sig, self._handle)

    def _handle(self, signum, frame):
        if self.signum == signal.SIGINT and signum == signal.SIGINT:
            raise KeyboardInterrupt
        self.signum = signum  # no print here: the handler may interrupt a write to stderr

    def restore(self):
        for sig, handler in self.saved.items():
            signal.signal(sig, handler)


def _main_thread() -> bool:
    import threading

    return threading.current_thread() is threading.main_thread()


def _spread_over_cores(p: Plan) -> None:
    """Fix the CPU device count before JAX starts (host_devices.py): a resumed sweep made on
    the CPU by one process keeps the count its padding runs were made for."""
    from mjx_curio import host_devices

    saved = None
    if p.resume:
        device = read_manifest(p.out).get("device", {})
        if device.get("platform") == "cpu" and device.get("processes", 1) == 1:
            saved = device.get("count")
    requested = p.values["host_devices"]
    host_devices.apply(host_devices.choose(requested, len(p.runs), saved), requested)


def _execute(p: Plan, stop: _StopSignals) -> int:
    import dataclasses

    import jax

    from mjx_curio import checkpoint as ckpt_lib
    from mjx_curio import distributed
    from mjx_curio import host_devices
    from mjx_curio import metrics as metrics_lib
    from mjx_curio import provenance
    from mjx_curio.program import SweepProgram

    v = p.values
    devices = jax.devices()
    lead = jax.process_index() == 0
    runs_loop = p.sweep.runs_loop if p.sweep.runs_loop != "auto" else ("map" if devices[0].platform == "cpu" else "vmap")
    cfg = dataclasses.replace(p.run, runs_loop=runs_loop)
    background = v["async_checkpoints"] == "true" or (v["async_checkpoints"] == "auto" and devices[0].platform != "cpu")
    n_runs = len(p.runs)
    n_pad = host_devices.padding(n_runs, len(devices))  # copies of run 0: every device holds as many runs
    steps, every = v["steps"], v["metrics_every"]
    n_windows = steps // every
    ckpts_dir = p.out / "checkpoints"
    if not p.resume:
        if lead:
            made = provenance.manifest(p, cfg, devices, n_pad, n_windows, background)
            metrics_lib.write_json_atomic(p.out / "manifest.json", made)
            store = metrics_lib.MetricsStore(p.out / "metrics", n_runs, n_windows, v["agents"], create=True)
            metrics_lib.write_steps(p.out / "metrics", n_windows, every)
    else:
        saved = read_manifest(p.out)
        if saved.get("padded_runs", 0) != n_pad:
            print(f"error: resume=true on {len(devices)} device(s) needs {n_pad} padding run(s); the sweep was "
                  f"saved with {saved.get('padded_runs', 0)}: resume it on {saved['device']['count']} device(s)",
                  file=sys.stderr)
            return 2
        if lead:
            store = _resize_metrics(p.out, n_runs, n_windows, v, metrics_lib, names=recorded_metrics(saved))
            if saved["config"]["steps"] != steps:
                done = read_progress(p.out).get("steps_done", 0)
                saved["config"]["steps"] = steps
                saved["metrics"]["windows"] = n_windows
                saved.setdefault("steps_planned", []).append({"steps": steps, "from_step": done})
                metrics_lib.write_json_atomic(p.out / "manifest.json", saved)
    program = SweepProgram(cfg, p.runs, n_pad, v["chunk"])
    ckpts = ckpt_lib.Checkpoints(ckpts_dir, save_replay=v["save_replay"], keep_last=v["keep_last"],
                                 keep_every=v["keep_every"] or None, keep_steps=tuple(v["keep_steps"]),
                                 asynchronous=background)

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

    from mjx_curio.progress import Progress

    progress = Progress(start, steps, n_runs, enabled=v["progress"] and lead)
    old = read_progress(p.out) if p.resume else {}
    halted_info = dict(old.get("halted", {}))
    step = last_saved = start
    # progress.json names the newest *complete* checkpoint: one still being written in the
    # background (async_checkpoints) is recorded once it is on disk.
    written = None  # (step, halted runs then) of the checkpoint under way, until recorded

    def record(block: bool):
        nonlocal written
        if written is None or (not block and ckpts.writing()):
            return
        ckpts.wait()
        done, halted_then = written
        written = None
        if lead:
            metrics_lib.write_json_atomic(p.out / "progress.json", {
                "steps_done": done, "steps": steps, "windows_done": done // every,
                "checkpoint": done, "halted": halted_then,
                "updated": datetime.datetime.now().isoformat(timespec="seconds")})

    def save(step):
        nonlocal written
        record(block=True)
        ckpts.save(step, states)
        written = (step, dict(halted_info))
        record(block=not background)

    checkpoint_steps = set(v["keep_steps"])
    while step < steps and not distributed.any_process(stop.signum is not None):
        states, m = program.chunk(states)
        # Gathers are collectives: every process takes part, whatever it then writes.
        m = {k: distributed.host(x)[:n_runs] for k, x in m.items()}
        halted = distributed.host(states.halted)[:n_runs]
        halted_at = distributed.host(states.halted_step)[:n_runs]
        w0 = step // every
        step += v["chunk"]
        if lead:
            store.write(w0, m)
            store.flush()
            for r in np.flatnonzero(halted):
                if str(r) not in halted_info:
                    halted_info[str(r)] = int(halted_at[r])
                    what = ("a loss became non-finite (NaN or inf) in the learner update" if m["non_finite"][r].any()
                            else "the physics diverged (a non-finite position or velocity) in the agent step")
                    progress.message(f"run {r} ({p.runs[r].name}): {what} at step {int(halted_at[r])}; that update or "
                                     f"step was discarded and the run is halted, frozen at its last good state, which "
                                     f"its checkpoints keep. The other runs go on.")
        if step % v["checkpoint_every"] == 0 or step == steps or step in checkpoint_steps:
            save(step)
            last_saved = step
        else:
            record(block=False)
        progress.update(step)
    if step < steps:  # stopped by a signal
        signum = stop.signum if stop.signum is not None else signal.SIGTERM
        if lead:
            progress.message(f"{signal.Signals(signum).name}: stopping at step {step}"
                             + (", writing a checkpoint (Ctrl-C again to stop at once)" if step != last_saved else ""))
        if step != last_saved:
            save(step)
        record(block=True)
        ckpts.close()
        progress.done()
        if lead:
            _stopped_message(p, signal.Signals(signum).name)
        return 128 + int(signum)
    record(block=True)
    ckpts.close()
    progress.done()
    if lead:
        print(f"sweep done: {n_runs} runs x {steps} steps in {p.out}\n"
              f"  manifest    {p.out / 'manifest.json'}\n  metrics     {p.out / 'metrics'}/*.npy\n"
              f"  checkpoints {ckpts_dir}/state/<step> (newest {step})", file=sys.stderr)
        if halted_info:
            print(f"{len(halted_info)} run(s) halted on a non-finite loss or physics state: "
                  + ", ".join(f"{p.runs[int(r)].name} at step {s}" for r, s in halted_info.items()), file=sys.stderr)
            return 1
    return 0


def _stopped_message(p: Plan, why: str) -> None:
    done = read_progress(p.out).get("checkpoint")
    where = (f"its newest complete checkpoint is step {done} of {p.values['steps']} "
             f"({p.out / 'checkpoints' / 'state' / str(done)})") if done else "it has no complete checkpoint yet"
    print(f"sweep stopped by {why}: {where}.\nresume with:\n  {resume_command(p)}", file=sys.stderr, flush=True)


def recorded_metrics(manifest: dict) -> tuple:
    """The metrics a sweep records, as its manifest lists them; a manifest from before the list
    was kept records every metric of the schema (none had been added since)."""
    from mjx_curio import metrics as metrics_lib

    return tuple(manifest["metrics"].get("schema") or metrics_lib.SCHEMA)


def _resize_metrics(out, n_runs, n_windows, v, metrics_lib, names):
    """Open the metrics of a resumed sweep, resized when `steps` changed: grown with empty
    windows, or cut to the new end (only windows not yet run are cut: plan() refuses fewer
    steps than are done). `names`: the metrics the sweep records (its manifest's: a metric
    added since it began is left out, rather than its earlier windows shown as zeros)."""
    mdir = pathlib.Path(out) / "metrics"
    for name, spec in metrics_lib.SCHEMA.items():
        if name not in names:
            continue
        path = mdir / f"{name}.npy"
        old = np.load(path, mmap_mode="r")
        if old.shape[1] != n_windows:
            tmp = path.with_name(path.name + ".resize.npy")
            new = np.lib.format.open_memmap(tmp, mode="w+", dtype=old.dtype, shape=(old.shape[0], n_windows) + old.shape[2:])
            new[...] = metrics_lib.fill_value(spec.dtype)
            kept = min(old.shape[1], n_windows)
            new[:, :kept] = old[:, :kept]
            new.flush()
            del new, old
            os.replace(tmp, path)
    metrics_lib.write_steps(mdir, n_windows, v["metrics_every"])
    return metrics_lib.MetricsStore(mdir, n_runs, n_windows, v["agents"], create=False, names=names)


if __name__ == "__main__":
    raise SystemExit(main())
