"""Shared pytest setup: GL for MuJoCo's renderer, one XLA compilation cache for the whole
session (in-process and subprocess alike), and the sweeps several test files read, made on the
second core while the tests that need none run first."""

import contextlib
import ctypes.util
import io
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time

import pytest

# MuJoCo chooses its OpenGL backend when `mujoco` is first imported (conftest runs before any test
# module); tests/test_render.py compares against MuJoCo's off-screen renderer, which on a headless
# machine needs OSMesa (apt-get install -y libosmesa6). Only where OSMesa is there: with
# MUJOCO_GL=osmesa and no libOSMesa, `import mujoco` itself fails (mujoco 4), and every test with
# it; without GL only the renderer comparison skips.
if "MUJOCO_GL" not in os.environ and ctypes.util.find_library("OSMesa"):
    os.environ["MUJOCO_GL"] = "osmesa"

# Compiling an MJX step takes ~30 s on a 2-core CPU, and the sweep tests start several
# processes that compile the same programs: a persistent cache shared by every process of the
# session (set before JAX initialises) makes each program compile once. Kept between sessions in
# the user's cache directory, it also spares the inner loop's next run (`pytest -m "not slow"`)
# every compile whose program has not changed. Reuse is safe: JAX keys an entry by the program,
# its compile options and the versions, and XLA's CPU loader refuses one compiled for CPU features
# this machine lacks (it compiles anew). Capped at 2 GiB, least recently used entries dropped first.
# JAX_COMPILATION_CACHE_DIR, if set, chooses another directory (a fresh one: a cold run, as CI's);
# where the home directory is not writable, a temporary one serves this session and is removed.
def _cache_dir() -> tuple[pathlib.Path, bool]:
    """(the directory, whether it is a temporary one made here)"""
    for path in (os.environ.get("JAX_COMPILATION_CACHE_DIR"), os.path.expanduser("~/.cache/mjx_curio/xla-tests")):
        if path:
            try:
                pathlib.Path(path).mkdir(parents=True, exist_ok=True)
                if os.access(path, os.W_OK):
                    return pathlib.Path(path), False
            except OSError:
                pass
    return pathlib.Path(tempfile.mkdtemp(prefix="mjx_curio_xla_")), True


CACHE, _CACHE_IS_TEMPORARY = _cache_dir()
os.environ["JAX_COMPILATION_CACHE_DIR"] = str(CACHE)
os.environ.setdefault("JAX_COMPILATION_CACHE_MAX_SIZE", str(2 << 30))

# One CPU device for every JAX program of the session, in this process and in the sweeps it starts
# (host_devices=auto honours a count set in XLA_FLAGS): the tests' reference results are one
# device's, and programs compiled for one device count are shared through the cache. The
# sharding tests ask for two devices explicitly (host_devices=2).
os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "") + " --xla_force_host_platform_device_count=1").strip()

# Every program of the session compiles for compile speed: LLVM's optimisation off and XLA CPU's
# older fusion emitters (its MLIR ones are the default). The tests compile far more than they run:
# these flags took the arena's MJX step from 19.3 s to 7.9 s of XLA compile on a 2-core Intel Xeon
# (30 s to 15 s on an AMD EPYC). Almost every test compares with an oracle within a tolerance, over
# a horizon too short for rounding to grow, or against a program compiled alike (a resumed sweep
# against the same sweep that never stopped), and passes under either codegen. What is about the
# programs users run compiles as theirs do, with XLA's defaults: the two sweeps of the test that a
# run alone and the same run inside a sweep agree bit for bit (made without these flags: under
# them the two were measured to differ in the last bit), and the programs given USERS_CODEGEN,
# the same options at XLA's default values, for one jit: the arena's long chaotic rollout, and the
# programs that run far longer than they compile (the default codegen runs them about 4 to 5
# times as fast: the arena's rollout in 10 s, not 55 s, on an AMD EPYC). LLVM's optimisation at
# level 1 rather than 0 was tried: the tiny sweep's program runs twice as fast (as fast as under
# the defaults), the arena's MJX step compiles in 21.5 s rather than 16 s, and the full suite took
# 631 s against 541 and 612 s at level 0 (AMD EPYC, 2026-12-02). A value set in XLA_FLAGS wins.
FAST_COMPILE_XLA_FLAGS = {"xla_backend_optimization_level": "0", "xla_cpu_use_fusion_emitters": "false"}
USERS_CODEGEN = {"xla_backend_optimization_level": 3, "xla_cpu_use_fusion_emitters": True}
# The flags added here (not those the user set), which the sweeps compiled as users' are leave out.
ADDED_XLA_FLAGS = [f"--{flag}={value}" for flag, value in FAST_COMPILE_XLA_FLAGS.items()
                   if f"--{flag}=" not in os.environ["XLA_FLAGS"]]
