"""The encoder's convolutions with a kernel per run, three ways: `python -m mjx_curio.bench what=convs`.

Under `runs_loop=vmap` (what a GPU runs) every run has its own weights, and JAX's batching rule
makes a convolution whose kernel is batched a grouped convolution (feature_group_count = runs).
The package computes such convolutions as batched matmuls instead (`nets._by_kernel`), on the
belief that GPUs run grouped convolutions slowly; on a CPU the matmul form moves many times the
bytes of a convolution (docs/cost_model.md, "Many runs at once, by component"). This bench times
each encoder layer at the main job's shapes, R runs each with its own kernel, in three forms:

    matmul    the package's: space-to-depth, then im2col (the 2 x 2 taps' shifted views side by
              side, [F, H-1, W-1, 4C]) times the kernel as a [4C, O] matrix (nets.conv4x4_stride2
              under vmap, its own backward)
    grouped   XLA's grouped convolution: lax.conv_general_dilated under vmap, JAX's own rule and
              gradients
    taps      space-to-depth, then one matmul of the whole input by all four taps' kernels side by
              side ([C, 4O]: the output of every tap at every position), then the four outputs
              added at their offsets: no im2col copy, for H x W positions of 4O outputs instead
              of (H-1) x (W-1) of O (fewer bytes where O is small against 4C; more FLOPs)

The forward pass on the re-encoding's frames (batch x seq_len x agents a run) and the backward
pass on the VAE update's (batch x agents a run: the gradients of input and kernel for a given
output gradient; the convolution is linear, so XLA drops the forward from that program): ms (best
of `repeats` after a warm-up), XLA's FLOPs and bytes accessed, and each form's largest deviation from the
per-run convolution (lax.map over the runs: one kernel at a time, no grouping), relative to that
result's largest magnitude. The forms compute the same sums in other orders.
"""

from __future__ import annotations

import time

import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from mjx_curio import nets, profile

FORMS = ("matmul", "grouped", "taps")
_DN = ("NHWC", "HWIO", "NHWC")


def strided_conv(x, w4):
    """The 4 x 4 stride-2 VALID convolution as XLA's own (one kernel: a plain convolution; under
    vmap with a batched kernel, a grouped one)."""
    return lax.conv_general_dilated(x, w4, (2, 2), "VALID", dimension_numbers=_DN)


def taps_conv(x, w4):
    """The same convolution as one matmul of the space-to-depth input by every tap's kernel,
    then the taps' outputs added at their offsets (module docstring)."""
    xs = nets.space_to_depth(x)
    w = nets.kernel4_to_s2d(w4)  # [2, 2, 4C, O]
    c4, o = w.shape[2], w.shape[3]
    y = jnp.einsum("bhwc,cto->bhwto", xs, w.reshape(4, c4, o).transpose(1, 0, 2))
    h, ww = xs.shape[1] - 1, xs.shape[2] - 1
    return sum(y[:, i : i + h, j : j + ww, t] for t, (i, j) in enumerate(nets._TAPS))


_FORWARD = {"matmul": nets.conv4x4_stride2, "grouped": strided_conv, "taps": taps_conv}


def batched(form: str):
    """The form over a leading runs axis of inputs and kernels, one kernel per run."""
    return jax.vmap(_FORWARD[form])


def per_run(x, w):
    """The reference: each run's convolution with its own kernel, one run at a time."""
    return lax.map(lambda xw: strided_conv(*xw), (x, w))


def gradients(fn):
    """(d/dx, d/dw) of sum(fn(x, w) * g): the backward pass for the output gradient g (fn is
    linear: the program computes no forward)."""
    return jax.grad(lambda x, w, g: jnp.sum(fn(x, w) * g), argnums=(0, 1))


def layer_shapes(image: int, channels: tuple) -> list[tuple[str, int, int, int]]:
    """(name, input side, input channels, output channels) of each encoder layer in use."""
    sizes = nets.encoder_sizes(image, len(channels))
    sides, chans = [image] + sizes[:-1], (3,) + tuple(channels)
    return [(f"conv{i + 1}_{s}x{s}x{chans[i + 1]}", sides[i], chans[i], chans[i + 1]) for i, s in enumerate(sizes)]


def _cost(compiled) -> tuple[float, float]:
    c = profile.cost(compiled)
    return c["xla_flops"], c["xla_bytes"]


def _rel_err(got, want) -> float:
    got, want = (np.asarray(a, np.float64) for a in (got, want))
    return float(np.max(np.abs(got - want)) / max(np.max(np.abs(want)), 1e-30))


