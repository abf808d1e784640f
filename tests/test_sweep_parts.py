"""The sweep's parts one by one (lock, plan, metrics files, progress line, provenance), and one
minimal sweep end to end: the quick tier's cover of what tests/test_sweep.py checks in depth."""

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

import json
import os
import signal
import subprocess
import sys

import numpy as np
import pytest

from mjx_curio import config, dirlock, metrics, plan, progress, provenance
from mjx_curio.config import ConfigError
from mjx_curio.presets import apply_preset
from mjx_curio import sweep as sweep_lib


# ------------------------------------------------------------------------------------ the lock


def test_the_lock_admits_one_holder_and_names_it(tmp_path):
    lock = dirlock.DirLock(tmp_path)
    try:
        with pytest.raises(ConfigError, match=rf"in use by another sweep \(pid {os.getpid()} on host "):
            dirlock.check_free(tmp_path)
        with pytest.raises(ConfigError, match="in use by another sweep"):
            dirlock.DirLock(tmp_path)  # flock locks are per open file: a second open conflicts here too
    finally:
        lock.release()
    dirlock.check_free(tmp_path)  # released: free again
    dirlock.DirLock(tmp_path).release()


def test_a_killed_holder_leaves_no_stale_lock(tmp_path):
    code = f"from mjx_curio import dirlock; l = dirlock.DirLock({str(tmp_path)!r}); print('held', flush=True); input()"
    proc = subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "held"
        with pytest.raises(ConfigError, match=f"pid {proc.pid} "):
            dirlock.check_free(tmp_path)
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    dirlock.check_free(tmp_path)
    assert (tmp_path / dirlock.LOCK_NAME).exists()  # the file stays; only the lock on it went


def test_check_free_creates_nothing(tmp_path):
    dirlock.check_free(tmp_path / "nope")
    dirlock.check_free(tmp_path)
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------------------------ the plan


def test_saved_values_read_an_older_manifest_as_the_behaviour_it_had():
    manifest = {"config": {"seeds": 3, "policies": ["eps"]}, "run_config": {"walls": "different",
                                                                          "learner": {"kl_tolerance": 0.25}}}
    saved = plan.saved_values(manifest)
    assert saved["seeds"] == 3 and saved["policies"] == ("eps",)  # from the config
    assert saved["walls"] == "different" and saved["kl_tolerance"] == 0.25  # from the run config
    assert saved["latent"] == config.LearnerConfig.latent  # recorded nowhere: the default ...
    for cls in (config.SweepConfig, config.RunConfig, config.LearnerConfig):
        for f in config.knobs(cls):  # ... or, where the knob says so, its behaviour before it existed
            if "legacy" in f.metadata and f.metadata["cli"] and f.name != "kl_tolerance":
                assert saved[config.key_name(f)] == f.metadata["legacy"], f.name


def test_resume_command_names_what_differs_from_the_defaults(tmp_path):
    values = sweep_lib.cli.parse(["seeds=2", "image=16", "policies=eps,ucb", "save_replay=false", f"out={tmp_path / 's'}"],
                                 sweep_lib.KEYS)
    command = plan.resume_command(plan.plan(values))
    assert command == (f"python -m mjx_curio.sweep policies=eps,ucb seeds=2 image=16 save_replay=false "
                       f"out={tmp_path / 's'} resume=true")
    # It parses back to the same settings.
    again = sweep_lib.cli.parse(command.split()[3:], sweep_lib.KEYS)
    assert {k: again[k] for k in values if k != "resume"} == {k: values[k] for k in values if k != "resume"}
    # A preset's sweep: resume checks the preset, so the command names it; a key the preset sets
    # but the command line set back to its default is named too, or the preset would win again.
    argv = ["preset=single_agent", "agents=2", "seeds=3", "steps=20000", f"out={tmp_path / 'p'}"]  # agents=2: the default
    values = sweep_lib.cli.parse(apply_preset(argv), sweep_lib.KEYS)
    command = plan.resume_command(plan.plan(values))
    assert command.split()[3] == "preset=single_agent" and {"agents=2", "seeds=3", "steps=20000"} <= set(command.split())
    again = sweep_lib.cli.parse(apply_preset(command.split()[3:]), sweep_lib.KEYS)
    assert {k: again[k] for k in values if k != "resume"} == {k: values[k] for k in values if k != "resume"}


