"""The sweep as a user runs it: `python -m mjx_curio.sweep ...` in a subprocess.

Every run is compared with the session's tiny sweep (tests/conftest.py: 8 runs, 16 px, 200 steps,
checkpoints at 100 and 200) bit for bit where the design guarantees it: the runs loop executes
each run with the program of a run alone, so alone, in a bigger sweep or resumed, on one device,
a run gives identical numbers. That a run alone and inside a sweep agree holds for XLA's default
codegen, which users' runs compile with: its test reads two sweeps compiled so, whereas the
session's other programs compile for compile speed (conftest.py), under which those two were
measured to differ in the last bit. Sharded over two devices, XLA compiles another program, whose
float rounding may differ in the last bit; that test compares only what cannot have grown apart.
"""

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

import json
import shutil
import signal
import subprocess
import sys
import time

import jax
import numpy as np
import pytest

from conftest import ADDED_XLA_FLAGS, CACHE, SMALL_LEARNER, STOPPED_BY, TINY_SWEEP, sweep_in_process
from mjx_curio import analysis as an
from mjx_curio import checkpoint as ckpt_lib
from mjx_curio import sweep as sweep_lib
from mjx_curio.arena import ACTIONS
from mjx_curio.config import ConfigError
from mjx_curio.metrics import SCHEMA

N_RUNS = 8  # eps x 2 seeds, boltzmann x 2 temperatures x 2 seeds, ucb x 2 seeds


def _metrics(out, runs=slice(None)):
    return {name: np.load(out / "metrics" / f"{name}.npy")[runs] for name in SCHEMA}


def _assert_same_metrics(a: dict, b: dict, what: str):
    for name in SCHEMA:
        np.testing.assert_array_equal(a[name], b[name], err_msg=f"{what}: metric {name} differs")


def _state(out, step):
    ck = ckpt_lib.Checkpoints(out / "checkpoints", read_only=True)
    try:
        return ck.restore_raw(step)
    finally:
        ck.close()


def _assert_same_tree(a, b, what: str):
    la, lb = jax.tree_util.tree_flatten_with_path(a)[0], jax.tree_util.tree_flatten_with_path(b)[0]
    assert [p for p, _ in la] == [p for p, _ in lb], what
    for (path, x), (_, y) in zip(la, lb):
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y), err_msg=f"{what}: {jax.tree_util.keystr(path)}")


def _snapshot(directory):
    return sorted((str(p.relative_to(directory)), p.stat().st_size, p.stat().st_mtime_ns) for p in directory.rglob("*"))


# ---------------------------------------------------------------------------------------------


def test_tiny_sweep_writes_metrics_and_checkpoints_that_load_back(tiny_sweep):
    manifest = json.loads((tiny_sweep / "manifest.json").read_text())
    names = [r["name"] for r in manifest["runs"]]
    assert len(names) == N_RUNS and len(set(names)) == N_RUNS
    assert {r["policy"] for r in manifest["runs"]} == {"eps", "boltzmann", "ucb"}
    assert sorted({r["temperature"] for r in manifest["runs"] if r["policy"] == "boltzmann"}) == [0.5, 1.5]
    for key in ("versions", "device", "git", "config"):
        assert manifest[key], key
    assert manifest["versions"]["jax"] and manifest["device"]["platform"] == "cpu"
    assert manifest["device"]["matmul_precision"] == str(jax.config.jax_default_matmul_precision or "default")
    # Compiled for compile speed, as every program of the session but the users' codegen ones.
    assert all(flag in manifest["device"]["xla_flags"].split() for flag in ADDED_XLA_FLAGS), manifest["device"]
    assert json.loads((tiny_sweep / "progress.json").read_text())["steps_done"] == 200

    m = _metrics(tiny_sweep)
    steps = np.load(tiny_sweep / "metrics" / "steps.npy")
    np.testing.assert_array_equal(steps, np.arange(20, 201, 20))
    assert m["curiosity"].shape == (N_RUNS, 10, 2)
    assert np.isfinite(m["curiosity"]).all() and (m["curiosity"] >= 0).all()
    assert (m["action_counts"].sum(-1) == 20).all()  # every agent acts every step
    # Turning back can happen at most at the 19 steps of a window after its first, and no more
    # often than the rarer of the two turns allows; near-random choices do it now and then.
    rot = m["action_counts"][..., ACTIONS.index("rotate_left") : ACTIONS.index("rotate_right") + 1]
    assert (m["rotation_reversals"] <= np.minimum(19, 2 * rot.min(-1))).all() and m["rotation_reversals"].sum() > 0
    assert (m["steps_taken"] == 20).all() and (m["non_finite"] == 0).all()
    # Learning starts once replay holds a sequence (17 steps), then every 4 steps.
    assert m["updates"][:, 0].tolist() == [1] * N_RUNS and (m["updates"][:, 1:] == 5).all()
    assert np.isfinite(m["vae_loss"]).all() and np.isfinite(m["nll"]).all()
    # UCB tries every action before repeating one: 7 distinct actions in its first 7 steps.
    ucb = [r["index"] for r in manifest["runs"] if r["policy"] == "ucb"]
    assert (m["action_counts"][ucb, 0] >= 1).all()
    frac = m["view_fraction"]
    assert ((frac >= 0) & (frac <= 1)).all() and frac.sum(-1).max() <= 1

    ck = ckpt_lib.Checkpoints(tiny_sweep / "checkpoints", read_only=True)
    assert ck.state_steps() == [100, 200] and ck.replay_steps() == [200] and ck.latest_complete() == 200
    ck.close()
    raw = _state(tiny_sweep, 200)
    assert (np.asarray(raw["step"]) == 200).all()
    assert raw["frames"].shape == (N_RUNS, 2, 16, 16, 3) and raw["frames"].dtype == np.uint8
    assert all(np.isfinite(x).all() for x in jax.tree.leaves(raw["learner"]))


