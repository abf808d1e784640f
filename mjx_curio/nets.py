"""The networks of the learning agent, as flax.linen modules.

- `VAE`: the vision model (paper 3.2, eq. 1/5). Encoder = the paper's convolutions
  32-64-128-256, kernel 4, stride 2, no padding (Ha & Schmidhuber; or the authors' padded
  layers with batch normalisation and leaky ReLUs, `layers="authors"`), then mean and
  log-variance heads. Decoder = one 4x4 stride-2 transposed convolution per encoder layer
  (DCGAN / H&S style), each computed as a 2x2 convolution to 4x the channels followed by
  depth-to-space: that *is* a stride-2 transposed convolution with a 4x4 kernel (same
  parameters and receptive field; only the alignment of the output grid differs) but its
  gradient costs a plain convolution instead of XLA CPU's slow lhs-dilated one.
- `MDNRNN`: the memory model (eq. 2/6): an LSTM over every agent's latent and one-hot
  action, with a mixture-density head giving, per agent and per latent dimension, a
  Gaussian mixture over the next latent (Ha & Schmidhuber's MDN-RNN).
- `SelfModel`: one agent's self-model (eq. 4): an MLP from (z_i, h) to the predicted
  curiosity of each of the 7 actions. Agents own separate parameters: world_model.py
  stacks them along a leading agent axis and vmaps.

All modules take unbatched or batched inputs as documented; parameters are plain pytrees,
so everything vmaps over a leading runs axis of parameters.

Speed notes (2-core CPU, jax 0.10.2, see bench.py): every strided convolution is
differentiated as space-to-depth + a stride-1 2x2 convolution (`conv2x2`) whose backward pass
is hand-written: the input gradient is another plain convolution and the kernel gradient
four matmuls. XLA's own gradients of strided / transposed convolutions go through
lhs-dilated or image-sized-window convolutions that run 2-6x slower here. The encoder's
forward pass, alone what re-encoding runs, is XLA's strided convolution where the input has
enough channels (`conv4x4_stride2`): it needs no space-to-depth transpose of its input.
"""

from __future__ import annotations

from typing import NamedTuple

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

_DN = ("NHWC", "HWIO", "NHWC")

# log-std bounds of the mixture components: keeps the NLL finite when a transition is
# deterministic (std would otherwise shrink without bound) and the density sane at init.
LOGSTD_MIN = -7.0
LOGSTD_MAX = 3.0


# ----------------------------------------------------------------------------------------
# Initialisation
# ----------------------------------------------------------------------------------------


def init_params(module: nn.Module, key, *args, method=None):
    """Parameters of `module` with flax's default initialisers (kernels lecun-normal,
    i.e. truncated normal with std 1/sqrt(fan_in); biases zero; batch normalisation's scales
    one), drawn in ONE random call.

    Why not `module.init`: it draws every kernel with its own threefry call, and XLA CPU
    (LLVM -O3) took ~10 s to compile the ~20 of them for the learner; one flat draw
    compiles in well under a second. `args` are example inputs (only shapes matter).
    """
    shapes = jax.eval_shape(lambda: module.init(jax.random.PRNGKey(0), *args, method=method))["params"]
    leaves, treedef = jax.tree_util.tree_flatten_with_path(shapes)
    names = [getattr(path[-1], "key", None) for path, _ in leaves]
    is_kernel = [name == "kernel" for name in names]
    sizes = [int(np.prod(leaf.shape)) if k else 0 for (_, leaf), k in zip(leaves, is_kernel)]
    flat = jax.random.truncated_normal(key, -2.0, 2.0, (max(sum(sizes), 1),), jnp.float32)
    out, offset = [], 0
    for (_, leaf), k, n, name in zip(leaves, is_kernel, sizes, names):
        if name == "scale":  # a batch normalisation's gain starts at 1 (flax's and PyTorch's)
            out.append(jnp.ones(leaf.shape, leaf.dtype))
        elif k:
            fan_in = int(np.prod(leaf.shape[:-1]))
            # 0.8796...: std of a unit normal truncated to [-2, 2] (flax's correction)
            scale = 1.0 / np.sqrt(fan_in) / 0.87962566103423978
            out.append(flat[offset : offset + n].reshape(leaf.shape).astype(leaf.dtype) * scale)
            offset += n
        else:
            out.append(jnp.zeros(leaf.shape, leaf.dtype))
    return jax.tree_util.tree_unflatten(treedef, out)