def test_one_rule_per_knob_in_code_and_on_the_command_line():
    with pytest.raises(ConfigError, match=r"mixtures=0 is out of range; allowed: an integer >= 1"):
        config.LearnerConfig(mixtures=0)
    with pytest.raises(ConfigError, match=r"mixtures=0 is out of range; allowed: an integer >= 1"):
        sweep_lib.cli.parse(["mixtures=0"], sweep_lib.KEYS)
    with pytest.raises(ConfigError, match=r"agents=3 is out of range; allowed: an integer in \[1, 2\]"):
        config.RunConfig(n_agents=3)
    assert config.LearnerConfig(vae_channels=[8, 16], dec_channels=[8, 8]).vae_channels == (8, 16)


# ------------------------------------------------------------------------ metrics and progress


def test_resized_metrics_keep_every_window_run(tmp_path):
    store = metrics.MetricsStore(tmp_path / "metrics", n_runs=2, n_windows=10, n_agents=2, create=True)
    chunk = {name: np.ones((2, 4) + spec.shape(2), spec.dtype) for name, spec in metrics.SCHEMA.items()}
    store.write(0, chunk)
    store.flush()
    del store
    values = {"metrics_every": 20, "agents": 2}
    for n in (6, 15):
        store = sweep_lib._resize_metrics(tmp_path, 2, n, values, metrics, names=tuple(metrics.SCHEMA))
        for name, spec in metrics.SCHEMA.items():
            arr = np.load(tmp_path / "metrics" / f"{name}.npy")
            assert arr.shape == (2, n) + spec.shape(2)
            assert (arr[:, :4] == 1).all(), name
            rest = arr[:, 4:]
            assert (np.isnan(rest) if spec.dtype.startswith("float") else rest == 0).all(), name
        np.testing.assert_array_equal(np.load(tmp_path / "metrics" / "steps.npy"), np.arange(1, n + 1) * 20)
        del store


def test_a_sweep_made_before_a_metric_existed_resumes_without_it(tmp_path):
    """Resumed, a sweep records the metrics its manifest lists: one added to the schema since is
    neither required on disk nor created with zeros for the windows it never recorded."""
    older = tuple(name for name in metrics.SCHEMA if name != "rotation_reversals")
    store = metrics.MetricsStore(tmp_path / "metrics", n_runs=2, n_windows=10, n_agents=2, create=True, names=older)
    assert set(store.arrays) == set(older)
    del store
    store = sweep_lib._resize_metrics(tmp_path, 2, 12, {"metrics_every": 20, "agents": 2}, metrics, names=older)
    chunk = {name: np.ones((2, 1) + spec.shape(2), spec.dtype) for name, spec in metrics.SCHEMA.items()}
    store.write(11, chunk)  # the program's chunk has every metric; the store keeps its own
    store.flush()
    assert not (tmp_path / "metrics" / "rotation_reversals.npy").exists()
    assert (np.load(tmp_path / "metrics" / "curiosity.npy")[:, 11] == 1).all()
    # Which metrics a resumed sweep records: its manifest's list, or, where it lists none, all.
    assert sweep_lib.recorded_metrics({"metrics": {"schema": {n: {} for n in older}}}) == older
    assert sweep_lib.recorded_metrics({"metrics": {"every": 20}}) == tuple(metrics.SCHEMA)


def test_progress_rate_counts_from_the_end_of_the_first_chunk():
    p = progress.Progress(start=0, total=1000, n_runs=4, enabled=False)
    p.base = (10.0, 100)  # the first chunk (with the compile) ended at t = 10 s, step 100
    assert p.rate(300, 20.0) == pytest.approx(200 * 4 / 10.0)
    assert progress.hms(3725) == "1:02:05" and progress.hms(float("nan")) == "?"


def test_provenance_names_versions_cpu_and_commit():
    v = provenance.versions()
    assert v["jax"] and v["mujoco"] and v["numpy"] and v["mjx_curio"] == mjx_curio.__version__
    assert isinstance(provenance.cpu_name(), str)
    assert set(provenance.git()) == {"commit", "dirty"}


