"""`python -m mjx_curio.bench what=profile` (mjx_curio/profile.py): the per-component profile of
a run-step. Checked against independent truths, never against timings: the encoder's FLOPs as
XLA reports them against a hand count from the layer shapes, and the loop correction against a
toy scan whose FLOPs are known."""

import jax
import jax.numpy as jnp
import pytest

from mjx_curio import bench, nets, profile
from mjx_curio import world_model as wm
from mjx_curio.config import ConfigError, LearnerConfig

TINY = ("image=16", "batch=2", "seq_len=4", "iters=1", "repeats=1", "peak_n=64", "buffer=20")


def _encoder_flops(lc: LearnerConfig) -> float:
    """FLOPs of encoding one frame, by hand: 2 x H_out x W_out x k x k x C_in x C_out per 4x4
    stride-2 convolution (nets.encoder_sizes gives H_out) and 2 x in x out for the mean and
    log-variance head."""
    sizes = nets.encoder_sizes(lc.image, len(lc.vae_channels), lc.vae_layers)
    chans = (3,) + tuple(lc.vae_channels[: len(sizes)])
    convs = sum(2 * s * s * 4 * 4 * chans[i] * chans[i + 1] for i, s in enumerate(sizes))
    return convs + 2 * sizes[-1] ** 2 * chans[len(sizes)] * 2 * lc.latent


def test_encoder_flops_match_a_hand_count(capsys):
    result = bench.main(["what=profile", "parts=encoding,memory,self_models", *TINY])
    out = capsys.readouterr().out
    assert "encoding" in out and '"what": "profile"' in out and "The same matmul in bfloat16: " in out
    assert result["peak_matmul_gflops"] > 0 and result["peak_matmul_bf16_gflops"] > 0
    comps = result["components"]
    assert set(comps) == {"encoding", "memory", "self_models"}
    for row in comps.values():
        assert row["ms_per_call"] > 0 and row["flops"] > 0 and row["xla_bytes"] > 0
    lc = LearnerConfig(image=16, n_agents=2)
    enc = comps["encoding"]
    assert enc["calls_per_run_step"] == 1 + 1 / 4  # every step, and once more after each update
    assert enc["scan_extra_flops"] == 0 and enc["flops"] == enc["xla_flops"]
    hand = lc.n_agents * _encoder_flops(lc)
    assert hand <= enc["xla_flops"] <= 1.05 * hand  # the rest: bias, relu, scaling, the sample
    # The jaxpr count counts the convolutions and matmuls alone: exactly the hand count.
    f = lambda p, x, k: wm.latent(lc, p, x, k)  # noqa: E731
    args = (wm.init_learner(lc, jax.random.key(0)).vae, jnp.zeros((2, 16, 16, 3), jnp.uint8), jax.random.key(1))
    counted, unknown = profile.jaxpr_flops(jax.make_jaxpr(f)(*args).jaxpr)
    assert counted == lc.n_agents * _encoder_flops(lc) and not unknown
    # memory: one LSTM step (input and recurrent gates) and the mixture head, matmuls only
    h, zin = lc.rnn_hidden, lc.n_agents * (lc.latent + lc.n_actions)
    mm = 2 * (zin * 4 * h + h * 4 * h + h * lc.n_agents * lc.latent * lc.mixtures * 3)
    assert mm <= comps["memory"]["xla_flops"] <= 1.1 * mm


def test_the_authors_layers_encoder_flops_match_a_hand_count():
    """vae_layers=authors: padded convolutions (16 -> 8, 4, 2 here), whose batch normalisation
    (by the running averages when acting) and leaky ReLUs add elementwise work only. XLA's own
    count leaves out the taps that fall on the padding, the jaxpr count does not."""
    result = bench.main(["what=profile", "parts=encoding", "vae_layers=authors", *TINY])
    lc = LearnerConfig(image=16, n_agents=2, vae_layers="authors")
    hand = lc.n_agents * _encoder_flops(lc)
    assert _encoder_flops(lc) > _encoder_flops(LearnerConfig(image=16, n_agents=2))  # three layers, not two
    assert 0.5 * hand <= result["components"]["encoding"]["xla_flops"] <= 1.1 * hand
    st = wm.init_learner(lc, jax.random.key(0))
    f = lambda p, s, x, k: wm.latent(lc, p, x, k, s)  # noqa: E731
    args = (st.vae, st.vae_stats, jnp.zeros((2, 16, 16, 3), jnp.uint8), jax.random.key(1))
    counted, unknown = profile.jaxpr_flops(jax.make_jaxpr(f)(*args).jaxpr)
    assert counted == hand and not unknown