# ----------------------------------------------------------------------------------------
# Convolution building blocks
# ----------------------------------------------------------------------------------------


def _conv2x2_conv(x, w):
    """conv2x2's forward as an XLA convolution: the form for one kernel. Plain VALID: an
    older version padded the rows on the CPU to keep the convolution away from YNNPACK, but
    with YNNPACK's fusions off (mjx_curio/__init__.py) the plain form is faster, and the
    padding cost up to twice the FLOPs in the deep layers (2 output rows computed as 4).
    `python -m mjx_curio.bench what=sweep runs=24 steps=100 repeats=1` on the 2-core AMD EPYC,
    the defaults: 21.5 run-steps/s against 17.8 padded (docs/cost_model.md has the profile)."""
    return lax.conv_general_dilated(x, w, (1, 1), "VALID", dimension_numbers=_DN)


def _conv2x2_dx_conv(dy, w):
    """conv2x2's input gradient as an XLA convolution: the "full" convolution of dy with
    the flipped, transposed kernel (a plain conv). dy [B,H-1,W-1,O] -> [B,H,W,C]."""
    wt = jnp.flip(w, (0, 1)).swapaxes(2, 3)
    return lax.conv_general_dilated(dy, wt, (1, 1), ((1, 1), (1, 1)), dimension_numbers=_DN)


_TAPS = ((0, 0), (0, 1), (1, 0), (1, 1))  # kernel taps (row, col), in w.reshape(4C, O)'s order


def _conv2x2_matmul(x, w):
    """conv2x2's forward as one matmul: the four taps' shifted views side by side along
    channels (im2col, [B,H-1,W-1,4C]) times the kernel as a [4C, O] matrix."""
    h, ww = x.shape[1] - 1, x.shape[2] - 1
    cols = jnp.concatenate([x[:, i : i + h, j : j + ww] for i, j in _TAPS], axis=-1)
    return jnp.einsum("bhwk,ko->bhwo", cols, w.reshape(-1, w.shape[-1]))


def _conv2x2_dx_matmul(dy, w):
    """conv2x2's input gradient as one matmul: dy times the [4C, O] kernel transposed gives
    each tap's contribution ([B,H-1,W-1,4C]), which is added back at the tap's offset."""
    c = w.shape[2]
    dcols = jnp.einsum("bhwo,ko->bhwk", dy, w.reshape(-1, w.shape[-1]))
    dx = None
    for t, (i, j) in enumerate(_TAPS):
        part = jnp.pad(dcols[..., t * c : (t + 1) * c], ((0, 0), (i, 1 - i), (j, 1 - j), (0, 0)))
        dx = part if dx is None else dx + part
    return dx


def _by_kernel(conv_form, matmul_form):
    """f(a, w) computed by `conv_form`, except under vmap with a batched kernel w.

    vmap's rule for a convolution whose kernel is batched (each run of a vmapped sweep has
    its own weights) is a grouped convolution (feature_group_count = batch), which GPUs
    run slowly. A batched kernel takes `matmul_form` instead, whose
    matmul vmap turns into a batched dot_general. With one kernel for the whole batch the
    batch axis folds into the images' batch and the convolution stays a convolution. The
    matmul form is not used without vmap: on a CPU its forward ran ~1.5x slower than
    Eigen's convolution for the encoder (README.md, "On a GPU")."""

    @jax.custom_batching.custom_vmap
    def f(a, w):
        return conv_form(a, w)

    @f.def_vmap
    def rule(axis_size, in_batched, a, w):
        a_batched, w_batched = in_batched
        if w_batched:
            return jax.vmap(matmul_form, in_axes=(0 if a_batched else None, 0))(a, w), True
        out = f(a.reshape((-1,) + a.shape[2:]), w)  # f again: an outer vmap may batch w
        return out.reshape((axis_size, -1) + out.shape[1:]), True

    return f