def test_provenance_counts_an_edited_scene_as_dirty(tmp_path):
    """The scenes sit beside the package, not in it: an edit to them (a mass, a friction) must
    mark the manifest's commit dirty as an edit to the code does."""
    repo = tmp_path / "repo"
    (repo / "pkg").mkdir(parents=True)
    (repo / "scenes").mkdir()
    (repo / "pkg" / "code.py").write_text("x = 1\n")
    (repo / "scenes" / "room.xml").write_text('<geom mass="1"/>\n')

    def git(*args):
        subprocess.run(["git", "-C", str(repo), "-c", "user.name=t", "-c", "user.email=t@t", *args],
                       check=True, capture_output=True)

    git("init", "-q")
    git("add", ".")
    git("commit", "-q", "-m", "scene")
    both = [repo / "pkg", repo / "scenes"]
    assert provenance.git(both)["dirty"] is False and len(provenance.git(both)["commit"]) == 40
    (repo / "scenes" / "room.xml").write_text('<geom mass="2"/>\n')
    assert provenance.git(both)["dirty"] is True
    assert provenance.git([repo / "pkg"])["dirty"] is False
    # A scene directory outside the checkout (an installed copy) is left out, not an error.
    elsewhere = tmp_path / "site-packages" / "scenes"
    elsewhere.mkdir(parents=True)
    assert provenance.git([repo / "pkg", elsewhere])["dirty"] is False
    # A package the checkout does not track (an installed copy in a site-packages that lies inside
    # another repository) is not that repository's commit.
    (repo / "site" / "pkg").mkdir(parents=True)
    assert provenance.git([repo / "site" / "pkg"]) == {"commit": None, "dirty": None}


# ------------------------------------------------------------------------- one minimal sweep


@pytest.mark.quick_only
def test_a_minimal_sweep_runs_every_stage_and_resumes_longer(minimal_sweep, minimal_sweep_resumed):
    from mjx_curio import checkpoint as ckpt_lib

    out = minimal_sweep  # MINIMAL_SWEEP (tests/conftest.py), run in a background process
    manifest = json.loads((out / "manifest.json").read_text())
    assert set(manifest["config"]) == {k.name for k in sweep_lib.KEYS}
    assert manifest["run_config"]["learner"]["vae_channels"] == [4, 8] and manifest["device"]["count"] >= 1
    assert manifest["command"].startswith("python -m mjx_curio.sweep preset=none policies=eps,ucb")
    m = {name: np.load(out / "metrics" / f"{name}.npy") for name in metrics.SCHEMA}
    assert m["curiosity"].shape == (2, 2, 1) and np.isfinite(m["curiosity"]).all()
    assert (m["action_counts"].sum(-1) == 20).all() and (m["updates"].sum(1) > 0).all()
    assert np.isfinite(m["vae_loss"][:, -1]).all()
    ck = ckpt_lib.Checkpoints(out / "checkpoints", read_only=True)
    assert ck.latest_complete() == 40
    ck.close()
    # Its copy, resumed with steps=60 in the background, went on from step 40.
    resumed = minimal_sweep_resumed
    assert "restored step 40" in (resumed.parent / "stderr.txt").read_text()
    curiosity = np.load(resumed / "metrics" / "curiosity.npy")
    assert curiosity.shape == (2, 3, 1) and np.isfinite(curiosity).all()
    np.testing.assert_array_equal(curiosity[:, :2], m["curiosity"])
    assert json.loads((resumed / "progress.json").read_text())["steps_done"] == 60


def test_a_sweep_made_before_the_fidelity_settings_is_refused_by_resume_naming_them(tmp_path):
    """Its manifest lacks the newer keys: they are read as the behaviour it had, so resuming it
    under today's defaults would change its physics, camera and learner mid-run."""
    values = sweep_lib.cli.parse([f"out={tmp_path}"], sweep_lib.KEYS)
    new_keys = ("camera", "friction", "z", "curiosity", "kl_tolerance")  # the learner knobs were no keys then
    old_config = {k: v for k, v in plan.config_of(values).items() if k not in new_keys}
    old_run = {"walls": "same", "learner": {"kl_tolerance": 0.5}}
    (tmp_path / "manifest.json").write_text(json.dumps({"config": old_config, "run_config": old_run}))
    with pytest.raises(ConfigError) as err:
        plan.plan({**values, "resume": True})
    text = str(err.value)
    for change in ("camera: saved 'square', given 'authors'", "friction: saved 'unit', given 'geoms'",
                   "z: saved 'mean', given 'sample'", "curiosity: saved 'sum', given 'mean'",
                   "kl_tolerance: saved 0.5, given 0.0"):
        assert change in text, text
    # Resumed with its own settings, it plans.
    legacy = ["camera=square", "friction=unit", "z=mean", "curiosity=sum", "kl_tolerance=0.5", f"out={tmp_path}",
              "resume=true"]
    assert plan.plan(sweep_lib.cli.parse(legacy, sweep_lib.KEYS)).resume
