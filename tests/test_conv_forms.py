"""`python -m mjx_curio.bench what=convs` (mjx_curio/conv_forms.py): the encoder's convolution
with a kernel per run in three forms, each checked against a float64 NumPy convolution and its
gradients, and the grouped form checked to be what it says (a grouped convolution in the
program) before its timings mean anything."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from mjx_curio import bench, conv_forms

RUNS, FRAMES, SIDE, CIN, COUT = 2, 3, 10, 5, 6


def numpy_conv(x, w):
    """4 x 4 stride-2 VALID convolution per run: x [R,B,H,W,C], w [R,4,4,C,O], float64."""
    out_side = (x.shape[2] - 4) // 2 + 1
    y = np.zeros(x.shape[:2] + (out_side, out_side, w.shape[-1]))
    for ky in range(4):
        for kx in range(4):
            patch = x[:, :, ky : ky + 2 * out_side - 1 : 2, kx : kx + 2 * out_side - 1 : 2]
            y += np.einsum("rbijc,rco->rbijo", patch, w[:, ky, kx])
    return y


def numpy_grads(x, w, g):
    """(d/dx, d/dw) of sum(conv(x, w) * g), float64."""
    out_side = g.shape[2]
    dx, dw = np.zeros_like(x), np.zeros_like(w)
    for ky in range(4):
        for kx in range(4):
            rows, cols = slice(ky, ky + 2 * out_side - 1, 2), slice(kx, kx + 2 * out_side - 1, 2)
            dw[:, ky, kx] = np.einsum("rbijc,rbijo->rco", x[:, :, rows, cols], g)
            dx[:, :, rows, cols] += np.einsum("rbijo,rco->rbijc", g, w[:, ky, kx])
    return dx, dw


@pytest.fixture(scope="module")
def inputs():
    rng = np.random.default_rng(0)
    x = rng.random((RUNS, FRAMES, SIDE, SIDE, CIN))
    w = rng.standard_normal((RUNS, 4, 4, CIN, COUT)) / 4
    g = rng.standard_normal((RUNS, FRAMES, 4, 4, COUT))
    return x, w, g


@pytest.mark.parametrize("form", conv_forms.FORMS)
def test_each_form_is_the_per_run_convolution_and_its_gradients(form, inputs):
    x, w, g = inputs
    xj, wj, gj = (jnp.asarray(a, jnp.float32) for a in inputs)
    np.testing.assert_allclose(jax.jit(conv_forms.batched(form))(xj, wj), numpy_conv(x, w), rtol=1e-5, atol=1e-5)
    dx, dw = jax.jit(conv_forms.gradients(conv_forms.batched(form)))(xj, wj, gj)
    want_dx, want_dw = numpy_grads(x, w, g)
    np.testing.assert_allclose(dx, want_dx, rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(dw, want_dw, rtol=1e-5, atol=1e-4)


def test_the_grouped_form_is_a_grouped_convolution_and_the_others_are_not(inputs):
    xj, wj, _ = (jnp.asarray(a, jnp.float32) for a in inputs)

    def hlo(form):
        return jax.jit(conv_forms.batched(form)).lower(xj, wj).as_text()

    assert f"feature_group_count = {RUNS}" in hlo("grouped")
    for form in ("matmul", "taps"):
        assert f"feature_group_count = {RUNS}" not in hlo(form), form


def test_the_bench_times_every_layer_in_every_form(capsys):
    result = bench.main(["what=convs", "runs=2", "image=16", "batch=2", "seq_len=4", "iters=1", "repeats=1"])
    assert [(r["layer"], r["form"]) for r in result["layers"]] == [
        (layer, form) for layer in ("conv1_7x7x32", "conv2_2x2x64") for form in conv_forms.FORMS]
    # one run: 2 sequences x 4 steps x 2 agents = 16 frames forward; 2 x 2 = 4 backward
    assert (result["forward_frames_per_run"], result["backward_frames_per_run"]) == (16, 4)
    for r in result["layers"]:
        assert r["forward_ms"] > 0 and r["backward_ms"] > 0 and r["forward_gflop"] > 0
        assert r["forward_rel_err"] < 1e-5 and r["grad_rel_err"] < 1e-5, r
    out = capsys.readouterr().out
    assert "conv2_2x2x64      taps" in out and '"what": "convs"' in out
