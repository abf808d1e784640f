"""The window metrics a sweep records (`run.reduce_windows`) against NumPy on the per-step values."""

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

import jax.numpy as jnp
import numpy as np
import pytest

from mjx_curio import metrics as metrics_lib
from mjx_curio import run as run_lib
from mjx_curio.arena import ACTIONS, OBJECTS
from mjx_curio.config import LearnerConfig

W, UPDATE_EVERY, WINDOWS, AGENTS = 10, 5, 4, 2
CFG = run_lib.RunConfig(image=16, metrics_every=W, update_every=UPDATE_EVERY,
                        learner=LearnerConfig(image=16, vae_channels=(8, 8), dec_channels=(8, 8)))


def _steps(rng):
    """Per-step and per-update values of WINDOWS windows; the run halts 3 steps into window 2, and
    a halted step's curiosity and prediction are NaN (what a diverged step leaves)."""
    t = W * WINDOWS
    taken = np.arange(t) < 2 * W + 3
    step_m = {
        "taken": taken,
        "action": rng.integers(0, len(ACTIONS), (t, AGENTS)).astype(np.int32),
        "curiosity": rng.gamma(2.0, 0.2, (t, AGENTS)).astype(np.float32),
        "predicted": rng.gamma(2.0, 0.2, (t, AGENTS)).astype(np.float32),
        "curiosity_spread": rng.gamma(2.0, 0.1, (t, AGENTS)).astype(np.float32),
        "contact_object": rng.random((t, AGENTS, len(OBJECTS))) < 0.2,
        "contact_agent": rng.random((t, AGENTS)) < 0.1,
        "view_fraction": rng.random((t, AGENTS, len(metrics_lib.VIEW_TARGETS))).astype(np.float32),
        "agent_pose": rng.normal(size=(t, AGENTS, 3)).astype(np.float32),
        "object_pos": rng.normal(size=(t, len(OBJECTS), 3)).astype(np.float32),
    }
    step_m["curiosity"][~taken] = np.nan
    step_m["predicted"][~taken] = np.nan
    step_m["curiosity_spread"][~taken] = np.nan
    u = t // UPDATE_EVERY
    learn_m = {k: rng.random(u).astype(np.float32) for k in ("vae_loss", "recon", "kl", "nll", "self_loss")}
    learn_m["self_loss_agents"] = rng.random((u, AGENTS)).astype(np.float32)
    learn_m["curiosity_agents"] = rng.random((u, AGENTS)).astype(np.float32)
    learn_m["updated"] = (np.arange(u) >= 1).astype(np.int32)
    learn_m["non_finite"] = np.zeros(u, np.int32)
    return step_m, learn_m


@pytest.fixture(scope="module")
def windows():
    step_m, learn_m = _steps(np.random.default_rng(0))
    got = run_lib.reduce_windows(CFG, {k: jnp.asarray(v) for k, v in step_m.items()},
                                 {k: jnp.asarray(v) for k, v in learn_m.items()})
    return step_m, {k: np.asarray(v) for k, v in got.items()}


def test_every_metric_of_the_schema_is_made_with_its_shape_and_dtype(windows):
    _, got = windows
    assert set(got) == set(metrics_lib.SCHEMA)
    for name, spec in metrics_lib.SCHEMA.items():
        assert got[name].shape == (WINDOWS,) + spec.shape(AGENTS), name
        assert got[name].dtype == np.dtype(spec.dtype), name


def test_within_window_moments_and_curiosity_by_action_are_numpys(windows):
    step_m, got = windows
    c = step_m["curiosity"].astype(np.float64)
    q = step_m["predicted"].astype(np.float64)
    a = step_m["action"]
    for w in range(WINDOWS):
        steps = np.arange(w * W, (w + 1) * W)
        steps = steps[step_m["taken"][steps]]
        for i in range(AGENTS):
            if steps.size == 0:  # windows after the halt: no step to take a moment of
                for name in ("predicted_var", "curiosity_var", "predicted_curiosity_cov"):
                    assert np.isnan(got[name][w, i])
                assert np.isnan(got["curiosity_by_action"][w, i]).all()
                continue
            cw, qw = c[steps, i], q[steps, i]
            assert got["curiosity"][w, i] == pytest.approx(cw.mean(), rel=1e-6)
            assert got["curiosity_spread"][w, i] == pytest.approx(step_m["curiosity_spread"][steps, i].mean(), rel=1e-6)
            assert got["predicted_var"][w, i] == pytest.approx(np.var(qw), rel=1e-4)
            assert got["curiosity_var"][w, i] == pytest.approx(np.var(cw), rel=1e-4)
            assert got["predicted_curiosity_cov"][w, i] == pytest.approx(np.cov(qw, cw, bias=True)[0, 1], rel=1e-4, abs=1e-7)
            for k in range(len(ACTIONS)):
                chose = a[steps, i] == k
                assert got["action_counts"][w, i, k] == chose.sum()
                if chose.any():
                    assert got["curiosity_by_action"][w, i, k] == pytest.approx(cw[chose].mean(), rel=1e-6)
                else:
                    assert np.isnan(got["curiosity_by_action"][w, i, k])
    # the window of the halt holds its 3 steps taken, and the count of steps says so
    assert got["steps_taken"].tolist() == [W, W, 3, 0]


def test_the_learners_metrics_are_means_over_the_windows_updates(windows):
    """Each learner metric of a window is the mean over the updates done in it (the first update
    slot holds none: replay had no sequence yet); the training batch's curiosity per agent."""
    _, learn_m = _steps(np.random.default_rng(0))
    _, got = windows
    per = W // UPDATE_EVERY
    for w in range(WINDOWS):
        slots = np.arange(w * per, (w + 1) * per)
        done = slots[learn_m["updated"][slots] > 0]
        assert got["updates"][w] == len(done)
        for name, source in (("nll", "nll"), ("self_loss_agents", "self_loss_agents"),
                             ("batch_curiosity", "curiosity_agents")):
            want = learn_m[source][done].astype(np.float64).mean(axis=0)
            np.testing.assert_allclose(got[name][w], want, rtol=1e-6, err_msg=name)