def bench(args: dict, time_fn) -> dict:
    """Every layer in every form (module docstring); `args` are bench.py's keys, `time_fn` is
    bench._time."""
    from mjx_curio.config import LearnerConfig

    lc = LearnerConfig(image=args["image"], n_agents=args["agents"], batch=args["batch"], seq_len=args["seq_len"])
    runs, iters, repeats = args["runs"], args["iters"], args["repeats"]
    n_fwd = lc.batch * lc.seq_len * lc.n_agents  # the re-encoding's frames a run
    n_bwd = lc.batch * lc.n_agents  # the VAE update's
    rng = np.random.default_rng(args["seed"])
    rows = []
    for name, side, cin, cout in layer_shapes(lc.image, lc.vae_channels):
        w = jnp.asarray(rng.standard_normal((runs, 4, 4, cin, cout), np.float32) / np.sqrt(16 * cin))
        x_fwd = jnp.asarray(rng.random((runs, n_fwd, side, side, cin), np.float32))
        x_bwd = jnp.asarray(rng.random((runs, n_bwd, side, side, cin), np.float32))
        want = jax.jit(per_run)(x_fwd, w)
        g = jnp.asarray(rng.standard_normal(want.shape[:1] + (n_bwd,) + want.shape[2:], np.float32))
        want_grads = jax.jit(gradients(per_run))(x_bwd, w, g)
        for form in FORMS:
            fwd = jax.jit(batched(form)).lower(x_fwd, w).compile()
            bwd = jax.jit(gradients(batched(form))).lower(x_bwd, w, g).compile()
            _, fwd_s = time_fn(fwd, (x_fwd, w), iters, repeats)
            _, bwd_s = time_fn(bwd, (x_bwd, w, g), iters, repeats)
            (fwd_flops, fwd_bytes), (bwd_flops, bwd_bytes) = _cost(fwd), _cost(bwd)
            grads = bwd(x_bwd, w, g)
            rows.append({
                "layer": name, "form": form,
                "forward_ms": round(fwd_s * 1e3, 3), "forward_gflop": round(fwd_flops / 1e9, 4),
                "forward_mb": round(fwd_bytes / 1e6, 1),
                "backward_ms": round(bwd_s * 1e3, 3), "backward_gflop": round(bwd_flops / 1e9, 4),
                "backward_mb": round(bwd_bytes / 1e6, 1),
                "forward_rel_err": _rel_err(fwd(x_fwd, w), want),
                "grad_rel_err": max(_rel_err(a, b) for a, b in zip(grads, want_grads)),
            })
    return {"what": "convs", "runs": runs, "image": lc.image, "forward_frames_per_run": n_fwd,
            "backward_frames_per_run": n_bwd, "iters": iters, "repeats": repeats,
            "device_kind": jax.devices()[0].device_kind,
            "matmul_precision": str(jax.config.jax_default_matmul_precision or "default"), "layers": rows}


def table(result: dict) -> str:
    head = (f"{'layer':<18}{'form':<9}{'fwd ms':>10}{'GFLOP':>9}{'MB':>9}{'bwd ms':>12}{'GFLOP':>9}{'MB':>9}"
            f"{'fwd err':>10}{'grad err':>10}")
    lines = [head, "-" * len(head)]
    for r in result["layers"]:
        lines.append(f"{r['layer']:<18}{r['form']:<9}{r['forward_ms']:>10.3f}{r['forward_gflop']:>9.3f}"
                     f"{r['forward_mb']:>9.1f}{r['backward_ms']:>12.3f}{r['backward_gflop']:>9.3f}{r['backward_mb']:>9.1f}"
                     f"{r['forward_rel_err']:>10.1e}{r['grad_rel_err']:>10.1e}")
    lines += [
        "",
        f"{result['runs']} runs, each its own kernel (vmap). fwd: the forward pass on the re-encoding's"
        f" {result['forward_frames_per_run']} frames a run; bwd: the backward pass (gradients of input and kernel) on the"
        f" VAE update's {result['backward_frames_per_run']} frames a run. GFLOP, MB: XLA's cost analysis (flops, bytes accessed) a call. err: the largest deviation from"
        " the per-run convolution (one kernel at a time), relative to its largest magnitude.",
        f"matmul: the package's batched matmuls (im2col); grouped: XLA's grouped convolution; taps: one matmul by"
        f" every tap's kernel, the taps added at their offsets. Device: {result['device_kind']}, matmul precision"
        f" {result['matmul_precision']}.",
    ]
    return "\n".join(lines)