_conv2x2_forward = _by_kernel(_conv2x2_conv, _conv2x2_matmul)
_conv2x2_dx = _by_kernel(_conv2x2_dx_conv, _conv2x2_dx_matmul)


@jax.custom_vjp
def conv2x2(x, w):
    """VALID 2x2 stride-1 convolution, NHWC: x [B,H,W,C], w [2,2,C,O] -> [B,H-1,W-1,O].

    Under vmap with a batched w (per-run weights) the forward and the input gradient are
    matmuls, not grouped convolutions (`_by_kernel`); the kernel gradient is matmuls always."""
    return _conv2x2_forward(x, w)


def _conv2x2_fwd(x, w):
    return _conv2x2_forward(x, w), (x, w)


def _conv2x2_bwd(res, dy):
    x, w = res
    dx = _conv2x2_dx(dy, w)
    # d/dw: one matmul per kernel tap, contracting over batch and pixels.
    oh, ow, cin, cout = dy.shape[1], dy.shape[2], x.shape[-1], dy.shape[-1]
    d2 = dy.reshape(-1, cout)
    dw = jnp.stack(
        [jnp.einsum("nc,no->co", x[:, i : i + oh, j : j + ow].reshape(-1, cin), d2) for i, j in _TAPS]
    ).reshape(w.shape)
    return dx, dw


conv2x2.defvjp(_conv2x2_fwd, _conv2x2_bwd)


def space_to_depth(x):
    """[B,H,W,C] -> [B,H//2,W//2,4C], channel order (row phase, column phase, C).

    An odd last row/column is dropped: a 4x4 stride-2 VALID convolution never reads it.
    """
    b, h, w, c = x.shape
    h2, w2 = h // 2, w // 2
    x = x[:, : 2 * h2, : 2 * w2]
    return x.reshape(b, h2, 2, w2, 2, c).transpose(0, 1, 3, 2, 4, 5).reshape(b, h2, w2, 4 * c)


def depth_to_space(x):
    """[B,H,W,4C] -> [B,2H,2W,C]; inverse of `space_to_depth` on even sizes."""
    b, h, w, c4 = x.shape
    c = c4 // 4
    return x.reshape(b, h, w, 2, 2, c).transpose(0, 1, 3, 2, 4, 5).reshape(b, 2 * h, 2 * w, c)


def kernel4_to_s2d(w4):
    """A 4x4 kernel [4,4,C,O] as the equivalent 2x2 kernel over space-to-depth input."""
    cin, cout = w4.shape[2], w4.shape[3]
    # ky = 2*dy + py, kx = 2*dx + px  ->  w2[dy, dx, (py, px, c), o]
    return w4.reshape(2, 2, 2, 2, cin, cout).transpose(0, 2, 1, 3, 4, 5).reshape(2, 2, 4 * cin, cout)


# Below this many input channels, conv4x4_stride2's forward runs as space-to-depth + conv2x2:
# XLA's strided convolution vectorises over the input channels, and the frames have 3 (12 after
# space-to-depth). The first encoder layer on 512 frames, on a 2-core Intel Xeon: 52 ms a call in
# the space-to-depth form against 62 ms strided (median of 6 rounds); docs/cost_model.md.
_STRIDED_MIN_CHANNELS = 8


def _conv4x4_stride2_s2d(x, w4):
    """The convolution as space-to-depth + conv2x2 (exact: the same taps, regrouped)."""
    return conv2x2(space_to_depth(x), kernel4_to_s2d(w4))


def _conv4x4_stride2_conv(x, w4):
    """conv4x4_stride2's forward for one kernel: XLA's own strided convolution, which skips the
    space-to-depth transpose of the input (as much time as the convolution itself for the second
    encoder layer on 512 frames), or the space-to-depth form for inputs of few channels."""
    if x.shape[-1] < _STRIDED_MIN_CHANNELS:
        return _conv2x2_conv(space_to_depth(x), kernel4_to_s2d(w4))
    return lax.conv_general_dilated(x, w4, (2, 2), "VALID", dimension_numbers=_DN)