os.environ["XLA_FLAGS"] = " ".join([os.environ["XLA_FLAGS"], *ADDED_XLA_FLAGS])


def users_xla_flags() -> str:
    """XLA_FLAGS for a process that compiles as users' runs do."""
    return " ".join(f for f in os.environ["XLA_FLAGS"].split() if f not in ADDED_XLA_FLAGS)


# The session's sweeps test the machinery (plan, program, chunks, metrics, checkpoints, resume,
# sharding, analysis), not learning at the paper's sizes (tests/test_nets.py and
# tests/test_world_model.py test that): with small networks and replay samples the many sweeps the
# tests run cost a fraction of the paper-size learner's time (100 steps of the tiny sweep's 8 runs:
# 17 s with the paper's sizes, under 3 s with these, on a 2-core Intel Xeon).
SMALL_LEARNER = ("latent=8", "vae_channels=8,16,32,32", "dec_channels=32,16,8,8", "rnn_hidden=32", "mixtures=3",
                 "self_hidden=32", "batch=4")

# The tiny sweep: image 16, 2 seeds x (eps, boltzmann at T=0.5 and 1.5, ucb) = 8 runs, 200 steps, checkpoints at 100 and 200.
TINY_SWEEP = ("seeds=2", "temperature=0.5,1.5", "steps=200", "image=16", *SMALL_LEARNER, "buffer=500", "chunk=100",
              "checkpoint_every=100", "keep_steps=100", "keep_every=0", "progress=false")


def sweep_in_process(*args: str, env: dict | None = None, check: bool = True) -> tuple[int, str]:
    """The same sweep run inside the test process: (exit status, stderr). Sweeps with one
    program share its trace and executable here (tracing alone costs ~20 s a process)."""
    from mjx_curio import sweep

    saved = {k: os.environ.get(k) for k in (env or {})}
    os.environ.update(env or {})
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err):
            try:
                rc = sweep.main([*args, f"compile_cache={CACHE}"])
            except SystemExit as exit_:
                rc = exit_.code
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    if check and rc != 0:
        raise AssertionError(f"sweep {' '.join(args)} failed ({rc}):\n{err.getvalue()[-4000:]}")
    return rc, err.getvalue()


# The quick tier, `pytest -m "not slow"`: every test that needs one of the session's sweeps (each
# compiles and runs a whole sweep program) is slow; other slow tests carry the mark themselves.
SWEEP_FIXTURES = {"tiny_sweep", "tiny_single_sweep", "tiny_sweeps_dir", "sharded_sweep", "crashed_sweep",
                  "interrupted_sweep", "users_tiny_sweep", "users_alone_sweep"}


@pytest.hookimpl(tryfirst=True)  # before -m deselects by marker
def pytest_collection_modifyitems(config, items):
    for item in items:
        if SWEEP_FIXTURES & set(getattr(item, "fixturenames", ())):
            item.add_marker(pytest.mark.slow)
    # The test files that read none of the session's sweeps run first, the others after them (each
    # group in pytest's order; whole files, so a module's fixtures are set up once): the sweeps are
    # made on the second core meanwhile, so the files that read them find them made rather than
    # wait for them.
    reads = {item.path for item in items if _sweeps_read(item) & SESSION_SWEEPS}
    items[:] = [i for i in items if i.path not in reads] + [i for i in items if i.path in reads]
    # The tests of the sweeps compiled as users' runs are (~90 s of CPU each) come last of all, so
    # that the background makes those sweeps last, while the tests before them run.
    users = [i for i in items if _sweeps_read(i) & USERS_CODEGEN_SWEEPS]
    items[:] = [i for i in items if i not in users] + users


# ------------------------------------------------------------------------------------------------
# Sweeps made in background processes, one after another in the order the tests read them, from as
# soon as collection shows which are needed: each compiles and runs on the second core while the
# tests before it run on the first (and the files that read none run first of all). One at a time,
# because two beside the test process oversubscribe a 2-core machine (XLA's thread pools). The
# in-process sweeps of tests/test_sweep.py that repeat the tiny sweep load its compiled program from
# the persistent cache.

