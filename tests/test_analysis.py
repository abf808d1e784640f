"""Reading sweeps and drawing the paper's figures (the package mjx_curio/analysis/), on the session's tiny
sweeps (tests/conftest.py): the 2-agent `tiny_sweep` (eps, Boltzmann at T=0.5 and 1.5, UCB; 2
seeds; 200 steps) and the 1-agent `tiny_single_sweep` (eps, UCB; one seed each).

The numbers behind the figures are checked against direct NumPy computations; every figure
function is drawn and must leave no empty panel; bad directories raise SweepError naming what is
missing and where.
"""

import json
import shutil

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from mjx_curio import analysis as an  # noqa: E402


@pytest.fixture(scope="module")
def sweep(tiny_sweep):
    return an.load(tiny_sweep)


@pytest.fixture(scope="module")
def single(tiny_single_sweep):
    return an.load(tiny_single_sweep)


# ---------------------------------------------------------------------------------- loading


def test_load(sweep, tiny_sweep):
    manifest = json.loads((tiny_sweep / "manifest.json").read_text())
    assert [r.name for r in sweep.runs] == [r["name"] for r in manifest["runs"]]
    assert sweep.n_runs == 8 and sweep.n_agents == 2 and sweep.agent_names == ["green", "purple"]
    np.testing.assert_array_equal(sweep.steps, np.arange(1, 11) * 20)
    for name, spec in manifest["metrics"]["schema"].items():
        arr = sweep.metrics[name]
        assert arr.shape[:2] == (8, 10), name
        assert arr.dtype == np.dtype(spec["dtype"]), name
        np.testing.assert_array_equal(arr, np.load(tiny_sweep / "metrics" / f"{name}.npy")[:, :10])
    assert sweep.table["policy"].tolist() == [r["policy"] for r in manifest["runs"]]
    assert "8 runs" in sweep.describe() and "100, 200" in sweep.describe()


def test_select_and_groups(sweep):
    b = sweep.select(policy="boltzmann")
    assert [sweep.runs[i].policy for i in b] == ["boltzmann"] * 4
    t05 = sweep.select(policy="boltzmann", temperature=0.5)
    assert len(t05) == 2 and all(sweep.runs[i].temperature == 0.5 for i in t05)
    assert sweep.select(seed=1, policy=["eps", "ucb"]).tolist() == [1, 7]
    with pytest.raises(an.SweepError, match="no run"):
        sweep.select(policy="ucb", ucb_c=3.0)
    groups = sweep.groups()
    assert [g.label for g in groups] == ["ε-greedy (ε=0.2)", "Boltzmann (T=0.5)", "Boltzmann (T=1.5)", "UCB (c=1)"]
    assert all(g.n == 2 for g in groups)
    assert sweep.group("ucb").label == "UCB (c=1)"
    assert sweep.group(3).indices.tolist() == [3]
    assert sweep.group(sweep.runs[5].name).indices.tolist() == [5]
    with pytest.raises(an.SweepError, match="neither a policy"):
        sweep.group("nonsense")


def test_configs_from_manifest(sweep):
    import dataclasses

    from mjx_curio.plan import grid

    cfg = sweep.run_config()
    assert cfg.image == 16 and cfg.n_agents == 2 and cfg.learner.image == 16 and cfg.learner.n_agents == 2
    assert cfg.learner.vae_channels == tuple(sweep.manifest["run_config"]["learner"]["vae_channels"])
    assert json.loads(json.dumps(dataclasses.asdict(cfg))) == sweep.manifest["run_config"]
    assert sweep.run_specs() == grid(dict(sweep.manifest["config"], policies=tuple(sweep.manifest["config"]["policies"]),
                                          eps=tuple(sweep.manifest["config"]["eps"]),
                                          temperature=tuple(sweep.manifest["config"]["temperature"]),
                                          ucb_c=tuple(sweep.manifest["config"]["ucb_c"])))


def test_configs_from_a_manifest_older_than_the_fidelity_knobs():
    """A sweep made before the knobs `curiosity`, `z` (LearnerConfig), `camera` and `friction`
    (RunConfig) existed has none of them in its manifest: it loads as what it ran, each knob's
    `legacy` value (sum, mean, square, unit), not today's defaults; its recorded kl_tolerance
    (0.5, the default then) is kept; a manifest that records them loads them."""
    import dataclasses

    from mjx_curio.config import LearnerConfig, RunConfig

    cfg = RunConfig(image=16, learner=LearnerConfig(image=16, latent=8, vae_channels=(8, 8, 8, 8)))
    recorded = json.loads(json.dumps(dataclasses.asdict(cfg)))
    assert an.run_config({"run_config": recorded}) == cfg
    old = json.loads(json.dumps(recorded))
    for k in ("camera", "friction"):
        del old[k]
    for k in ("curiosity", "z"):
        del old["learner"][k]
    old["learner"]["kl_tolerance"] = 0.5
    got = an.run_config({"run_config": old})
    assert (got.camera, got.friction, got.learner.curiosity, got.learner.z) == ("square", "unit", "sum", "mean")
    assert got.learner.kl_tolerance == 0.5 and got.learner.latent == 8 and got.learner.vae_channels == (8, 8, 8, 8)
    assert an.learner_config({"run_config": old}) == got.learner
    assert (cfg.camera, cfg.friction, cfg.learner.curiosity, cfg.learner.z) == ("authors", "geoms", "mean", "sample")


