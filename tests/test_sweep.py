"""The sweep as a user runs it: `python -m mjx_curio.sweep ...` in a subprocess.

Every run is compared with the session's tiny sweep (tests/conftest.py: 8 runs, 16 px, 200 steps,
checkpoints at 100 and 200) bit for bit: the runs loop executes each run with the program of a
run alone, so alone, in a bigger sweep or resumed, a run gives identical numbers. Sharded over two
devices, XLA compiles a program for four runs a device rather than eight, and rounds some float
expressions (in MJX's contact solver among them) differently in the last bit: there the test asks
for the same actions and contacts and the same numbers to float rounding.
"""

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

import json
import os
import signal
import subprocess
import sys
import time

import jax
import numpy as np
import pytest

from conftest import CACHE, TINY_SWEEP, run_sweep, sweep_in_process
from mjx_curio import checkpoint as ckpt_lib
from mjx_curio import sweep as sweep_lib
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


def _assert_close_metrics(a: dict, b: dict, what: str):
    for name, spec in SCHEMA.items():
        if np.issubdtype(a[name].dtype, np.floating):
            np.testing.assert_allclose(a[name], b[name], rtol=1e-3, atol=1e-5, err_msg=f"{what}: metric {name} differs")
        else:  # actions, contacts, counters: exactly
            np.testing.assert_array_equal(a[name], b[name], err_msg=f"{what}: metric {name} differs")


def _assert_close_tree(a, b, what: str):
    la, lb = jax.tree_util.tree_flatten_with_path(a)[0], jax.tree_util.tree_flatten_with_path(b)[0]
    assert [p for p, _ in la] == [p for p, _ in lb], what
    for (path, x), (_, y) in zip(la, lb):
        x, y, where = np.asarray(x), np.asarray(y), f"{what}: {jax.tree_util.keystr(path)}"
        if "['data']['_impl']" in where:
            # MJX's contacts and constraint rows, recomputed from the poses every step: where two
            # faces touch, the contact points picked on them jump with the last bit of a pose.
            # The poses and velocities themselves are compared.
            continue
        if np.issubdtype(x.dtype, np.floating):
            # Loose: 200 steps grow a last-bit difference to ~1e-4 in gradient moments; a run
            # mixed up with another, or a wrong key, differs by O(1).
            np.testing.assert_allclose(x, y, rtol=1e-2, atol=1e-3, err_msg=where)
        elif x.dtype == np.uint8:  # rendered frames: a pose a rounding apart may flip an edge pixel
            assert np.mean(x != y) < 1e-3, where
        else:
            np.testing.assert_array_equal(x, y, err_msg=where)


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
    assert json.loads((tiny_sweep / "progress.json").read_text())["steps_done"] == 200

    m = _metrics(tiny_sweep)
    steps = np.load(tiny_sweep / "metrics" / "steps.npy")
    np.testing.assert_array_equal(steps, np.arange(20, 201, 20))
    assert m["curiosity"].shape == (N_RUNS, 10, 2)
    assert np.isfinite(m["curiosity"]).all() and (m["curiosity"] >= 0).all()
    assert (m["action_counts"].sum(-1) == 20).all()  # every agent acts every step
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


def test_the_same_seed_gives_the_same_metrics_alone_and_inside_a_sweep(tiny_sweep, tmp_path):
    alone = tmp_path / "alone"
    args = [a for a in TINY_SWEEP if not a.startswith(("seeds=", "temperature="))]
    sweep_in_process(*args, "policies=ucb", "seeds=1", "first_seed=1", f"out={alone}")
    manifest = json.loads((tiny_sweep / "manifest.json").read_text())
    (index,) = [r["index"] for r in manifest["runs"] if r["name"] == "ucb-ucb_c1-seed1"]
    _assert_same_metrics(_metrics(alone, 0), _metrics(tiny_sweep, index), "run alone vs in the sweep")