def test_the_same_seed_gives_the_same_metrics_alone_and_inside_a_sweep(users_tiny_sweep, users_alone_sweep):
    """Both sweeps compiled with XLA's default codegen, as users' runs are (conftest.py)."""
    manifest = json.loads((users_tiny_sweep / "manifest.json").read_text())
    for m in (manifest, json.loads((users_alone_sweep / "manifest.json").read_text())):
        assert not set(m["device"]["xla_flags"].split()) & set(ADDED_XLA_FLAGS), m["device"]
    (index,) = [r["index"] for r in manifest["runs"] if r["name"] == "ucb-ucb_c1-seed1"]
    _assert_same_metrics(_metrics(users_alone_sweep, 0), _metrics(users_tiny_sweep, index), "run alone vs in the sweep")


def test_a_second_writer_is_refused_and_resume_after_sigkill_equals_the_run_that_never_stopped(tiny_sweep, tmp_path):
    out = tmp_path / "killed"
    cmd = [sys.executable, "-m", "mjx_curio.sweep", *TINY_SWEEP, f"out={out}", f"compile_cache={CACHE}"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 600
    refused = []
    while time.monotonic() < deadline and proc.poll() is None:
        if not refused and (out / "manifest.json").exists():
            # One writer per directory: a second sweep on it, with or without resume, is refused
            # before any work, naming the process that holds it; nothing of the first is touched.
            for extra in ((), ("resume=true",)):
                refused.append(sweep_in_process(*TINY_SWEEP, f"out={out}", *extra, check=False))
        progress = out / "progress.json"
        if progress.exists() and json.loads(progress.read_text())["checkpoint"] == 100:
            proc.send_signal(signal.SIGKILL)
            break
        time.sleep(0.05)
    proc.wait(timeout=60)
    assert proc.returncode == -signal.SIGKILL, f"not killed mid-sweep:\n{proc.stderr.read()[-2000:]}"
    assert json.loads((out / "progress.json").read_text())["steps_done"] == 100
    assert len(refused) == 2
    for rc, stderr in refused:
        assert rc == 2 and f"out={out} is in use by another sweep (pid {proc.pid} on host " in stderr, stderr[-2000:]

    # The kernel dropped the killed sweep's lock with it: resume takes over at once.

    _, stderr = sweep_in_process(*TINY_SWEEP, f"out={out}", "resume=true")
    assert "restored step 100" in stderr
    _assert_same_metrics(_metrics(out), _metrics(tiny_sweep), "resumed vs straight")
    _assert_same_tree(_state(out, 200), _state(tiny_sweep, 200), "final checkpoint, resumed vs straight")


def test_killed_while_writing_a_checkpoint_resumes_from_the_previous_one(tiny_sweep, crashed_sweep):
    out, returncode, stderr = crashed_sweep  # the tiny sweep, its crash hook set to kill it (conftest.py)
    assert STOPPED_BY["crashed_sweep"][0] == {ckpt_lib.CRASH_ENV: "after-state:200"}
    assert returncode == -signal.SIGKILL, stderr[-2000:]
    ckdir = out / "checkpoints"
    assert (ckdir / "state" / "200").exists() and not (ckdir / "replay" / "200").exists()
    # What orbax leaves when killed inside a write: a temporary directory, never a step directory.
    junk = ckdir / "replay" / "200.orbax-checkpoint-tmp-123456"
    junk.mkdir()
    (junk / "partial").write_bytes(b"\0" * 100)
    _assert_same_tree(_state(out, 100), _state(tiny_sweep, 100), "the previous checkpoint")

    _, stderr = sweep_in_process(*TINY_SWEEP, f"out={out}", "resume=true")
    assert "restored step 100" in stderr and "incomplete" in stderr
    assert not junk.exists()
    _assert_same_metrics(_metrics(out), _metrics(tiny_sweep), "resumed after a crash in a write vs straight")
    _assert_same_tree(_state(out, 200), _state(tiny_sweep, 200), "final checkpoint")


def test_checkpoints_written_in_the_background_equal_those_the_sweep_waited_for(tiny_sweep, tmp_path):
    # On a CPU the sweep waits for each write (async_checkpoints=auto); asked to write in the
    # background it steps on meanwhile, its next chunk unable to donate the state being written
    # (tests/test_checkpoint.py). The same program: the same numbers, bit for bit.
    out = tmp_path / "background"
    sweep_in_process(*TINY_SWEEP, f"out={out}", "async_checkpoints=true")
    for sweep, background in ((tiny_sweep, False), (out, True)):
        assert json.loads((sweep / "manifest.json").read_text())["checkpoints"]["written_in_background"] is background
    assert json.loads((out / "progress.json").read_text())["checkpoint"] == 200
    _assert_same_metrics(_metrics(out), _metrics(tiny_sweep), "checkpoints in the background vs waited for")
    for step in (100, 200):
        _assert_same_tree(_state(out, step), _state(tiny_sweep, step), f"checkpoint {step}")
    ck, ref = (ckpt_lib.Checkpoints(d / "checkpoints", read_only=True) for d in (out, tiny_sweep))
    _assert_same_tree(ck.restore_raw(200, "replay"), ref.restore_raw(200, "replay"), "replay at step 200")
    ck.close()
    ref.close()


@pytest.mark.parametrize("interrupted_sweep", ["sigint_sweep", "sigterm_sweep"], ids=["ctrl-c", "sigterm"], indirect=True)
def test_an_interrupted_sweep_checkpoints_says_how_to_resume_and_resumes_exactly(interrupted_sweep, tiny_sweep, tmp_path):
    # The tiny sweep planned for 300 steps in a subprocess, sent the signal once its first chunk is
    # done, so that it arrives during the second (conftest.py).
    signum, out, rc, stderr = interrupted_sweep
    assert rc == 128 + signum, stderr[-3000:]
    assert "Traceback" not in stderr, stderr[-3000:]
    name = signal.Signals(signum).name
    # The signal lands while the second chunk runs (or, if it wins the race with the loop's check,
    # just before it starts): the sweep stops at the end of that chunk.
    stopped = json.loads((out / "progress.json").read_text())["steps_done"]
    assert stopped in (100, 200)
    assert f"{name}: stopping at step {stopped}, writing a checkpoint" in stderr, stderr[-3000:]
    assert f"sweep stopped by {name}: its newest complete checkpoint is step {stopped} of 300" in stderr, stderr[-3000:]
    assert json.loads((out / "progress.json").read_text())["checkpoint"] == stopped
    command = stderr.split("resume with:\n", 1)[1].split("\n", 1)[0].strip()
    assert command.startswith("python -m mjx_curio.sweep ") and command.endswith(f"out={out} resume=true")
    given = [a for a in command.split()[3:] if not a.startswith("compile_cache=")]  # the test's own cache
    assert "steps=300" in given and "image=16" in given and "seeds=2" in given

    if signum == signal.SIGTERM:
        # Finishing early: resume with fewer steps than planned (but no fewer than done) ends there,
        # equal to the sweep that was planned for 200 steps and never stopped.
        _, err = sweep_in_process(*[a for a in given if not a.startswith("steps=")], "steps=200")
        assert f"restored step {stopped}" in err
        _assert_same_metrics(_metrics(out), _metrics(tiny_sweep), "stopped, then resumed with steps=200")
        _assert_same_tree(_state(out, 200), _state(tiny_sweep, 200), "final checkpoint")
        manifest = json.loads((out / "manifest.json").read_text())
        assert manifest["config"]["steps"] == 200 and manifest["metrics"]["windows"] == 10
        assert manifest["steps_planned"] == [{"steps": 300, "from_step": 0}, {"steps": 200, "from_step": stopped}]
        np.testing.assert_array_equal(np.load(out / "metrics" / "steps.npy"), np.arange(20, 201, 20))
        return
    # The printed command continues it to 300 steps, equal to the tiny sweep continued to 300.
    _, err = sweep_in_process(*given)
    assert f"restored step {stopped}" in err
    straight = tmp_path / "straight"
    shutil.copytree(tiny_sweep, straight)
    sweep_in_process(*[a for a in TINY_SWEEP if a != "steps=200"], "steps=300", f"out={straight}", "resume=true")
    _assert_same_metrics(_metrics(out), _metrics(straight), "interrupted and resumed vs straight, 300 steps")
    _assert_same_tree(_state(out, 300), _state(straight, 300), "final checkpoint")


@pytest.mark.slow
def test_the_authors_vae_layers_checkpoint_their_running_averages_and_resume_exactly(tmp_path):
    """vae_layers=authors: batch normalisation's running averages are part of each run's state,
    saved with its checkpoints and restored on resume (what acting normalises by), so a resumed
    sweep equals the one that never stopped; the analysis reads them beside the weights."""
    args = ("agents=1", "policies=eps", "seeds=1", "image=16", *SMALL_LEARNER, "vae_layers=authors", "buffer=500",
            "chunk=100", "checkpoint_every=100", "keep_steps=100", "keep_every=0", "progress=false")
    straight, stopped = tmp_path / "straight", tmp_path / "stopped"
    sweep_in_process(*args, "steps=200", f"out={straight}")
    sweep_in_process(*args, "steps=100", f"out={stopped}")
    _, stderr = sweep_in_process(*args, "steps=200", f"out={stopped}", "resume=true")
    assert "restored step 100" in stderr
    _assert_same_metrics(_metrics(stopped), _metrics(straight), "resumed vs straight")
    _assert_same_tree(_state(stopped, 200), _state(straight, 200), "final checkpoint, resumed vs straight")
    stats = an.load(straight).params(200, 0)["vae_stats"]
    assert {"down_norm_0", "up_norm_0"} <= set(stats)
    assert not np.allclose(stats["down_norm_0"]["var"], 1.0)  # updated from their initial 0 and 1


def test_a_chunk_compiled_ahead_of_time_is_the_jitted_chunk(tiny_sweep, tmp_path):
    """SweepProgram.compile (what `python -m mjx_curio.bench what=sweep` times as compiling) runs
    the program chunk() runs through jit: from the same start, bit for bit the same states and
    metrics. The tiny sweep compiled that program in this process already (tiny_sweep first)."""
    import dataclasses

    from mjx_curio import cli
    from mjx_curio import plan as plan_lib
    from mjx_curio.program import SweepProgram

    p = plan_lib.plan(cli.parse([*TINY_SWEEP, f"out={tmp_path / 'unused'}"], sweep_lib.KEYS))
    cfg = dataclasses.replace(p.run, runs_loop="map")  # what the sweep picks on a CPU
    n_pad = -len(p.runs) % len(jax.devices())
    jitted, ahead = (SweepProgram(cfg, p.runs, n_pad, p.values["chunk"]) for _ in range(2))
    start = ahead.init()
    ahead.compile(start)
    got = ahead.chunk(start)  # the chunk donates its input: each program starts from its own init
    want = jitted.chunk(jitted.init())
    plain = lambda tree: jax.tree.map(  # noqa: E731  (PRNG keys as their raw data)
        lambda x: jax.random.key_data(x) if jax.dtypes.issubdtype(x.dtype, jax.dtypes.prng_key) else x, tree)
    _assert_same_tree(plain(got), plain(want), "a chunk compiled ahead of time vs the jitted one")


def test_sharding_gives_every_device_its_own_runs_with_their_own_keys(tiny_sweep, sharded_sweep):
    """TINY_SWEEP on two forced host devices (conftest.py) against the same sweep on one.

    What sharding guarantees, and so what this asks, on any CPU: every device advances the runs
    the plan gave it, with their own seeds and settings. Two device counts compile two programs,
    whose float rounding may differ in the last bit; along a chaotic run such differences grow
    (on one CPU, with the paper's network sizes, 35 of 160 curiosity windows parted by up to 14 %
    within 200 steps), so only two things are compared: (1) the first metrics window, 20 steps,
    before rounding can have grown: the same actions and contacts, floats to 1e-4 (measured:
    equal but for the predictions, 1.2e-7), the memory's and self-models' training losses to
    1e-2 (see `LOSS_RTOL`), while a run on the wrong device slot, or with another key, differs
    at O(1) from its first step (measured with device 1's keys changed: the curiosity of all
    its runs, by up to 34 %); (2) what involves no float at all: every run's random stream,
    step count and policy settings after 200 steps."""
    manifest = json.loads((sharded_sweep / "manifest.json").read_text())
    assert manifest["device"]["count"] == 2 and manifest["padded_runs"] == 0
    assert_same_runs_on_other_devices(sharded_sweep, tiny_sweep, "2 devices vs 1")


# The MDN-RNN trains on the replay frames re-encoded by the current VAE (latents=reencode): an
# encoder pass over the sample's frames each update (512 at the paper's sizes) whose sums run in
# an order that depends on how many threads a device has, and Adam turns last-bit gradient
# differences near zero into steps of the learning rate's size. Measured on the first window of
# the tiny sweep with the paper's network sizes, 2 devices vs 1 (AMD EPYC): nll 5.1e-4, self_loss
# 1.7e-3, self_loss_agents 2.2e-3 relative; every other metric, curiosity included, equal (the
# training batch's curiosity, recorded since, is computed from those latents as the nll is). With
# TINY_SWEEP's small networks (Intel Xeon): every metric of every window equal but the predictions
# (1.2e-7).
LOSS_RTOL = {"nll": 1e-2, "self_loss": 1e-2, "self_loss_agents": 1e-2, "batch_curiosity": 1e-2}


def assert_same_runs_on_other_devices(out, reference, what: str):
    """`out` holds the runs of `reference` (a sweep of the same runs on another number of devices
    or processes): the same runs in the same order, the same first metrics window (integers
    exactly, floats to 1e-4, the memory's and self-models' losses to LOSS_RTOL), and the same
    random streams, step counts and settings at the end."""
    assert json.loads((out / "manifest.json").read_text())["runs"] == json.loads((reference / "manifest.json").read_text())["runs"]
    first = (slice(None), slice(0, 1))
    a, b = _metrics(out, first), _metrics(reference, first)
    for name in SCHEMA:
        if np.issubdtype(b[name].dtype, np.floating):
            np.testing.assert_allclose(a[name], b[name], rtol=LOSS_RTOL.get(name, 1e-4), atol=1e-6,
                                       err_msg=f"{what}, first window: {name}")
        else:
            np.testing.assert_array_equal(a[name], b[name], err_msg=f"{what}, first window: {name}")
    end = int(np.load(reference / "metrics" / "steps.npy")[-1])
    a, b = _state(out, end), _state(reference, end)
    for leaf in ("key", "step", "policy", "halted", "halted_step"):
        _assert_same_tree(a[leaf], b[leaf], f"{what}, after {end} steps: {leaf}")


def _poison_at(monkeypatch, at_step: int, edit):
    """Replace the states with `edit(states)` when the sweep reaches `at_step`: the program's chunk
    wrapped for this test only."""
    from mjx_curio import program

    real = program.SweepProgram.chunk

    def chunk(self, states):
        if int(np.asarray(states.step)[0]) == at_step:
            states = edit(states)
        return real(self, states)

    monkeypatch.setattr(program.SweepProgram, "chunk", chunk)


def _nan_in_run(x, run: int):
    """x [runs, ...] with run `run`'s entries NaN."""
    import jax.numpy as jnp

    return jnp.where((jnp.arange(x.shape[0]) == run).reshape((-1,) + (1,) * (x.ndim - 1)), jnp.nan, x)


def _poison_replay_carry(monkeypatch, run: int, at_step: int):
    """Fill run `run`'s stored LSTM states in replay with NaN when the sweep reaches `at_step`:
    its next MDN-RNN BPTT starts from one, so the loss is NaN (whatever latents it trains on)."""
    def edit(states):
        carry = tuple(_nan_in_run(x, run) for x in states.replay.carry)
        return states._replace(replay=states.replay._replace(carry=carry))

    _poison_at(monkeypatch, at_step, edit)


def _sweep_halting_one_run(tiny_sweep, out, bad: int, says: str, halted_at: int) -> dict:
    """The tiny sweep into `out` with a fault planted in run `bad`: the sweep exits 1 saying
    `says` of that run, records it halted at `halted_at`, and every other run, and this one's
    first 5 windows (steps 0-100), are as in the clean sweep. Returns the metrics."""
    rc, stderr = sweep_in_process(*TINY_SWEEP, f"out={out}", check=False)
    assert rc == 1, stderr[-2000:]
    name = json.loads((out / "manifest.json").read_text())["runs"][bad]["name"]
    assert f"run {bad} ({name}): {says}" in stderr
    assert json.loads((out / "progress.json").read_text())["halted"] == {str(bad): halted_at}
    clean, m = _metrics(tiny_sweep), _metrics(out)
    others = [r for r in range(N_RUNS) if r != bad]
    _assert_same_metrics({k: v[others] for k, v in m.items()}, {k: v[others] for k, v in clean.items()}, "other runs")
    _assert_same_metrics({k: v[bad, :5] for k, v in m.items()}, {k: v[bad, :5] for k, v in clean.items()}, "before")
    # A halted run keeps the pose of its last good state, so the analysis sees a halt, not a
    # divergence to drop (analysis.drop_diverged), and reads the step it halted at as recorded.
    assert np.isfinite(m["agent_pose"][bad]).all() and np.isfinite(m["object_pos"][bad]).all()
    assert an.load(out).progress["halted"] == {str(bad): halted_at}
    return m


def test_a_nan_loss_halts_that_run_only_and_keeps_its_last_good_state(tiny_sweep, tmp_path, monkeypatch):
    out, bad = tmp_path / "nan", 3
    _poison_replay_carry(monkeypatch, run=bad, at_step=100)
    m = _sweep_halting_one_run(tiny_sweep, out, bad, "a loss became non-finite", 104)
    assert m["non_finite"][bad, 5] == 1 and m["steps_taken"][bad, 5] == 4 and (m["steps_taken"][bad, 6:] == 0).all()
    assert np.isnan(m["curiosity"][bad, 6:]).all()
    # Its last good state: the networks after the update at step 100, the last one that was finite.
    halted = jax.tree.map(lambda x: x[bad], _state(out, 200)["learner"])
    good = jax.tree.map(lambda x: x[bad], _state(tiny_sweep, 100)["learner"])
    _assert_same_tree(halted, good, "halted run's networks vs the clean run's at step 100")
    assert all(np.isfinite(x).all() for x in jax.tree.leaves(halted))


def _poison_physics(monkeypatch, run: int, at_step: int):
    """Fill run `run`'s joint velocities with NaN when the sweep reaches `at_step`: its next
    physics step diverges, as a simulation that blows up does."""
    def edit(states):
        data = states.env.data.replace(qvel=_nan_in_run(states.env.data.qvel, run))
        return states._replace(env=states.env.replace(data=data))

    _poison_at(monkeypatch, at_step, edit)


def test_diverged_physics_halts_that_run_only_and_masks_its_windows(tiny_sweep, tmp_path, monkeypatch):
    out, bad = tmp_path / "diverged", 5
    _poison_physics(monkeypatch, run=bad, at_step=100)
    m = _sweep_halting_one_run(tiny_sweep, out, bad, "the physics diverged", 100)
    # From step 100 on no step was taken: nothing counted, no pose or curiosity recorded.
    assert (m["steps_taken"][bad, 5:] == 0).all() and (m["action_counts"][bad, 5:] == 0).all()
    assert np.isnan(m["curiosity"][bad, 5:]).all() and (m["updates"][bad, 5:] == 0).all()
    assert int(_state(out, 200)["step"][bad]) == 100


# --------------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    "args, knob, allowed",
    [
        (["policies=eps,greedy"], "policies='greedy'", "'eps', 'boltzmann', 'ucb'"),
        (["seeds=0"], "seeds=0", ">= 1"),
        (["steps=abc"], "steps='abc'", "integer >= 1"),
        (["steps=-5"], "steps=-5", ">= 1"),
        (["steps=1.5"], "steps='1.5'", "integer"),
        (["colour=red"], "unknown key 'colour'", "policies, seeds"),
        (["agents=3"], "agents=3", "[1, 2]"),
        (["image=48"], "image=48", "power of two"),
        (["temperature=0"], "temperature=0.0", "> 0.0"),
        (["eps=1.5"], "eps=1.5", "<= 1.0"),
        (["steps=150", "chunk=100"], "steps=150", "multiple of chunk=100"),
        (["walls=glass"], "walls='glass'", "'same', 'different'"),
        (["resume=true"], "resume=true needs out=", "sweep directory"),
        (["latent=0"], "latent=0", "integer >= 1"),
        (["mixtures=two"], "mixtures='two'", "integer >= 1"),
        (["kl_tolerance=-1"], "kl_tolerance=-1.0", ">= 0.0"),
        (["vae_channels=32,64"], "dec_channels=128,64,32,16", "one width per encoder layer"),
        (["latents=fresh"], "latents='fresh'", "'stored', 'reencode'"),
        (["async_checkpoints=yes"], "async_checkpoints='yes'", "'auto', 'true', 'false'"),
        (["policies=ucb", "eps=0.1,0.5"], "eps=0.1,0.5 lists several values", "add eps to policies"),
        (["compile_cache=/dev/null"], "compile_cache=/dev/null is a file", "name a directory"),
        # Alone, with no cluster to join: refused before out is made or locked.
        (["distributed=true"], "distributed=true: joining the cluster failed", "JAX_COORDINATOR_ADDRESS"),
    ],
)
def test_bad_input_stops_before_any_work(args, knob, allowed, tmp_path):
    out = tmp_path / "never"
    extra = [] if any(a.startswith("resume") for a in args) else [f"out={out}"]
    proc = subprocess.run([sys.executable, "-m", "mjx_curio.sweep", *args, *extra], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 2, proc.stderr
    assert knob in proc.stderr and allowed in proc.stderr, proc.stderr
    assert not out.exists()


@pytest.mark.parametrize("out, why", [("/proc/nope/sweep", "cannot be created"), ("/dev/null/sweep", "is not a directory")])
def test_an_out_that_cannot_be_created_is_refused_with_a_message(out, why):
    proc = subprocess.run([sys.executable, "-m", "mjx_curio.sweep", f"out={out}"], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
    assert proc.stderr.startswith(f"error: out={out} cannot be created") and why in proc.stderr, proc.stderr


def test_an_existing_sweep_is_never_overwritten(tiny_sweep):
    before = _snapshot(tiny_sweep)
    rc, stderr = sweep_in_process(*TINY_SWEEP, f"out={tiny_sweep}", check=False)
    assert rc == 2 and "already holds a sweep" in stderr and "resume=true" in stderr
    other = [a for a in TINY_SWEEP if not a.startswith("seeds=")] + ["seeds=3"]
    rc, stderr = sweep_in_process(*other, f"out={tiny_sweep}", "resume=true", check=False)
    assert rc == 2 and "other settings" in stderr and "seeds: saved 2, given 3" in stderr
    assert _snapshot(tiny_sweep) == before


def test_plan_refuses_a_non_sweep_directory(tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    values = sweep_lib.cli.parse([f"out={tmp_path}"], sweep_lib.KEYS)
    with pytest.raises(ConfigError, match="not an empty directory"):
        sweep_lib.plan(values)
    values = sweep_lib.cli.parse([f"out={tmp_path}", "resume=true"], sweep_lib.KEYS)
    with pytest.raises(ConfigError, match="holds no sweep"):
        sweep_lib.plan(values)
    assert [p.name for p in tmp_path.iterdir()] == ["notes.txt"]


@pytest.mark.parametrize("text, why", [("{not json", "cannot be read as a sweep's JSON"), ("[1, 2]", "a JSON list")])
def test_resume_refuses_a_damaged_manifest_naming_it(text, why, tmp_path):
    (tmp_path / "manifest.json").write_text(text)
    values = sweep_lib.cli.parse([f"out={tmp_path}", "resume=true"], sweep_lib.KEYS)
    with pytest.raises(ConfigError, match=why) as err:
        sweep_lib.plan(values)
    assert str(tmp_path / "manifest.json") in str(err.value)
    assert (tmp_path / "manifest.json").read_text() == text


def test_grid_multiplies_each_policy_by_its_own_setting_only():
    values = sweep_lib.cli.parse(["policies=eps,boltzmann,ucb", "seeds=2", "temperature=0.5,1,2", "eps=0.1,0.2"],
                                 sweep_lib.KEYS)
    runs = sweep_lib.grid(values)
    by_policy = {p: [r for r in runs if r.policy == p] for p in ("eps", "boltzmann", "ucb")}
    assert [len(v) for v in by_policy.values()] == [4, 6, 2]
    assert sorted({r.temperature for r in by_policy["boltzmann"]}) == [0.5, 1.0, 2.0]
    assert {r.temperature for r in by_policy["eps"]} == {0.5}  # unused by eps: not multiplied
    with pytest.raises(ConfigError, match="same run twice"):
        sweep_lib.grid(sweep_lib.cli.parse(["policies=eps,eps"], sweep_lib.KEYS))


def test_help_lists_every_knob_with_its_default_as_a_user_types_it():
    proc = subprocess.run([sys.executable, "-m", "mjx_curio.sweep", "--help"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0
    for key in sweep_lib.KEYS:
        assert f"  {key.name} " in proc.stdout, key.name
    lines = {line.split()[0]: line for line in proc.stdout.splitlines() if line.startswith("  ")}
    assert lines["save_replay"].endswith("[true]") and lines["resume"].endswith("[false]")
    assert lines["out"].endswith("[runs/<date-time>]") and lines["policies"].endswith("[eps,boltzmann,ucb]")
    assert lines["vae_channels"].endswith("[32,64,128,256]") and lines["lr"].endswith("[0.001]")
    # Every default shown parses back to itself.
    for key in sweep_lib.KEYS:
        if key.shown is None:
            assert key.parse(key.show_default()) == key.default, key.name


def test_every_learner_and_run_knob_is_a_sweep_key_recorded_in_the_manifest(tiny_sweep):
    from mjx_curio import config

    keys = {k.name for k in sweep_lib.KEYS}
    for cls in (config.LearnerConfig, config.RunConfig, config.SweepConfig):
        for f in config.knobs(cls):
            assert config.key_name(f) in keys or not f.metadata["cli"], f.name
    manifest = json.loads((tiny_sweep / "manifest.json").read_text())
    assert set(manifest["config"]) == keys
    values = sweep_lib.cli.parse(["latent=8", "rnn_hidden=32", "mixtures=3", "beta=2", "kl_tolerance=0",
                                  "self_hidden=16", "vae_channels=8,16", "dec_channels=8,8", "image=16"], sweep_lib.KEYS)
    learner = sweep_lib.plan({**values, "out": "/tmp/never-made"}).learner
    assert (learner.latent, learner.rnn_hidden, learner.mixtures, learner.beta, learner.kl_tolerance) == (8, 32, 3, 2.0, 0.0)
    assert (learner.self_hidden, learner.vae_channels, learner.dec_channels) == (16, (8, 16), (8, 8))


def test_every_paper_preset_plans_and_command_line_keys_override_it(tmp_path):
    presets = sweep_lib.load_presets()
    assert {"single_agent", "multi_agent", "single_agent_walls_different", "boltzmann_temperatures"} <= set(presets)
    for name in presets:
        argv = sweep_lib.apply_preset([f"preset={name}", f"out={tmp_path / name}"])
        p = sweep_lib.plan(sweep_lib.cli.parse(argv, sweep_lib.KEYS))
        assert p.values["steps"] == 80_000 and p.values["seeds"] == 8, name
        assert p.out == tmp_path / name and not p.out.exists()
    p = sweep_lib.plan(sweep_lib.cli.parse(sweep_lib.apply_preset(
        ["preset=boltzmann_temperatures", "seeds=2", f"out={tmp_path / 'b'}"]), sweep_lib.KEYS))
    assert sorted({r.temperature for r in p.runs}) == [0.5, 1.0, 1.5, 2.0, 2.5] and len(p.runs) == 10
    assert {r.policy for r in p.runs} == {"boltzmann"} and p.values["agents"] == 2
    single = sweep_lib.apply_preset(["preset=single_agent_walls_different"])
    values = sweep_lib.cli.parse(single, sweep_lib.KEYS)
    assert (values["agents"], values["walls"], values["policies"], values["out"]) == (
        1, "different", ("eps",), "runs/paper/single_agent_walls_different")
    with pytest.raises(ConfigError, match="preset='nope' is not allowed; choose one of: none, single_agent"):
        sweep_lib.apply_preset(["preset=nope"])


@pytest.mark.parametrize("env, message", [
    ({"JAX_NUM_PROCESSES": "two"}, "JAX_NUM_PROCESSES='two' must be a positive integer"),
    ({"JAX_NUM_PROCESSES": "2", "JAX_PROCESS_ID": "2"}, "JAX_PROCESS_ID='2' must be an integer from 0 to JAX_NUM_PROCESSES - 1 = 1"),
])
def test_bad_process_environment_stops_before_any_work(env, message, tmp_path, monkeypatch):
    for k, val in env.items():
        monkeypatch.setenv(k, val)
    values = sweep_lib.cli.parse([f"out={tmp_path / 'x'}"], sweep_lib.KEYS)
    with pytest.raises(ConfigError, match=message):
        sweep_lib.plan(values)
    assert not (tmp_path / "x").exists()
    sweep_lib.plan({**values, "distributed": "false"})  # not used unless distributed