def test_find_sweeps(tiny_sweeps_dir, tiny_sweep):
    assert an.find_sweeps(tiny_sweep) == [tiny_sweep]
    sweeps = an.load_sweeps(tiny_sweeps_dir)
    assert [s.name for s in sweeps] == ["multi", "single"]
    single, multi = an.pick_single_multi(sweeps)
    assert single.n_agents == 1 and multi.n_agents == 2


# ---------------------------------------------------------------------------------- statistics


def test_windows_after_a_diverged_simulation_are_dropped():
    # Three runs, six windows of 20 steps: run 1's physics goes NaN in window 3 while it still steps
    # (a sweep from before such runs halted); run 2 halted at window 2 (its pose is NaN by design).
    steps = np.arange(1, 7) * 20
    taken = np.full((3, 6), 20, np.int32)
    taken[2, 2:] = 0
    pose = np.ones((3, 6, 2, 3), np.float32)
    pose[1, 3:, 0, 1] = np.nan
    pose[2, 2:] = np.nan
    metrics = {"steps_taken": taken, "agent_pose": pose, "object_pos": np.ones((3, 6, 4, 3), np.float32),
               "curiosity": np.full((3, 6, 2), 0.5, np.float32), "action_counts": np.ones((3, 6, 2, 7), np.int32)}
    before = {k: v.copy() for k, v in metrics.items()}
    assert an.drop_diverged(metrics, steps) == {"1": 80}
    for k, v in metrics.items():
        np.testing.assert_array_equal(v[[0, 2]], before[k][[0, 2]], err_msg=k)  # the others untouched
        np.testing.assert_array_equal(v[1, :3], before[k][1, :3], err_msg=k)  # before it, too
    assert np.isnan(metrics["curiosity"][1, 3:]).all() and np.isnan(metrics["object_pos"][1, 3:]).all()
    assert (metrics["steps_taken"][1, 3:] == 0).all() and (metrics["action_counts"][1, 3:] == 0).all()