def _conv4x4_stride2_matmul(x, w4):
    return _conv2x2_matmul(space_to_depth(x), kernel4_to_s2d(w4))


_conv4x4_stride2_forward = _by_kernel(_conv4x4_stride2_conv, _conv4x4_stride2_matmul)


@jax.custom_vjp
def conv4x4_stride2(x, w4):
    """VALID 4x4 stride-2 convolution (the paper's encoder layer): x [B,H,W,C], w4 [4,4,C,O].

    The forward is XLA's strided convolution (`_conv4x4_stride2_conv`; under vmap with per-run
    kernels, batched matmuls); the gradients are those of the space-to-depth form, whose input
    gradient is a plain convolution where XLA's own is an lhs-dilated one that runs 2-6x slower on
    a CPU (module docstring)."""
    return _conv4x4_stride2_forward(x, w4)


def _conv4x4_stride2_fwd(x, w4):
    return _conv4x4_stride2_forward(x, w4), (x, w4)


def _conv4x4_stride2_bwd(res, dy):
    return jax.vjp(_conv4x4_stride2_s2d, *res)[1](dy)


conv4x4_stride2.defvjp(_conv4x4_stride2_fwd, _conv4x4_stride2_bwd)


def upconv4x4_stride2(x, w):
    """Stride-2 4x4 transposed convolution as a 2x2 conv to 4*O channels + depth-to-space.

    x [B,H,W,C], w [2,2,C,4*O] -> [B,2H,2W,O].
    """
    x = jnp.pad(x, ((0, 0), (0, 1), (0, 1), (0, 0)))
    return depth_to_space(conv2x2(x, w))


_TAPS3 = tuple((i, j) for i in range(3) for j in range(3))  # 3x3 taps, in w's (row, col) order


def _taps3_matrix(w):
    """A 3x3 kernel [3,3,C,O] as [C, 9*O]: each input channel's weight on every tap's output."""
    return w.transpose(2, 0, 1, 3).reshape(w.shape[2], 9 * w.shape[3])


@jax.custom_vjp
def conv3x3_same(x, w):
    """SAME 3x3 stride-1 convolution, NHWC: x [B,H,W,C], w [3,3,C,O] -> [B,H,W,O].

    For few output channels (the authors' decoder ends in 3): one matmul takes every pixel to
    each of the nine taps' contributions ([B,H,W,9*O]), and the output adds each tap's slice at its
    offset. XLA's CPU convolution idles with 3 output channels: on a 2-core Intel Xeon the layer's
    forward and backward pass over 32 views at 64 x 64 x 32 ran about 3x faster this way, the
    authors' whole VAE update 9 % faster, and a sweep of 4 one-agent runs with their layers (one
    thread a device) 1.5x faster (docs/cost_model.md). The backward pass is matmuls too;
    under vmap with per-run kernels they batch as matmuls, never as grouped convolutions."""
    return _conv3x3_same_fwd(x, w)[0]


def _conv3x3_same_fwd(x, w):
    o = w.shape[3]
    h, ww = x.shape[1], x.shape[2]
    taps = jnp.einsum("bhwc,ck->bhwk", x, _taps3_matrix(w))
    taps = jnp.pad(taps, ((0, 0), (1, 1), (1, 1), (0, 0)))
    # output (r, c) reads input (r + i - 1, c + j - 1) through tap (i, j)
    y = sum(taps[:, i : i + h, j : j + ww, t * o : (t + 1) * o] for t, (i, j) in enumerate(_TAPS3))
    return y, (x, w)