def test_loop_bodies_are_counted_per_iteration():
    """XLA's cost analysis counts a scan body once; `counts` adds the iterations it leaves out."""
    def f(x, w):
        return jax.lax.scan(lambda c, _: (jnp.tanh(c @ w), None), x, None, length=10)[0]

    x, w = jnp.ones((16, 64)), jnp.ones((64, 64))
    traced = jax.jit(f).trace(x, w)
    c = profile.counts(traced.lower().compile(), traced.jaxpr.jaxpr)
    one = 2 * 16 * 64 * 64
    assert c["xla_flops"] < 2 * one  # the body once (this is what the correction is for)
    assert c["scan_extra_flops"] == 9 * one
    assert 10 * one <= c["flops"] <= 10.2 * one


def test_bad_parts_is_refused_naming_the_key(capsys):
    with pytest.raises(SystemExit):
        bench.main(["what=profile", "parts=encoding,warp"])
    err = capsys.readouterr().err
    assert "parts" in err and "warp" in err and "encoding" in err


@pytest.mark.parametrize("args, knob, allowed", [
    (["checkpoint=later"], "checkpoint", "none, sync, async, both"),
    (["checkpoint=both", "checkpoint_dir=/nonexistent/place"], "checkpoint_dir", "a directory you can write"),
])
def test_bad_checkpoint_timing_input_is_refused_before_any_work(args, knob, allowed, capsys):
    with pytest.raises(SystemExit) as exit_:
        bench.main(["what=sweep", *args])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and knob in err and all(a in err for a in allowed.split(", ")), err


@pytest.mark.parametrize("args, knob, allowed", [
    (["what=learner", "walls=different"], "walls", "what=env"),
    (["what=env", "parts=encoding"], "parts", "what=profile"),
    (["what=learner", "runs_loop=vmap"], "runs_loop", "what=sweep | profile"),
    (["what=profile", "host_devices=2"], "host_devices", "what=sweep"),
    (["what=sweep", "checkpoint_dir=/tmp"], "checkpoint_dir", "checkpoint=sync | async | both"),
])
def test_a_key_the_bench_ignores_is_refused_before_any_work(args, knob, allowed, capsys):
    with pytest.raises(SystemExit) as exit_:
        bench.main(args)
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and knob in err and allowed in err, err


def test_the_checkpoint_timing_fills_each_replay_with_copies_of_its_written_steps():
    """bench what=sweep checkpoint=...: an unfilled replay would checkpoint as zeros, which
    compress to nothing; each run's buffer is filled by repeating what it wrote (NumPy's view of
    the same rule), and a full one is left as it is."""
    import jax.numpy as jnp
    import numpy as np

    from mjx_curio import replay as replay_lib
    from mjx_curio import run as run_lib

    rng = np.random.default_rng(0)
    cap, sizes, heads = 10, np.array([3, 10]), np.array([3, 4])
    one = replay_lib.init(n_agents=2, image=4, latent=3, rnn_hidden=5, capacity=cap)
    replay = jax.tree.map(lambda x: np.stack([np.asarray(x)] * 2), one)
    replay = replay._replace(frames=rng.integers(0, 256, replay.frames.shape, dtype=np.uint8),
                             latents=rng.normal(size=replay.latents.shape).astype(np.float32),
                             actions=rng.integers(0, 7, replay.actions.shape, dtype=np.int32),
                             carry=tuple(rng.normal(size=c.shape).astype(np.float32) for c in replay.carry),
                             index=heads.astype(np.int32), size=sizes.astype(np.int32))
    states = run_lib.RunState(*([None] * len(run_lib.RunState._fields)))._replace(
        replay=jax.tree.map(jnp.asarray, replay))
    got = bench._fill_replay(states).replay
    np.testing.assert_array_equal(got.size, [cap, cap])
    np.testing.assert_array_equal(got.index, [0, 4])  # the full buffer keeps its write head
    for r, size in enumerate(sizes):
        take = np.arange(cap) % size
        for name in ("frames", "latents", "actions"):
            np.testing.assert_array_equal(np.asarray(getattr(got, name))[r], getattr(replay, name)[r][take])
        for c_got, c_want in zip(got.carry, replay.carry):
            np.testing.assert_array_equal(np.asarray(c_got)[r], c_want[r][take])