# The smallest sweep there is: one agent, 8 px, tiny networks, 40 steps; it runs every stage (plan,
# lock, program, chunks, metrics, checkpoints, manifest). Compiling it (mostly MJX's physics, ~90 s of
# CPU on a 2-core Intel Xeon) was the quick tier's longest wait while it ran in the test process.
MINIMAL_SWEEP = ("agents=1", "policies=eps,ucb", "seeds=1", "image=8", "latent=4", "vae_channels=4,8",
                 "dec_channels=4,4", "rnn_hidden=8", "mixtures=2", "self_hidden=8", "batch=2", "seq_len=4", "buffer=40",
                 "steps=40", "chunk=20", "checkpoint_every=20", "keep_steps=20", "keep_every=0", "progress=false")

# The analysis, notebook and video tests read a tiny single-agent sweep beside the tiny sweep, in one
# directory, as the notebook reads them.
TINY_SINGLE_SWEEP = ("agents=1", "policies=eps,ucb", "seeds=1", "steps=200", "image=16", *SMALL_LEARNER, "buffer=500",
                     "chunk=100", "checkpoint_every=100", "keep_steps=100", "keep_every=0", "progress=false")

# One run of the tiny sweep (UCB, seed 1) as a sweep of its own.
ALONE_SWEEP = (*(a for a in TINY_SWEEP if not a.startswith(("seeds=", "temperature="))), "policies=ucb", "seeds=1",
               "first_seed=1")

# The minimal sweep resumed to 60 steps, in a copy of its directory (both are read).
MINIMAL_SWEEP_RESUMED = (*(a for a in MINIMAL_SWEEP if a != "steps=40"), "steps=60", "resume=true")

# The tiny sweep planned for 300 steps, checkpointing only at its end, its progress on stderr: sent a
# signal once its first chunk is done, so that the signal arrives during the second.
INTERRUPTED_SWEEP = (*(a for a in TINY_SWEEP if not a.startswith(("steps=", "checkpoint_every=", "keep_steps=", "progress="))),
                     "steps=300", "checkpoint_every=300", "keep_steps=300", "progress=true")

BACKGROUND_SWEEPS = {  # made in the order the session's tests first read them
    "tiny_sweep": TINY_SWEEP,
    "tiny_single_sweep": TINY_SINGLE_SWEEP,
    "minimal_sweep": MINIMAL_SWEEP,
    "minimal_sweep_resumed": MINIMAL_SWEEP_RESUMED,
    "crashed_sweep": TINY_SWEEP,  # killed inside its step-200 checkpoint write (STOPPED_BY)
    "sigint_sweep": INTERRUPTED_SWEEP,
    "sigterm_sweep": (*INTERRUPTED_SWEEP, "async_checkpoints=true"),  # its stop's checkpoint written in the background
    "sharded_sweep": (*TINY_SWEEP, "host_devices=2"),  # the tiny sweep on two forced host devices
    # The tiny sweep and one of its runs alone, compiled as users' runs are (USERS_CODEGEN_SWEEPS).
    "users_tiny_sweep": TINY_SWEEP,
    "users_alone_sweep": ALONE_SWEEP,
}
USERS_CODEGEN_SWEEPS = {"users_tiny_sweep", "users_alone_sweep"}
# What a test reads of them: a sweep's fixture (or its name, as interrupted_sweep's parameter) or a
# fixture that reads one.
SESSION_SWEEPS = SWEEP_FIXTURES | set(BACKGROUND_SWEEPS)
RESUMED_FROM = {"minimal_sweep_resumed": "minimal_sweep"}  # starts in a copy of the other, finished
# The sweeps stopped before their end, for the tests of stopping and resuming: their subprocesses
# (~35 s each, mostly tracing on one core) run here, on the core the test process leaves idle.
# sweep: (extra environment, the signal it is sent, the stderr text after which it is sent)
STOPPED_BY = {
    "crashed_sweep": ({"MJX_CURIO_CRASH_AT": "after-state:200"}, None, None),  # checkpoint.CRASH_ENV
    "sigint_sweep": ({}, signal.SIGINT, "step 100/300"),
    "sigterm_sweep": ({}, signal.SIGTERM, "step 100/300"),
}
_background: dict[str, tuple[pathlib.Path, subprocess.Popen]] = {}
_background_lock = threading.Lock()
_stopping = threading.Event()