def _conv3x3_same_bwd(res, dy):
    x, w = res
    c, o = w.shape[2], w.shape[3]
    h, ww = dy.shape[1], dy.shape[2]
    padded = jnp.pad(dy, ((0, 0), (1, 1), (1, 1), (0, 0)))
    # dy where each tap takes input (r, c) to: output (r - i + 1, c - j + 1)
    shifted = jnp.concatenate([padded[:, 2 - i : 2 - i + h, 2 - j : 2 - j + ww] for i, j in _TAPS3], axis=-1)
    dx = jnp.einsum("bhwk,ck->bhwc", shifted, _taps3_matrix(w))
    dw = jnp.einsum("nc,nk->ck", x.reshape(-1, c), shifted.reshape(-1, 9 * o))
    return dx, dw.reshape(c, 3, 3, o).transpose(1, 2, 0, 3)


conv3x3_same.defvjp(_conv3x3_same_fwd, _conv3x3_same_bwd)


def _channel_sums(rows):
    """[N, C] -> [C], the sum over rows, as a matmul with a vector of ones: XLA's CPU backend runs
    a reduction over the leading axes several times slower (`add_bias`; batch normalisation over
    256 frames' 32 x 32 x 32 first layer, on a 2-core Intel Xeon: 44 ms against 91-94 ms for
    flax's BatchNorm or jnp.mean). Rows set side by side to widen the matmul ([N/k, k*C], then the
    k partial sums added) ran faster alone but slower inside a VAE update (docs/cost_model.md)."""
    return (jnp.ones((1, rows.shape[0]), rows.dtype) @ rows)[0]


@jax.custom_vjp
def add_bias(y, b):
    """y + b, b broadcast over the last axis: a convolution's bias.

    The same maths as `y + b`; only its gradient for b is computed differently. That gradient sums
    dy over every axis but the channels, which XLA's CPU backend runs as a slow reduction over the
    leading axes; as this matmul with a vector of ones, `python -m mjx_curio.bench what=profile
    parts=vae_update` took about 14 % less a VAE update on a 2-core Intel Xeon (docs/cost_model.md,
    "What else was tried on this CPU")."""
    return y + b


def _add_bias_fwd(y, b):
    return y + b, None


def _add_bias_bwd(_, dy):
    return dy, _channel_sums(dy.reshape(-1, dy.shape[-1]))


add_bias.defvjp(_add_bias_fwd, _add_bias_bwd)


class DownConv(nn.Module):
    """The paper's encoder layer: conv kernel 4, stride 2, VALID, + bias."""

    features: int

    @nn.compact
    def __call__(self, x):
        w = self.param("kernel", nn.initializers.lecun_normal(), (4, 4, x.shape[-1], self.features))
        b = self.param("bias", nn.initializers.zeros, (self.features,))
        return add_bias(conv4x4_stride2(x, w), b)


class UpConv(nn.Module):
    """Doubles the resolution: a stride-2 4x4 transposed conv, computed as conv + depth-to-space."""

    features: int

    @nn.compact
    def __call__(self, x):
        w = self.param("kernel", nn.initializers.lecun_normal(), (2, 2, x.shape[-1], 4 * self.features))
        b = self.param("bias", nn.initializers.zeros, (4 * self.features,))
        # bias before depth-to-space: a per-(phase, channel) bias, as in the transposed conv
        return depth_to_space(add_bias(conv2x2(jnp.pad(x, ((0, 0), (0, 1), (0, 1), (0, 0))), w), b))


class Conv3x3(nn.Module):
    """A SAME 3x3 convolution + bias (`conv3x3_same`); the parameters of flax's
    `nn.Conv(features, (3, 3), padding="SAME")`, so the two are interchangeable."""

    features: int

    @nn.compact
    def __call__(self, x):
        w = self.param("kernel", nn.initializers.lecun_normal(), (3, 3, x.shape[-1], self.features))
        b = self.param("bias", nn.initializers.zeros, (self.features,))
        return add_bias(conv3x3_same(x, w), b)


# ----------------------------------------------------------------------------------------
# VAE
# ----------------------------------------------------------------------------------------


# The authors' layers: PyTorch's BatchNorm2d (running averages updated with momentum 0.1 and
# the batch's unbiased variance, eps 1e-5) and LeakyReLU (slope 0.01).
_BN_MOMENTUM = 0.1
_BN_EPSILON = 1e-5
_LEAKY_SLOPE = 0.01