LEARNER_PARTS = "replay_sample,vae_update,mdn_rnn_bptt,self_model_update,reencode,reencode_layers"


@pytest.mark.slow
def test_every_learner_component_at_tiny_sizes(capsys):
    """The learner's components (the acting ones are in the test above). The MJX programs
    (physics, rendering, the whole run-step) are left to `python -m mjx_curio.bench
    what=profile`: their compiles take minutes on a 2-core CPU, and the sweep tests compile and
    check those programs already."""
    result = bench.main(["what=profile", f"parts={LEARNER_PARTS}", *TINY])
    names = LEARNER_PARTS.split(",")
    assert list(result["components"]) == [name for name, when in profile.COMPONENTS
                                          if name in names and when != "detail"]
    comps = result["components"]
    for name, row in comps.items():
        assert row["ms_per_call"] > 0 and (row["flops"] > 0 or name == "replay_sample"), name
    assert comps["mdn_rnn_bptt"]["scan_extra_flops"] > 0  # the BPTT time loop
    assert comps["reencode"]["calls_per_run_step"] == 0.25  # latents=reencode, an update every 4 steps
    # re-encoding: the encoder on B x T x n_agents = 2 x 4 x 2 = 16 frames
    lc = LearnerConfig(image=16)
    assert comps["reencode"]["flops"] == pytest.approx(16 * _encoder_flops(lc), rel=0.05)
    # ... and stage by stage: each convolution against its hand count, the head's matmul
    layers = result["reencode_layers"]
    assert list(layers) == ["conv1_7x7x32", "conv2_2x2x64", "head"]
    sizes, chans = nets.encoder_sizes(16, 4), (3, 32, 64)
    for i, (name, row) in enumerate(list(layers.items())[:2]):
        hand = 16 * 2 * sizes[i] ** 2 * 4 * 4 * chans[i] * chans[i + 1]
        assert hand <= row["flops"] <= 1.05 * hand, name  # the rest: bias, ReLU (and scaling)
        assert row["calls_per_run_step"] == 0.25
    head = 16 * 2 * sizes[-1] ** 2 * chans[-1] * 2 * lc.latent
    assert head <= layers["head"]["flops"] <= 1.05 * head
    assert sum(row["flops"] for row in layers.values()) == pytest.approx(comps["reencode"]["flops"], rel=0.05)
    out = capsys.readouterr().out
    assert "vae_update" in out and "  conv1_7x7x32" in out


@pytest.mark.parametrize("loop", ["vmap", "map"])
def test_several_runs_profile_every_run_and_count_each(loop, capsys):
    """`runs=2`: each part runs over both runs the way the sweep's runs loop would (vmap batched,
    as on a GPU; map one by one), so a call does twice one run's work: the re-encoding's FLOPs
    are twice the hand count of one run's 16 frames, and the per-run-step figures divide by the
    runs."""
    result = bench.main(["what=profile", "parts=encoding,reencode,learner_update", "runs=2", f"runs_loop={loop}",
                         *TINY])
    assert result["runs"] == 2 and result["runs_loop"] == loop
    comps = result["components"]
    lc = LearnerConfig(image=16)
    # one run's re-encoding: the encoder on B x T x n_agents = 2 x 4 x 2 = 16 frames
    assert comps["reencode"]["flops"] == pytest.approx(2 * 16 * _encoder_flops(lc), rel=0.05)
    assert comps["encoding"]["flops"] == pytest.approx(2 * 2 * _encoder_flops(lc), rel=0.1)
    for row in comps.values():
        assert row["runs_per_call"] == 2
        assert row["ms_per_run_step"] == pytest.approx(row["ms_per_call"] * row["calls_per_run_step"] / 2, rel=1e-5)
        assert row["flops_per_run_step"] == pytest.approx(row["flops"] * row["calls_per_run_step"] / 2, rel=1e-5)
    assert f"runs: 2, runs_loop={loop}" in capsys.readouterr().out


def test_runs_auto_is_one_run_for_the_profile_and_refuses_zero(capsys):
    result = bench.main(["what=profile", "parts=memory", *(a for a in TINY if not a.startswith("peak_n="))])
    assert result["runs"] == 1
    assert result["peak_matmul_n"] == 2048  # peak_n=auto on a CPU
    with pytest.raises(SystemExit):
        bench.main(["what=profile", "runs=0"])
    err = capsys.readouterr().err
    assert "runs" in err and "auto" in err, err