def _start_background(name: str) -> None:
    """Start sweep `name` unless it has started (the caller holds _background_lock, and the sweep
    it resumes, if any, has finished)."""
    if name in _background:
        return
    out = pathlib.Path(tempfile.mkdtemp(prefix=f"mjx_curio_{name}_")) / name
    if name in RESUMED_FROM:
        shutil.copytree(_background[RESUMED_FROM[name]][0], out)
    env, signum, after = STOPPED_BY.get(name, ({}, None, None))
    if name in USERS_CODEGEN_SWEEPS:
        env = dict(env, XLA_FLAGS=users_xla_flags())
    stderr = out.parent / "stderr.txt"
    with open(stderr, "w") as err:  # a file, not a pipe: nothing blocks if nobody reads it yet
        proc = subprocess.Popen([sys.executable, "-m", "mjx_curio.sweep", *BACKGROUND_SWEEPS[name], f"out={out}",
                                 f"compile_cache={CACHE}"], stdout=subprocess.DEVNULL, stderr=err,
                                env=dict(os.environ, **env))
    _background[name] = out, proc
    if signum is not None:
        threading.Thread(target=_signal_after, args=(proc, stderr, after, signum), daemon=True).start()


def _signal_after(proc: subprocess.Popen, stderr: pathlib.Path, text: str, signum: int) -> None:
    """Send `signum` to `proc` as soon as `text` shows in its stderr."""
    while proc.poll() is None:
        if text in stderr.read_text(errors="replace"):
            proc.send_signal(signum)
            return
        time.sleep(0.05)


def _run_in_turn(names: list[str]) -> None:
    for name in names:
        if name in RESUMED_FROM:
            try:
                _finished_background(RESUMED_FROM[name])
            except AssertionError:  # the test reading it says why
                continue
        with _background_lock:
            if _stopping.is_set():
                return
            _start_background(name)
            proc = _background[name][1]
        proc.wait()


def _ended_background(name: str) -> tuple[pathlib.Path, int, str]:
    """(directory, exit status, stderr) of background sweep `name`, once it has ended."""
    if name in RESUMED_FROM:
        _finished_background(RESUMED_FROM[name])
    with _background_lock:  # a sweep read before its turn (e.g. a test run alone) starts now
        _start_background(name)
        out, proc = _background[name]
    proc.wait(timeout=900)
    return out, proc.returncode, (out.parent / "stderr.txt").read_text()


def _finished_background(name: str) -> pathlib.Path:
    out, returncode, err = _ended_background(name)
    if returncode != 0:
        raise AssertionError(f"{name} failed ({returncode}):\n{err[-4000:]}")
    return out


def pytest_collection_finish(session):
    # A quick_only test stands in, in the quick tier, for what the slow tests check in depth: when
    # they run too (the full suite), it is skipped rather than paid for twice.
    if any(item.get_closest_marker("slow") for item in session.items):
        for item in session.items:
            if item.get_closest_marker("quick_only"):
                item.add_marker(pytest.mark.skip(reason="the full suite's slow tests cover this in depth"))
    if session.config.option.collectonly:
        return
    needed = []
    for item in session.items:
        if not _skipped(item):
            needed += [name for name in BACKGROUND_SWEEPS if name in _sweeps_read(item) and name not in needed]
    threading.Thread(target=_run_in_turn, args=(needed,), daemon=True).start()


def _sweeps_read(item) -> set:
    """The session's sweeps `item` reads: its fixtures, and the sweep a parametrized fixture
    (interrupted_sweep) is given by name."""
    callspec = getattr(item, "callspec", None)
    params = {v for v in callspec.params.values() if isinstance(v, str)} if callspec else set()
    return set(getattr(item, "fixturenames", ())) | params


def _skipped(item) -> bool:
    """Whether `item` is marked to skip, unconditionally or by a true skipif condition (given as a bool)."""
    return item.get_closest_marker("skip") is not None or any(
        m.args and m.args[0] is True for m in item.iter_markers("skipif"))