@jax.custom_vjp
def _batch_normalise(x, scale, bias):
    """Training-mode batch normalisation of x [..., C] by its own moments over every axis but the
    channels -> (y, batch mean [C], biased batch variance [C]). The moments are returned for the
    running averages only: their cotangents are ignored (nothing differentiates through them)."""
    return _batch_normalise_fwd(x, scale, bias)[0]


def _batch_normalise_fwd(x, scale, bias):
    rows = x.reshape(-1, x.shape[-1])
    n = rows.shape[0]
    mean = _channel_sums(rows) / n
    centred = rows - mean
    var = _channel_sums(jnp.square(centred)) / n
    inv = lax.rsqrt(var + _BN_EPSILON)
    xhat = centred * inv
    y = (xhat * scale + bias).reshape(x.shape)
    return (y, mean, var), (xhat, inv, scale)


def _batch_normalise_bwd(res, cotangents):
    xhat, inv, scale = res
    dy = cotangents[0]
    rows = dy.reshape(xhat.shape)
    c, n = xhat.shape[1], xhat.shape[0]
    sums = _channel_sums(jnp.concatenate([rows, rows * xhat], axis=-1))  # one pass for both
    dbias, dscale = sums[:c], sums[c:]
    # d/dx of (x - mean) / std with the batch's own mean and std (both depend on x)
    dx = inv * scale * (rows - dbias / n - xhat * (dscale / n))
    return dx.reshape(dy.shape), dscale, dbias


_batch_normalise.defvjp(_batch_normalise_fwd, _batch_normalise_bwd)


class BatchNorm(nn.Module):
    """PyTorch's BatchNorm2d over the last (channel) axis: `use_running_average=False`
    normalises by the batch's own moments and folds them into the running averages (collection
    "batch_stats": mean, and var from the unbiased batch variance, momentum 0.1); True
    normalises by the running averages."""

    @nn.compact
    def __call__(self, x, use_running_average: bool):
        c = x.shape[-1]
        scale = self.param("scale", nn.initializers.ones, (c,))
        bias = self.param("bias", nn.initializers.zeros, (c,))
        ra_mean = self.variable("batch_stats", "mean", jnp.zeros, (c,), jnp.float32)
        ra_var = self.variable("batch_stats", "var", jnp.ones, (c,), jnp.float32)
        if use_running_average:
            return (x - ra_mean.value) * (lax.rsqrt(ra_var.value + _BN_EPSILON) * scale) + bias
        y, mean, var = _batch_normalise(x, scale, bias)
        if not self.is_initializing():
            n = x.size // c
            mean, var = lax.stop_gradient(mean), lax.stop_gradient(var) * (n / max(n - 1, 1))
            ra_mean.value = (1.0 - _BN_MOMENTUM) * ra_mean.value + _BN_MOMENTUM * mean
            ra_var.value = (1.0 - _BN_MOMENTUM) * ra_var.value + _BN_MOMENTUM * var
        return y


def encoder_sizes(image: int, n_channels: int, layers: str = "hs") -> list[int]:
    """Spatial sizes after each encoder layer: as many of the paper's layers as fit.

    A layer is used while its output is at least 2x2. Ha & Schmidhuber's unpadded layers
    ("hs"): 64 -> 31, 14, 6, 2 (all four; 16 -> 7, 2: two; 8 -> 3: one). The authors' layers,
    padded by one pixel ("authors"), halve the side: 64 -> 32, 16, 8, 4 (16 -> 8, 4, 2: three).
    Tiny test images get a shallower encoder.
    """
    sizes, s = [], image
    for _ in range(n_channels):
        nxt = (s - 4) // 2 + 1 if layers == "hs" else s // 2
        if nxt < 2:
            break
        sizes.append(nxt)
        s = nxt
    if not sizes:
        raise ValueError(f"image {image} is too small for a 4x4 stride-2 encoder")
    return sizes