def test_moving_average_matches_numpy():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(3, 120))
    w = 50
    ma = an.moving_average(x, w, axis=1)
    for r in range(3):
        valid = np.convolve(x[r], np.ones(w) / w, mode="valid")  # full windows
        np.testing.assert_allclose(ma[r, w - 1 :], valid, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(ma[r, : w - 1], np.cumsum(x[r, : w - 1]) / np.arange(1, w), rtol=1e-12)
    y = x.copy()
    y[0, 10:20] = np.nan  # NaNs are skipped
    ma = an.moving_average(y, 5, axis=1)
    assert np.isnan(ma[0, 14:20]).all() and np.isfinite(ma[0, 20])
    np.testing.assert_allclose(ma[0, 21], y[0, 20:22].mean())


def test_mean_ci():
    x = np.array([[1.0, 2.0], [2.0, 2.0], [4.0, np.nan], [5.0, 2.0], [3.0, 2.0]])
    mean, lo, hi, n = an.mean_ci(x)
    half = 2.776 * np.std(x[:, 0], ddof=1) / np.sqrt(5)
    np.testing.assert_allclose([mean[0], lo[0], hi[0]], [3.0, 3.0 - half, 3.0 + half], rtol=1e-4)
    assert n.tolist() == [5, 4] and lo[1] == hi[1] == 2.0
    _, lo, hi, _ = an.mean_ci(np.ones((1, 3)))
    assert np.isnan(lo).all() and np.isnan(hi).all()
    np.testing.assert_allclose(an.t_quantile_975([1, 9, 30, 1000]), [12.706, 2.262, 2.042, 1.962], atol=2e-3)


# ---------------------------------------------------------------------------------- figure data


@pytest.mark.parametrize("kind", ["object", "agent"])
def test_cumulative_interactions(sweep, kind):
    d = an.cumulative_interactions(sweep, kind)
    top = d.pop("_max")
    raw = (sweep.metrics["contact_object"].sum(axis=(2, 3)) if kind == "object"
           else sweep.metrics["contact_agent"].max(axis=2))
    means = [np.cumsum(raw[g.indices], axis=1).mean(axis=0)[-1] for g in sweep.groups()]
    assert top == pytest.approx(max(means))
    for label, v in d.items():
        assert np.all(np.diff(v["mean"]) >= 0), label
        assert np.all(np.diff(v["runs"], axis=1) >= 0), label
    finals = [v["mean"][-1] for v in d.values()]
    if top > 0:
        assert max(finals) == pytest.approx(1.0) and max(np.nanmax(v["mean"]) for v in d.values()) == pytest.approx(1.0)
    else:
        assert max(finals) == 0.0


def test_action_totals_sum_to_steps(sweep):
    for g in sweep.groups():
        tot = an.action_totals(sweep, g)
        assert tot.shape == (g.n, 2, len(sweep.actions))
        taken = sweep.metrics["steps_taken"][g.indices].sum(axis=1)
        np.testing.assert_array_equal(tot.sum(axis=2), np.repeat(taken[:, None], 2, axis=1))
        np.testing.assert_array_equal(taken, 200)


def test_interaction_frequency(sweep):
    g = sweep.group("ucb")
    steps, f = an.interaction_frequency(sweep, g, every=100)
    assert steps.tolist() == [100, 200] and f.shape == (2, 2, 4)
    c = sweep.metrics["contact_object"][g.indices]
    np.testing.assert_allclose(f[:, 0], c[:, :5].sum(axis=(1, 2)) / (100 * 2))
    assert np.all((f >= 0) & (f <= 1))
    _, f0 = an.interaction_frequency(sweep, g, every=100, agent=0)
    np.testing.assert_allclose(f0[:, 1], c[:, 5:, 0].sum(axis=1) / 100)


def test_observation_classes(sweep, single):
    d = an.observation_classes(sweep)
    assert d["cls"].shape == (8, 10, 2) and d["count"].sum() == 8 * 10 * 2
    touched = (sweep.metrics["contact_object"].sum(axis=3) > 0) | (sweep.metrics["contact_agent"] > 0)
    np.testing.assert_array_equal(d["cls"] == 0, touched)
    with pytest.raises(an.SweepError, match="two"):
        an.observation_classes(single)


def test_headline_table(sweep, single):
    t = an.headline_table(sweep)
    assert [r[0] for r in t.rows] == [g.label for g in sweep.groups()]
    assert len(t.columns) == len(t.rows[0])
    md = t.to_markdown()
    assert "UCB (c=1)" in md and "±" in md
    assert t.to_csv().splitlines()[0].startswith("group,policy")
    obj = sweep.metrics["contact_object"][sweep.group("ucb").indices].sum(axis=(1, 2, 3))
    row = t.values[[r["group"] for r in t.values].index("UCB (c=1)")]
    assert row["object_contacts_mean"] == pytest.approx(obj.mean())
    assert "n/a" in an.headline_table(single).rows[0]  # no agent-agent contacts with one agent


def test_reconstructions(sweep):
    rec = an.reconstructions(sweep, run=2, n_frames=6)
    assert rec.steps == [100, 200]
    assert rec.frames.shape == (6, 16, 16, 3) and rec.frames.dtype == np.uint8
    assert [s[1] for s in rec.sources[:4]] == [2, 2, 2, 2]  # the run's own views first
    raw = sweep.restore_raw(200)
    s, i, a = rec.sources[3]
    np.testing.assert_array_equal(rec.frames[3], sweep.restore_raw(s)["frames"][i, a])
    for step in rec.steps:
        assert rec.decoded[step].shape == (6, 16, 16, 3)
        assert 0 <= rec.decoded[step].min() and rec.decoded[step].max() <= 1
    assert not np.allclose(rec.decoded[100], rec.decoded[200])  # the VAE learned in between
    p = sweep.params(200, 2)
    np.testing.assert_array_equal(p["vae"]["fc"]["kernel"], raw["learner"]["vae"]["fc"]["kernel"][2])


def test_edge_error():
    """0 for a perfect reconstruction, exactly 1 for a flat one (no edge kept), between for a blur,
    above 1 for noise where the real image has no edge; the hand-computed value of a tiny case."""
    rng = np.random.default_rng(0)
    real = rng.uniform(size=(4, 12, 12, 3))
    assert an.edge_error(real, real) == 0.0
    assert an.edge_error(np.full_like(real, 0.5), real) == pytest.approx(1.0)
    blurred = (real + np.roll(real, 1, axis=1) + np.roll(real, 1, axis=2)) / 3.0
    assert 0.0 < an.edge_error(blurred, real) < 1.0
    step = np.zeros((1, 2, 4, 1))  # 2 rows of 4 pixels, one channel
    step[..., 2:, :] = 1.0  # rows [0, 0, 1, 1]: an edge of 1 in each row, 2 in all
    noisy = step.copy()
    noisy[0, 0, 0, 0] = 0.5  # a new difference of 0.5 along its row and one of 0.5 down its column
    assert an.edge_error(noisy, step) == pytest.approx((0.5 + 0.5) / 2.0)
    assert an.edge_error(1.0 - step, step) == pytest.approx(2.0)  # every edge reversed
    assert np.isnan(an.edge_error(real, np.zeros_like(real)))  # nothing to compare against


def test_cells_visited():
    """Distinct 0.25 m squares at the windows' ends, per run and agent; NaN windows skipped."""
    pose = np.zeros((2, 6, 2, 3))
    pose[0, :, 0, 0] = [0.0, 0.1, 0.3, 0.3, -0.1, 0.6]  # squares 0, 0, 1, 1, -1, 2: four
    pose[0, :, 0, 1] = [0.0, 0.0, 0.0, 0.26, 0.0, 0.0]  # the fourth window moves up a square: five
    pose[1, :, 1, :2] = np.nan  # a halted run's blanked windows
    pose[1, :2, 1, :2] = [[1.0, 1.0], [1.0, 1.2]]
    np.testing.assert_array_equal(an.cells_visited(pose), [[5, 1], [1, 1]])
    np.testing.assert_array_equal(an.cells_visited(pose, cell=1.0), [[2, 1], [1, 1]])


def test_heldout_slots():
    np.testing.assert_array_equal(an.heldout_slots(200, 5), [0, 50, 100, 149, 199])
    np.testing.assert_array_equal(an.heldout_slots(3, 8), [0, 1, 2])
    assert an.heldout_slots(0, 8).size == 0


def test_reconstruction_quality(sweep):
    """Each run's VAE at each checkpoint on the other runs' replay frames, recomputed here from the
    replay and the world model's own encode and decode, one run and step at a time."""
    from mjx_curio import world_model as wm

    q = an.reconstruction_quality(sweep, frames_per_run=4)
    assert q.steps == [100, 200] and q.replay_step == 200 and q.frames_per_run == 4
    assert q.error.shape == q.edge_error.shape == (sweep.n_runs, 2)
    assert np.isfinite(q.error).all() and np.isfinite(q.edge_error).all()
    replay = sweep.restore_replay(200, keys=("frames", "size"))
    cfg = sweep.learner_config()
    run, k = 3, 0
    slots = an.heldout_slots(int(np.asarray(replay["size"]).reshape(-1)[0]), 4)
    others = np.concatenate([np.asarray(replay["frames"][j][slots]).reshape((-1, 16, 16, 3))
                             for j in range(sweep.n_runs) if j != run])
    assert len(others) == (sweep.n_runs - 1) * 4 * sweep.n_agents
    vae = sweep.params(q.steps[k], run)["vae"]
    decoded = np.asarray(wm.decode(cfg, vae, wm.encode(cfg, vae, others)[0]), np.float64)
    real = others / 255.0
    np.testing.assert_allclose(q.error[run, k], np.square(decoded - real).sum(axis=(1, 2, 3)).mean(), rtol=1e-5)
    np.testing.assert_allclose(q.edge_error[run, k], an.edge_error(decoded, real), rtol=1e-5)
    # Per source run: the same frames' errors, in the runs' order; a run's own frames are not used.
    per_frame = np.square(decoded - real).sum(axis=(1, 2, 3)).reshape(sweep.n_runs - 1, -1).mean(axis=1)
    np.testing.assert_allclose(np.delete(q.error_by_source[run, :, k], run), per_frame, rtol=1e-5)
    assert np.isnan(np.diagonal(q.error_by_source[..., k])).all()
    np.testing.assert_allclose(np.nanmean(q.error_by_source, axis=1), q.error, rtol=1e-6)
    assert an.reconstruction_quality(sweep, steps=[200], frames_per_run=4).error.shape == (sweep.n_runs, 1)
    with pytest.raises(ValueError, match="frames_per_run=0"):
        an.reconstruction_quality(sweep, frames_per_run=0)


def test_action_values(sweep):
    """Every state of the newest replay, each agent's self-model evaluated by a NumPy MLP, and the
    actions read back against the UCB counts the checkpoint keeps (every policy counts them)."""
    run = sweep.select(policy="boltzmann", temperature=0.5)[1]
    v = an.action_values(sweep, run)
    assert v.step == 200 and v.actions == tuple(sweep.actions)
    assert v.q.shape == (200, 2, len(sweep.actions)) and v.taken.shape == (200, 2)  # 200 steps, buffer 500
    raw = sweep.restore_raw(200)
    for agent in range(2):
        np.testing.assert_array_equal(np.bincount(v.taken[:, agent], minlength=len(sweep.actions)),
                                      raw["counts"][run, agent])
    replay = sweep.restore_replay(200, keys=("latents", "carry"))
    assert set(replay) == {"latents", "carry"}  # the frames stay on disk
    p = sweep.params(200, run)["self_model"]
    x = np.concatenate([replay["latents"][run, :200], np.repeat(replay["carry"]["1"][run, :200, None], 2, axis=1)], -1)
    hidden = np.maximum(np.einsum("nai,aij->naj", x, p["Dense_0"]["kernel"]) + p["Dense_0"]["bias"], 0)
    q = np.einsum("naj,ajk->nak", hidden, p["Dense_1"]["kernel"]) + p["Dense_1"]["bias"]
    np.testing.assert_allclose(v.q, q, rtol=1e-4, atol=1e-5)
    np.testing.assert_allclose(v.spread(), q.max(-1) - q.min(-1), rtol=1e-4, atol=1e-5)
    for t in (0.5, 1.5):
        pr = v.boltzmann(t)
        np.testing.assert_allclose(pr.sum(-1), 1.0, rtol=1e-12)
        np.testing.assert_allclose(np.log(pr[..., 3] / pr[..., 0]), (v.q[..., 3] - v.q[..., 0]) / t, atol=1e-9)
    fp = v.favoured_probability([1e-6, 0.5, 1e6])  # argmax, the run's own T, uniform
    assert fp[0] > 0.99 and abs(fp[2] - 1 / len(sweep.actions)) < 1e-6 and fp[0] > fp[1] > fp[2]
    assert fp[1] == pytest.approx(v.boltzmann(0.5).max(-1).mean())
    with pytest.raises(ValueError, match="temperature=0"):
        v.boltzmann(0)
    with pytest.raises(an.SweepError, match="no replay buffers at step 100: only the newest checkpoint keeps them; they "
                                            "exist at steps 200"):
        an.action_values(sweep, run, step=100)
    with pytest.raises(KeyError, match="has no pixels; it holds actions, carry, frames, index, latents, size"):
        sweep.restore_replay(200, keys=("pixels",))


def test_curiosity_noise(sweep, monkeypatch):
    """The closed-form mean and variance of a step's curiosity over the latent's sampling noise
    against 20,000 draws through the sweep's own sampling and curiosity; the self-model's
    prediction against `action_values`; the within-window shares and correlations against NumPy;
    and a ring buffer whose head has moved round reads back in the same time order."""
    import jax

    from mjx_curio import world_model as wm

    run = sweep.select(policy="ucb")[0]
    cn = an.curiosity_noise(sweep, run, chunk=64)
    assert cn.step == 200 and cn.expected.shape == cn.noise_var.shape == cn.predicted.shape == (199, 2)
    assert (cn.noise_var > 0).all() and (cn.expected > cn.spread).all() and (cn.spread > 0).all()
    v = an.action_values(sweep, run)
    np.testing.assert_array_equal(cn.taken, v.taken[:199])
    np.testing.assert_allclose(cn.predicted, np.take_along_axis(v.q[:199], cn.taken[..., None], -1)[..., 0],
                               rtol=1e-4, atol=1e-5)

    cfg, params = sweep.learner_config(), sweep.params(200, run)
    rp = sweep.restore_replay(200, keys=("frames", "latents", "carry", "actions", "index", "size"))
    k = 20_000
    for t in (0, 57, 198):
        c, h = rp["carry"]["0"][run, t], rp["carry"]["1"][run, t]
        _, mix = wm.rnn_step(cfg, params["rnn"], (c, h), rp["latents"][run, t], rp["actions"][run, t])
        mu, logvar = wm.encode(cfg, params["vae"], rp["frames"][run, t + 1])
        z = jax.vmap(lambda key: wm.sample_latent(key, mu, logvar))(jax.random.split(jax.random.key(t), k))
        draws = np.asarray(jax.vmap(lambda zi: wm.curiosity(cfg, zi, mix))(z), np.float64)  # [k, agents]
        se = draws.std(axis=0) / np.sqrt(k)
        assert (np.abs(draws.mean(axis=0) - cn.expected[t]) < 5 * se).all(), (t, draws.mean(0), cn.expected[t])
        np.testing.assert_allclose(draws.var(axis=0), cn.noise_var[t], rtol=0.1)
        np.testing.assert_allclose(cn.spread[t], np.exp(np.asarray(logvar, np.float64)).mean(-1), rtol=1e-5)

    e, q = cn.expected[:180].reshape(9, 20, 2), cn.predicted[:180].reshape(9, 20, 2)
    within = e.var(axis=1).mean(axis=0)
    noise = cn.noise_var[:180].mean(axis=0)
    np.testing.assert_allclose(cn.noise_share(20), noise / (noise + within), rtol=1e-12)
    np.testing.assert_allclose(cn.ceiling(20), np.sqrt(within / (noise + within)), rtol=1e-12)
    ed, qd = (e - e.mean(1, keepdims=True)).reshape(-1, 2), (q - q.mean(1, keepdims=True)).reshape(-1, 2)
    for agent in range(2):
        r = np.corrcoef(qd[:, agent], ed[:, agent])[0, 1]
        np.testing.assert_allclose(cn.tracking(20)["self"][agent], r, rtol=1e-9)
        means = [cn.expected[cn.taken[:, agent] == i, agent].mean() for i in range(len(sweep.actions))]
        assert cn.action_means()[5, agent] == pytest.approx(means[cn.taken[5, agent]], rel=1e-12)
    with pytest.raises(ValueError, match="window=1: want a whole number of steps >= 2"):
        cn.noise_share(1)
    # From a zero carry: the same steps' E[c] without their history, in closed form.
    zero = an.curiosity_noise(sweep, run, chunk=64, zero_state=True)
    t = 57
    blank = np.zeros_like(rp["carry"]["0"][run, t])
    _, mix = wm.rnn_step(cfg, params["rnn"], (blank, blank), rp["latents"][run, t], rp["actions"][run, t])
    mu, logvar = wm.encode(cfg, params["vae"], rp["frames"][run, t + 1])
    want = (np.square(np.asarray(mu - wm.mixture_mean(mix), np.float64)) + np.exp(np.asarray(logvar, np.float64))).mean(-1)
    np.testing.assert_allclose(zero.expected[t], want, rtol=1e-4)
    np.testing.assert_array_equal(zero.spread, cn.spread)  # the posterior does not depend on the memory
    assert not np.allclose(zero.expected, cn.expected)

    # Over the buffer's 200 views: the 199 that follow a step, and the first.
    spread = an.posterior_spread(sweep, run, every=1)
    assert sorted(spread) == sweep.checkpoint_steps()
    first = np.exp(np.asarray(wm.encode(cfg, params["vae"], rp["frames"][run, 0])[1], np.float64)).mean(-1)  # [agents]
    np.testing.assert_allclose(spread[200] * 200 * 2, cn.spread.sum() + first.sum(), rtol=1e-5)
    # Dimension by dimension, the same variances: their mean is the spread.
    dims = an.posterior_dims(sweep, run, every=1)
    assert sorted(dims) == sorted(spread) and dims[200].shape == (cfg.latent,)
    views = np.exp(np.asarray(wm.encode(cfg, params["vae"], rp["frames"][run, :200])[1], np.float64))
    np.testing.assert_allclose(dims[200], views.reshape(-1, cfg.latent).mean(0), rtol=1e-5)
    assert all(dims[k].mean() == pytest.approx(v, rel=1e-12) for k, v in spread.items())
    with pytest.raises(ValueError, match="every=0: want a whole number of views >= 1"):
        an.posterior_spread(sweep, run, every=0)
    # The same buffer written from slot 430 on, its head gone round past the end to 130: the same steps.
    shift, cap = 430, rp["actions"].shape[1]
    rolled = jax.tree.map(lambda x: np.roll(x, shift, axis=1) if np.ndim(x) > 1 else x, rp)
    rolled["index"] = (rp["index"] + shift) % cap
    monkeypatch.setattr(type(sweep), "restore_replay", lambda self, step, keys=(): rolled)
    again = an.curiosity_noise(sweep, run, chunk=64)
    np.testing.assert_array_equal(again.taken, cn.taken)
    np.testing.assert_array_equal(again.expected, cn.expected)
    np.testing.assert_array_equal(again.predicted, cn.predicted)


# ---------------------------------------------------------------------------------- figures


def _has_data(ax):
    lines = any(np.isfinite(np.asarray(ln.get_ydata(), float)).any() for ln in ax.lines)
    return lines or ax.collections or ax.patches or ax.images


def test_every_figure_draws(sweep, single, tmp_path):
    draws = [
        lambda ax: an.plot_curiosity(sweep, ax, "ucb"),
        lambda ax: an.plot_curiosity(single, ax, "eps"),
        lambda ax: an.plot_curiosity_groups(sweep, ax),
        lambda ax: an.plot_temperatures(sweep, ax),
        lambda ax: an.plot_boltzmann_greediness(sweep, ax),
        lambda ax: an.plot_single_vs_multi(single, sweep, ax),
        lambda ax: an.plot_vae_single_vs_multi(single, sweep, ax),
        lambda ax: an.plot_cumulative_interactions(sweep, ax, "object"),
        lambda ax: an.plot_cumulative_interactions(sweep, ax, "agent"),
        lambda ax: an.plot_interaction_frequency(sweep, ax, "eps"),
        lambda ax: an.plot_action_histogram(sweep, ax, "boltzmann"),
        lambda ax: an.plot_self_model_tracking(sweep, ax),
        lambda ax: an.plot_self_model_tracking(single, ax),
        lambda ax: an.plot_view_fractions(sweep, ax, "ucb", agent=1),
        lambda ax: an.plot_observational(sweep, ax),
    ]
    for i, draw in enumerate(draws):
        fig, ax = plt.subplots()
        assert draw(ax) is ax
        assert _has_data(ax), i
        assert ax.get_title() and ax.get_xlabel() and ax.get_ylabel(), i
        path = an.save_figure(fig, tmp_path, f"fig{i}")
        assert path.stat().st_size > 1000
        plt.close(fig)
    fig, axes = plt.subplots(1, 3)
    an.plot_losses(sweep, axes)
    assert all(_has_data(ax) for ax in axes)
    plt.close(fig)
    fig, axes = plt.subplots(1, 2)
    an.plot_turn_reversals(sweep, axes)
    assert all(_has_data(ax) and ax.get_title() and ax.get_ylabel() for ax in axes)
    plt.close(fig)
    fig, axes = plt.subplots(1, 5)
    an.plot_temperature_measures(sweep, axes)
    assert all(_has_data(ax) and ax.get_title() and ax.get_xscale() == "log" for ax in axes)
    plt.close(fig)
    fig = plt.figure()
    an.plot_reconstructions(sweep, fig, run=0, n_frames=4)
    assert len(fig.axes) == 3 * 4 and all(ax.images for ax in fig.axes)
    plt.close(fig)


def test_curiosity_figure_values(sweep):
    fig, ax = plt.subplots()
    an.plot_curiosity(sweep, ax, "ucb", window=3)
    g = sweep.group("ucb")
    ma = an.moving_average(sweep.metrics["curiosity_sample"][g.indices, :, 1], 3, axis=1).mean(axis=0)
    drawn = [ln for ln in ax.lines if ln.get_label() == "purple agent: moving average (3 points)"]
    np.testing.assert_allclose(drawn[0].get_ydata(), ma, rtol=1e-6)
    plt.close(fig)


def test_error_without_spread_figure_values(sweep):
    """Red: the sampled sweep's curiosity minus its spread; blue: the z=mean sweep's curiosity;
    each the agents' mean, moving-averaged, mean over runs (one sweep standing for both here)."""
    fig, ax = plt.subplots()
    an.plot_error_without_spread(sweep, sweep, ax, "ucb", window=3)
    g = sweep.group("ucb")
    c = sweep.metrics["curiosity"][g.indices].astype(float).mean(axis=2)
    s = sweep.metrics["curiosity_spread"][g.indices].astype(float).mean(axis=2)
    want = {"tab:red": c - s, "tab:blue": c}
    drawn = {ln.get_color(): ln.get_ydata() for ln in ax.lines}
    for color, x in want.items():
        np.testing.assert_allclose(drawn[color], an.moving_average(x, 3, axis=1).mean(axis=0), rtol=1e-6)
    assert (s > 0).any()  # the two lines differ
    plt.close(fig)


def test_claim_effects_figure_draws_each_test_where_its_interval_lies():
    """One row per test with an effect, top to bottom in the table's order: blue on the paper's
    side, red on the other, grey across 0; filled where Holm's adjustment keeps it."""
    table = an.Table([], [], [
        {"key": "1", "test": "a.seeds-0-7 rise", "d": 2.0, "d_low": 1.0, "d_high": 3.0, "p_holm": 0.01},
        {"key": "5", "test": "share", "d": -2.0, "d_low": -3.0, "d_high": -1.0, "p_holm": 0.2},
        {"key": "7", "test": "late curiosity", "d": None, "d_low": None, "d_high": None, "p_holm": None},
        {"key": "11", "test": "UCB > ε", "d": 0.1, "d_low": -0.5, "d_high": 0.7, "p_holm": 1.0},
    ], "")
    fig, ax = plt.subplots()
    an.plot_claim_effects(table, ax)
    spans, dots = ax.lines[0:6:2], ax.lines[1:6:2]  # each row's interval, then its dot
    assert [tuple(ln.get_xdata()) for ln in spans] == [(1.0, 3.0), (-3.0, -1.0), (-0.5, 0.7)]
    assert [ln.get_ydata()[0] for ln in spans] == [2, 1, 0]  # claim 7's row left out
    assert [ln.get_color() for ln in spans] == [an.EFFECT_COLORS[k] for k in ("paper", "other way", "neither")]
    assert [ln.get_markerfacecolor() for ln in dots] == [an.EFFECT_COLORS["paper"], "white", "white"]
    assert [t.get_text() for t in ax.get_yticklabels()] == ["1: a rise", "5: share", "11: UCB > ε"]
    plt.close(fig)
    with pytest.raises(ValueError, match="no test with an effect"):
        an.plot_claim_effects(an.Table([], [], [table.values[2]], ""), plt.subplots()[1])


def test_empty_figure_refused(tmp_path):
    fig, ax = plt.subplots()
    ax.plot([1, 2], [np.nan, np.nan])
    ax.set_title("nothing")
    with pytest.raises(an.SweepError, match="empty axes: nothing"):
        an.save_figure(fig, tmp_path, "empty")
    plt.close(fig)


def test_figures_never_written_into_sweep_outputs(sweep, tiny_sweep):
    fig, ax = plt.subplots()
    ax.plot([0, 1])
    for bad in (tiny_sweep / "metrics", tiny_sweep / "checkpoints" / "x", tiny_sweep):
        with pytest.raises(an.SweepError, match="refusing"):
            an.save_figure(fig, bad, "x")
    assert an.figures_dir(tiny_sweep) == tiny_sweep / "figures"
    plt.close(fig)


# ---------------------------------------------------------------------------------- bad input


def test_not_a_sweep(tmp_path):
    with pytest.raises(an.SweepError, match="does not exist"):
        an.load(tmp_path / "nowhere")
    with pytest.raises(an.SweepError, match="no manifest.json"):
        an.load(tmp_path)
    with pytest.raises(an.SweepError, match="none of its subdirectories"):
        an.find_sweeps(tmp_path)
    (tmp_path / "manifest.json").write_text("{not json")
    with pytest.raises(an.SweepError, match="not valid JSON"):
        an.load(tmp_path)
    (tmp_path / "manifest.json").write_text(json.dumps({"format": "something/2"}))
    with pytest.raises(an.SweepError, match="format 'something/2'"):
        an.load(tmp_path)


def _copy_without(src, dst, *leave_out):
    shutil.copytree(src, dst, ignore=lambda d, names: [n for n in names if n in leave_out])
    return dst


def test_missing_parts(tiny_sweep, tmp_path):
    d = _copy_without(tiny_sweep, tmp_path / "a", "kl.npy", "checkpoints")
    with pytest.raises(an.SweepError, match=r"metrics file .*kl\.npy is missing"):
        an.load(d)
    np.save(d / "metrics" / "kl.npy", np.zeros((8, 3), np.float32))
    with pytest.raises(an.SweepError, match=r"kl\.npy has shape \(8, 3\)"):
        an.load(d)
    shutil.copy(tiny_sweep / "metrics" / "kl.npy", d / "metrics" / "kl.npy")
    s = an.load(d)  # metrics alone are enough to load
    with pytest.raises(an.SweepError, match=r"has no checkpoints: .*checkpoints/state does not exist"):
        s.checkpoint_steps()
    with pytest.raises(an.SweepError, match="no checkpoints"):
        an.reconstructions(s)
    e = _copy_without(tiny_sweep, tmp_path / "b", "metrics")
    with pytest.raises(an.SweepError, match="no metrics directory"):
        an.load(e)
    f = _copy_without(tiny_sweep, tmp_path / "c", "progress.json")
    with pytest.raises(an.SweepError, match="no finished metrics yet"):
        an.load(f)
    for text, why in (("{not json", "is not valid JSON"), ("[1, 2]", "a JSON list, not the sweep's progress")):
        (f / "progress.json").write_text(text)
        with pytest.raises(an.SweepError, match=why) as err:
            an.load(f)
        assert str(f / "progress.json") in str(err.value)


def test_missing_checkpoint_step(sweep):
    with pytest.raises(an.SweepError, match=r"no checkpoint at step 150: .*state/150 does not exist; checkpoints exist "
                                            r"at steps 100, 200"):
        sweep.restore_raw(150)
    with pytest.raises(an.SweepError, match="step 150"):
        an.reconstructions(sweep, 0, steps=[100, 150])
    with pytest.raises(an.SweepError, match="out of range"):
        sweep.run(8)


def test_wrong_sweep_kind(sweep, single):
    with pytest.raises(an.SweepError, match="not a single-agent sweep"):
        an.plot_single_vs_multi(sweep, sweep, None)
    with pytest.raises(an.SweepError, match="no Boltzmann runs"):
        an.plot_temperatures(single, None)