@pytest.fixture(scope="session", autouse=True)
def repository_left_as_found():
    """No test writes into the repository: what git sees changed or added in the working tree
    (with each such file's modification time) is the same after the session as before it, so
    that a test cannot overwrite a committed result or leave a stray file (a script's output
    path not redirected). Outside a git checkout there is nothing to compare."""
    before = _working_tree_changes()
    yield
    after = _working_tree_changes()
    if before is not None and after != before:
        changed = sorted(k for k in after.keys() | before.keys() if after.get(k) != before.get(k))
        pytest.fail("the tests wrote into the repository: " + ", ".join(changed), pytrace=False)


def _working_tree_changes() -> dict | None:
    """{path: modification time in ns (None where deleted)} of the files `git status` lists as
    changed or untracked (ignored ones not), or None where this is no git checkout."""
    root = pathlib.Path(__file__).resolve().parents[1]
    if not (root / ".git").exists() or shutil.which("git") is None:
        return None
    out = subprocess.run(["git", "status", "--porcelain", "--untracked-files=all", "-z"], cwd=root,
                         capture_output=True, text=True)
    if out.returncode != 0:
        return None
    paths = [entry[3:] for entry in out.stdout.split("\0") if len(entry) > 3]
    return {p: (root / p).stat().st_mtime_ns if (root / p).exists() else None for p in paths}


def pytest_sessionfinish(session, exitstatus):
    with _background_lock:
        _stopping.set()
    for out, proc in _background.values():
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        shutil.rmtree(out.parent, ignore_errors=True)
    if _CACHE_IS_TEMPORARY:
        shutil.rmtree(CACHE, ignore_errors=True)


@pytest.fixture(scope="session")
def tiny_sweep() -> pathlib.Path:
    """The tiny sweep (TINY_SWEEP: 8 runs of two agents), finished."""
    return _finished_background("tiny_sweep")


@pytest.fixture(scope="session")
def tiny_single_sweep() -> pathlib.Path:
    """The tiny single-agent sweep (TINY_SINGLE_SWEEP: eps and ucb, one seed each), finished."""
    return _finished_background("tiny_single_sweep")


@pytest.fixture(scope="session")
def tiny_sweeps_dir(tmp_path_factory, tiny_sweep, tiny_single_sweep) -> pathlib.Path:
    """A directory holding the two tiny sweeps (symlinks `multi` and `single`), as runs/paper holds the presets."""
    parent = tmp_path_factory.mktemp("sweeps_parent")
    (parent / "multi").symlink_to(tiny_sweep, target_is_directory=True)
    (parent / "single").symlink_to(tiny_single_sweep, target_is_directory=True)
    return parent


@pytest.fixture(scope="session")
def sharded_sweep() -> pathlib.Path:
    """The tiny sweep (TINY_SWEEP) run on two forced host devices, finished."""
    return _finished_background("sharded_sweep")


@pytest.fixture(scope="session")
def minimal_sweep() -> pathlib.Path:
    """MINIMAL_SWEEP, finished."""
    return _finished_background("minimal_sweep")


@pytest.fixture(scope="session")
def minimal_sweep_resumed() -> pathlib.Path:
    """MINIMAL_SWEEP_RESUMED, finished: the minimal sweep's copy, resumed to 60 steps. Its
    stderr is `stderr.txt` beside it."""
    return _finished_background("minimal_sweep_resumed")


@pytest.fixture(scope="session")
def users_tiny_sweep() -> pathlib.Path:
    """TINY_SWEEP compiled as users' runs are (XLA's default codegen), finished."""
    return _finished_background("users_tiny_sweep")


@pytest.fixture(scope="session")
def users_alone_sweep() -> pathlib.Path:
    """ALONE_SWEEP (one run of the tiny sweep on its own) compiled as users' runs are, finished."""
    return _finished_background("users_alone_sweep")


@pytest.fixture(scope="session")
def crashed_sweep() -> tuple[pathlib.Path, int, str]:
    """The tiny sweep killed inside its step-200 checkpoint write (STOPPED_BY): (directory, exit
    status, stderr)."""
    return _ended_background("crashed_sweep")


@pytest.fixture(scope="session")
def interrupted_sweep(request) -> tuple[int, pathlib.Path, int, str]:
    """INTERRUPTED_SWEEP sent the signal of `request.param` ("sigint_sweep" or "sigterm_sweep")
    during its second chunk: (the signal, directory, exit status, stderr)."""
    return (STOPPED_BY[request.param][1], *_ended_background(request.param))