def _leaky_relu(x):
    return jnp.where(x >= 0, x, _LEAKY_SLOPE * x)


class VAE(nn.Module):
    """The vision model. `layers` chooses between two readings of the paper's encoder
    (convolutions 32-64-128-256, kernel 4, stride 2):

    - "hs", Ha & Schmidhuber's (the architecture the paper names): unpadded convolutions, each
      followed by a ReLU; decoder: a dense layer and a ReLU, then one 4x4 stride-2 transposed
      convolution per encoder layer (`dec_channels`, then 3 channels), ReLUs between, a sigmoid.
    - "authors", the authors' code: convolutions padded by one pixel, each followed by batch
      normalisation and a leaky ReLU; decoder: a dense layer (no activation), transposed
      convolutions of the encoder's widths reversed with the last repeated (256-128-64-32-32),
      each with batch normalisation and a leaky ReLU, then a 3x3 convolution to 3 channels and a
      sigmoid. Batch normalisation keeps running averages in the "batch_stats" collection:
      `train=True` normalises by the batch's own statistics and updates them (call with
      mutable=["batch_stats"]), `train=False` normalises by them.
    """

    image: int = 64
    latent: int = 32
    channels: tuple = (32, 64, 128, 256)
    dec_channels: tuple = (128, 64, 32, 16)
    layers: str = "hs"

    @property
    def n_layers(self) -> int:
        return len(encoder_sizes(self.image, len(self.channels), self.layers))

    def setup(self):
        n = self.n_layers
        self.down = [DownConv(c) for c in self.channels[:n]]
        self.heads = nn.Dense(2 * self.latent)  # mean and log-variance
        if self.layers == "hs":
            # mirror: decoder widths for the n layers used, from the coarse end
            self.dec = tuple(self.dec_channels[len(self.dec_channels) - n :])
            self.up = [UpConv(c) for c in self.dec[1:]] + [UpConv(3)]
        else:
            widths = tuple(reversed(self.channels[:n]))
            self.dec = widths + widths[-1:]  # 256-128-64-32-32: the last width repeated
            self.up = [UpConv(c) for c in self.dec[1:]]
            self.out = Conv3x3(3)
            self.down_norm = [BatchNorm() for _ in range(n)]
            self.up_norm = [BatchNorm() for _ in range(n)]
        self.start = self.image // 2**n  # 4 for 8..64 px
        self.fc = nn.Dense(self.start * self.start * self.dec[0])

    def encode(self, frames, train: bool = False):
        """frames uint8 (or float in [0,1]) [B,H,W,3] -> (mu, logvar), each [B,latent]."""
        x = frames
        for stage in range(self.n_layers + 1):
            x = self.encode_stage(stage, x, train)
        return x

    def encode_stage(self, stage: int, x, train: bool = False):
        """One stage of `encode`, which runs them in turn: stage i < n_layers is the i-th
        convolution and its activation (the first also scales uint8 frames to [0, 1]), stage
        n_layers the mean and log-variance head. Apart so that the profile can time each layer
        alone."""
        if stage == 0:
            dtype = x.dtype
            x = x.astype(jnp.float32)
            if jnp.issubdtype(dtype, jnp.integer):
                x = x * (1.0 / 255.0)
        if stage < self.n_layers:
            if self.layers == "hs":
                return nn.relu(self.down[stage](x))
            x = self.down[stage](jnp.pad(x, ((0, 0), (1, 1), (1, 1), (0, 0))))
            return _leaky_relu(self.down_norm[stage](x, use_running_average=not train))
        out = self.heads(x.reshape(x.shape[0], -1))
        return out[:, : self.latent], out[:, self.latent :]

    def decode(self, z, train: bool = False):
        """z [B,latent] -> images [B,H,W,3] in [0,1]."""
        x = self.fc(z)
        if self.layers == "hs":
            x = nn.relu(x).reshape(z.shape[0], self.start, self.start, self.dec[0])
            for i, layer in enumerate(self.up):
                x = layer(x)
                if i < len(self.up) - 1:
                    x = nn.relu(x)
            return nn.sigmoid(x)
        x = x.reshape(z.shape[0], self.start, self.start, self.dec[0])
        for layer, norm in zip(self.up, self.up_norm):
            x = _leaky_relu(norm(layer(x), use_running_average=not train))
        return nn.sigmoid(self.out(x))

    def __call__(self, frames, key, train: bool = False):
        """Encode, sample z with the reparameterisation trick, decode."""
        mu, logvar = self.encode(frames, train)
        z = mu + jnp.exp(0.5 * logvar) * jax.random.normal(key, mu.shape, mu.dtype)
        return self.decode(z, train), mu, logvar