def test_resume_after_sigkill_equals_the_run_that_never_stopped(tiny_sweep, tmp_path):
    out = tmp_path / "killed"
    cmd = [sys.executable, "-m", "mjx_curio.sweep", *TINY_SWEEP, f"out={out}", f"compile_cache={CACHE}"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 600
    while time.monotonic() < deadline and proc.poll() is None:
        progress = out / "progress.json"
        if progress.exists() and json.loads(progress.read_text())["checkpoint"] == 100:
            proc.send_signal(signal.SIGKILL)
            break
        time.sleep(0.05)
    proc.wait(timeout=60)
    assert proc.returncode == -signal.SIGKILL, f"not killed mid-sweep:\n{proc.stderr.read()[-2000:]}"
    assert json.loads((out / "progress.json").read_text())["steps_done"] == 100

    _, stderr = sweep_in_process(*TINY_SWEEP, f"out={out}", "resume=true")
    assert "restored step 100" in stderr
    _assert_same_metrics(_metrics(out), _metrics(tiny_sweep), "resumed vs straight")
    _assert_same_tree(_state(out, 200), _state(tiny_sweep, 200), "final checkpoint, resumed vs straight")


def test_killed_while_writing_a_checkpoint_resumes_from_the_previous_one(tiny_sweep, tmp_path):
    out = tmp_path / "crashed"
    crashed = run_sweep(*TINY_SWEEP, f"out={out}", env={ckpt_lib.CRASH_ENV: "after-state:200"}, check=False)
    assert crashed.returncode == -signal.SIGKILL, crashed.stderr[-2000:]
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


def test_sharded_over_two_devices_equals_one_device(tiny_sweep, sharded_sweep):
    out = sharded_sweep  # TINY_SWEEP with XLA_FLAGS=--xla_force_host_platform_device_count=2 (conftest.py)
    assert json.loads((out / "manifest.json").read_text())["device"]["count"] == 2
    _assert_close_metrics(_metrics(out), _metrics(tiny_sweep), "2 devices vs 1")
    _assert_close_tree(_state(out, 200), _state(tiny_sweep, 200), "final checkpoint, 2 devices vs 1")


def test_a_nan_loss_halts_that_run_only_and_keeps_its_last_good_state(tiny_sweep, tmp_path):
    out = tmp_path / "nan"
    bad = 3
    rc, stderr = sweep_in_process(*TINY_SWEEP, f"out={out}", env={sweep_lib.FAULT_ENV: f"nan-latents:{bad}:100"},
                                  check=False)
    assert rc == 1, stderr[-2000:]
    name = json.loads((out / "manifest.json").read_text())["runs"][bad]["name"]
    assert f"run {bad} ({name}): a loss became non-finite" in stderr
    assert json.loads((out / "progress.json").read_text())["halted"] == {str(bad): 104}

    clean, m = _metrics(tiny_sweep), _metrics(out)
    others = [r for r in range(N_RUNS) if r != bad]
    _assert_same_metrics({k: v[others] for k, v in m.items()}, {k: v[others] for k, v in clean.items()}, "other runs")
    _assert_same_metrics({k: v[bad, :5] for k, v in m.items()}, {k: v[bad, :5] for k, v in clean.items()}, "before")
    assert m["non_finite"][bad, 5] == 1 and m["steps_taken"][bad, 5] == 4 and (m["steps_taken"][bad, 6:] == 0).all()
    assert np.isnan(m["curiosity"][bad, 6:]).all()
    # Its last good state: the networks after the update at step 100, the last one that was finite.
    halted = jax.tree.map(lambda x: x[bad], _state(out, 200)["learner"])
    good = jax.tree.map(lambda x: x[bad], _state(tiny_sweep, 100)["learner"])
    _assert_same_tree(halted, good, "halted run's networks vs the clean run's at step 100")
    assert all(np.isfinite(x).all() for x in jax.tree.leaves(halted))


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


def test_an_existing_sweep_is_never_overwritten(tiny_sweep):
    before = _snapshot(tiny_sweep)
    rc, stderr = sweep_in_process(*TINY_SWEEP, f"out={tiny_sweep}", check=False)
    assert rc == 2 and "already holds a sweep" in stderr and "resume=true" in stderr
    other = [a for a in TINY_SWEEP if not a.startswith("seeds=")] + ["seeds=3"]
    rc, stderr = sweep_in_process(*other, f"out={tiny_sweep}", "resume=true", check=False)
    assert rc == 2 and "another config" in stderr and "seeds: saved 2, given 3" in stderr
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


def test_help_lists_every_key():
    proc = subprocess.run([sys.executable, "-m", "mjx_curio.sweep", "--help"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0
    for key in sweep_lib.KEYS:
        assert f"  {key.name} " in proc.stdout, key.name


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