# ----------------------------------------------------------------------------------------
# MDN-RNN
# ----------------------------------------------------------------------------------------


class Mixture(NamedTuple):
    """Per-agent, per-dimension Gaussian mixtures; each field [..., n_agents, latent, K]."""

    log_pi: jax.Array  # log mixture weights (normalised over K)
    mu: jax.Array
    log_std: jax.Array


class MDNRNN(nn.Module):
    """LSTM over (z of all agents, one-hot actions of all agents) + mixture-density head.

    `__call__` is one step on unbatched inputs: carry = (c, h), each [hidden];
    z [n_agents, latent]; a int [n_agents]. Returns (new carry, Mixture for z_{t+1}).

    The step is split into `input_gates` (the input's contribution to the four gates),
    `cell` (recurrence) and `mixture` (head) so a training sequence computes the input
    gates and the head for all steps in one matmul each, outside the time loop; only
    h @ W_h stays inside it (world_model.rnn_sequence).
    """

    n_agents: int = 2
    latent: int = 32
    mixtures: int = 5
    hidden: int = 256
    n_actions: int = 7

    def setup(self):
        self.in_gates = nn.Dense(4 * self.hidden)  # [z_1..z_n, onehot(a_1)..onehot(a_n)] -> gates
        self.rec_gates = nn.Dense(4 * self.hidden, use_bias=False)  # h -> gates
        self.head = nn.Dense(self.n_agents * self.latent * self.mixtures * 3)

    def input_gates(self, z, a):
        """z [..., n_agents, latent], a int [..., n_agents] -> [..., 4*hidden]."""
        lead = z.shape[:-2]
        x = jnp.concatenate(
            [
                z.reshape(lead + (-1,)),
                jax.nn.one_hot(a, self.n_actions, dtype=z.dtype).reshape(lead + (-1,)),
            ],
            axis=-1,
        )
        return self.in_gates(x)

    def cell(self, carry, gx):
        """One LSTM step from precomputed input gates gx [..., 4*hidden]."""
        c, h = carry
        i, f, g, o = jnp.split(gx + self.rec_gates(h), 4, axis=-1)
        c = nn.sigmoid(f) * c + nn.sigmoid(i) * jnp.tanh(g)
        h = nn.sigmoid(o) * jnp.tanh(c)
        return (c, h)

    def mixture(self, h):
        """h [..., hidden] -> Mixture, fields [..., n_agents, latent, K]."""
        out = self.head(h).reshape(h.shape[:-1] + (self.n_agents, self.latent, self.mixtures, 3))
        log_pi = jax.nn.log_softmax(out[..., 0], axis=-1)
        log_std = jnp.clip(out[..., 2], LOGSTD_MIN, LOGSTD_MAX)
        return Mixture(log_pi, out[..., 1], log_std)

    def __call__(self, carry, z, a):
        carry = self.cell(carry, self.input_gates(z, a))
        return carry, self.mixture(carry[1])


# ----------------------------------------------------------------------------------------
# Self-model
# ----------------------------------------------------------------------------------------


class SelfModel(nn.Module):
    """One agent's self-model: (z_i [latent], h [hidden]) -> predicted curiosity [n_actions]."""

    hidden: int = 256
    n_actions: int = 7

    @nn.compact
    def __call__(self, z, h):
        x = jnp.concatenate([z, h], axis=-1)
        x = nn.relu(nn.Dense(self.hidden)(x))
        return nn.Dense(self.n_actions)(x)
