"""Batched egocentric cameras as a pure-JAX ray caster: rgb and geom id per pixel.

MJX has no CPU renderer (`mjx.render` needs MuJoCo Warp / CUDA; see docs/paper_setup.md), so
every agent's view is ray cast analytically against the scene's visible geoms:

* `camera_poses(data, agent_body_ids)`: each agent's eye (0.2 above its body centre, i.e. on
  the top face of its cube) looking horizontally along its heading, as MuJoCo camera frames.
* `Renderer(mj_model, image, fovy, agent_body_ids, source=...)(data) -> (rgb, geom_id)`: the
  images of every agent of one world; `jit` and `vmap` it over worlds.

The camera: a square image of `image` x `image` pixels at vertical field of view `fovy`.
With `source=None` it is a square camera (the same field of view both ways, one ray through
each pixel's centre). With `source=(width, height)` it is the camera the authors' code uses:
render width x height (640 x 480: aspect 4:3, so about 106 degrees horizontally at fovy 90)
and resize that to the square image by nearest-pixel sampling, which squeezes the view
sideways. It is ray cast directly at the square size, never at 640 x 480: output pixel (i, j)
casts the ray through the centre of the source pixel that nearest-pixel resizing keeps,
column floor((j + 0.5) * width / image) and row floor((i + 0.5) * height / image) (the
convention of PIL's and torch's "nearest-exact"; `source_pixels`). The authors' resize is
torchvision's `Resize` (bilinear, antialiased on a PIL image), which blends the source pixels
around each output pixel's centre; one ray per pixel keeps that geometry and leaves out the
blur.

Everything that does not change while the world moves (which geoms are drawn, their types,
sizes, colours, textures, the convex hulls of meshes, the pixel rays in camera coordinates)
is read from the `mujoco.MjModel` once, in numpy, when the renderer is built. A call only
reads the poses `xpos`, `xmat`, `geom_xpos`, `geom_xmat` of the `mjx.Data`.

How a call works, and why it is fast on a CPU (24 worlds x 2 agents x 64x64 in ~7 ms):
* Rays are expressed in each primitive's local frame, where every intersection is a
  textbook formula (plane, slab box, sphere, capped cylinder, convex half-spaces).
* The primitives are visited by a Python loop *at trace time* (about ten of them here).
  Each visit computes hit depths for all rays at once ([views, rays] arrays) and keeps a
  running nearest hit with its payload (the shade, and the texel to colour it with, which
  also identifies the geom) by `where`. The whole loop is elementwise, so XLA compiles it
  into one fused, vectorised loop over rays that keeps intermediates in registers: no
  [rays, primitives] array is written to memory, no argmin and no per-primitive gather.
  Two XLA habits had to be worked around, each costing 6-8x: divides and square roots are
  not fused into several consumers (`_recip`, `_sqrt`), and the loop would be recomputed
  inside every consumer of its result (`_materialize`).
* Colour is one gather at the end from a table holding every drawn geom's texture
  (premultiplied by its material colour) or its one colour, and the sky.
* Ray directions are (x, y, -1) in camera coordinates, *not* normalised, so the ray
  parameter t is the depth along the view axis: near/far clip exactly like OpenGL's
  frustum, which is what MuJoCo's renderer (the ground truth in tests/test_render.py) does.

Drawn geoms: every geom with group < 3 and nonzero alpha (group 3 holds this project's
invisible collision proxies). Supported types: plane (finite half-extents; size 0 means
infinite as in MuJoCo; seen from its front only), sphere, cylinder (with caps), box, and mesh
(drawn as its convex hull, exact for convex meshes). Anything else raises at construction.

Colours: geom rgba, or the material's where MuJoCo would use it; 2D textures on planes and
boxes, nearest texel, mapped as MuJoCo maps them (checked against its renderer: on a
texuniform plane `texrepeat` copies per 2 m from the plane's corner, so the floor's checker
squares are 1 m; on a box face `texrepeat` copies across the face, u along the face's first
other axis, v along its second, texture row 0 at the top). A textured geom of another type
is drawn in its texture's mean colour. Shading: ambient + sun diffuse * max(0, n.l) +
headlight diffuse * max(0, n.view axis), from the model's first directional light and
`visual/headlight`; no specular, no shadows. The sky is flat `sky_rgb`.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import jax.numpy as jnp
from jax import lax
import mujoco
import numpy as np

# MuJoCo enum values (mjtGeom, mjtTexture, mjtTextureRole), spelled out for readability.
PLANE, SPHERE, CAPSULE, ELLIPSOID, CYLINDER, BOX, MESH = 0, 2, 3, 4, 5, 6, 7
_TEX_2D = 0
_TEXROLE_RGB = 1
_SUPPORTED = {PLANE: "plane", SPHERE: "sphere", CYLINDER: "cylinder", BOX: "box", MESH: "mesh"}

SKY_RGB = (10, 130, 200)  # the paper's background colour (the authors' code; docs/paper_setup.md)
EYE_HEIGHT = 0.2  # eye above the agent body's centre: the top face of a 0.2 half-extent cube
NEAR = 0.1
FAR = 10.0
_INVISIBLE_GROUP = 3  # geoms in this group or above are never drawn
_OWN = object()  # `Renderer.view`'s default source: the renderer's own


def camera_poses(data, agent_body_ids):
    """Each agent's egocentric camera: eye position and MuJoCo camera frame, world coordinates.

    The eye is `EYE_HEIGHT` above the body's centre. The camera looks along the body's local
    x axis projected to the horizontal plane, with world +z as up, so a cube that tilts does
    not roll or pitch the view. MuJoCo's convention: the camera looks along -z of `xmat`,
    +y is up and +x is right; `xmat[:, k]` is column k. For a heading of +x, right is -y.

    Args:
      data: `mjx.Data` (or anything with `xpos [nbody, 3]` and `xmat [nbody, 3, 3]` or
        `[nbody, 9]`, e.g. a `mujoco.MjData`).
      agent_body_ids: body ids of the agents, a static sequence of ints.
    Returns:
      pos `[n, 3]`, xmat `[n, 3, 3]` as float32.
    """
    ids = np.asarray(agent_body_ids, dtype=np.int32)
    xpos = jnp.asarray(data.xpos, jnp.float32)[ids]
    xmat = jnp.asarray(data.xmat, jnp.float32).reshape(-1, 3, 3)  # mujoco.MjData stores [nbody, 9]
    heading = xmat[ids][:, :, 0]  # body x axis in world
    hx, hy = heading[:, 0], heading[:, 1]
    # A heading pointing straight up would have no horizontal part; planar agents never do.
    norm = jnp.maximum(jnp.sqrt(hx * hx + hy * hy), 1e-9)
    hx, hy = hx / norm, hy / norm
    zero, one = jnp.zeros_like(hx), jnp.ones_like(hx)
    right = jnp.stack([hy, -hx, zero], axis=-1)  # heading x (0, 0, 1)
    up = jnp.stack([zero, zero, one], axis=-1)
    back = jnp.stack([-hx, -hy, zero], axis=-1)  # the camera looks along -z
    xmat = jnp.stack([right, up, back], axis=-1)  # columns
    pos = xpos + jnp.asarray([0.0, 0.0, EYE_HEIGHT], jnp.float32)
    return pos, xmat


def agent_bodies(mj_model) -> tuple[int, ...]:
    """Ids of the bodies named ``agent_*``, in body order (the default cameras)."""
    names = [mujoco.mj_id2name(mj_model, mujoco.mjtObj.mjOBJ_BODY, b) or "" for b in range(mj_model.nbody)]
    return tuple(b for b, n in enumerate(names) if n.startswith("agent_"))


@dataclass(frozen=True)
class _Prim:
    """One drawn geom, with everything about it that is constant (numpy / Python scalars)."""

    geom_id: int
    type: int
    body: int
    size: tuple  # geom_size
    texel: int  # colour-table entry (untextured) or first texel of its texture (textured)
    tex: tuple | None  # (width, height, repeat_u, repeat_v, uniform) for 2D-textured plane/box
    planes: np.ndarray | None  # mesh: [F, 4] outward unit normals n and offsets b, n.x <= b


class Renderer:
    """Renders every agent's egocentric view of one world; pure JAX, jit- and vmap-able.

    Args:
      mj_model: the `mujoco.MjModel` the `mjx.Data` comes from.
      image: image side in pixels (images are square).
      fovy: vertical field of view in degrees.
      source: None for a square camera; (width, height) for a camera of that aspect whose
        width x height picture is resized to the square image by nearest-pixel sampling (the
        authors' (640, 480)); see the module docstring.
      agent_body_ids: the bodies carrying a camera; default: the bodies named ``agent_*``.
        Each agent's view leaves out the geoms of its own body (its eye is on its own top face).
      near, far: clipping depths along the view axis; hits outside are ignored (far -> sky).
      sky_rgb: background colour.

    Calling it with one world's `mjx.Data` returns `rgb` uint8 `[n_agents, image, image, 3]`
    and `geom_id` int32 `[n_agents, image, image]` (MuJoCo geom id, -1 for sky); row 0 is the
    top of the image.
    """

    def __init__(
        self,
        mj_model,
        image: int,
        fovy: float = 90.0,
        agent_body_ids=None,
        near: float = NEAR,
        far: float = FAR,
        sky_rgb=SKY_RGB,
        source=None,
    ):
        m = mj_model
        self.source = _check_source(source)
        if agent_body_ids is None:
            agent_body_ids = agent_bodies(m)
        self.agent_body_ids = tuple(int(b) for b in agent_body_ids)
        if not self.agent_body_ids:
            raise ValueError("Renderer needs at least one agent body (agent_body_ids is empty)")
        self.image = int(image)
        self.fovy = float(fovy)
        self.near, self.far = float(near), float(far)

        self._ambient, self._sun, self._head = _scene_lights(m)
        self._shade_max = self._ambient + self._sun[1] + self._head
        self._prims, table, texel_gid = _extract_prims(m)
        # The colour table: every drawn geom's own block of texels (its texture premultiplied by
        # its colour, or its one colour), then the sky. `_texel_gid` maps a texel to its geom.
        self._sky_texel = len(table)
        self._table = np.concatenate([table, np.asarray(sky_rgb, np.float32)[None]], axis=0)
        self._texel_gid = np.append(texel_gid, -1).astype(np.int32)
        # A pixel's texel index and its quantised shade share one int32 (see __call__).
        self._shade_bits = min(16, 31 - max(int(len(self._table) - 1).bit_length(), 1))
        if self._shade_bits < 8:
            raise ValueError(f"textures too large for the renderer: {len(self._table)} texels (max 2**23)")
        self._gids = np.asarray([p.geom_id for p in self._prims], np.int32)
        # own[v, p]: primitive p belongs to agent v's own body, so v must not see it.
        self._own = self.hide_bodies([[b] for b in self.agent_body_ids])

    @property
    def n_agents(self) -> int:
        return len(self.agent_body_ids)

    @property
    def aspect(self) -> float:
        """Width / height of the agents' camera before it is squeezed into the square image."""
        return 1.0 if self.source is None else self.source[0] / self.source[1]

    def __call__(self, data):
        """Render every agent's view of one world: (rgb uint8 [V,H,W,3], geom_id int32 [V,H,W])."""
        eye, cam = camera_poses(data, self.agent_body_ids)  # [V,3], [V,3,3]
        # The agent's own body is never seen from its own eye (which sits on its top face).
        return self.view(data, eye, cam, hidden=self._own)

    def view(self, data, eye, cam, hidden=None, image: int | None = None, fovy: float | None = None,
             source=_OWN):
        """Render one world from any cameras with this scene's geoms, textures and lights.

        Args:
          data: `mjx.Data` (anything with `geom_xpos`, `geom_xmat`).
          eye: camera positions `[V, 3]`, world frame.
          cam: camera frames `[V, 3, 3]`, MuJoCo's convention (columns: right, up, back; the
            camera looks along -z).
          hidden: optional bool numpy `[V, n_prims]`: primitives left out of each view.
          image, fovy: image side and vertical field of view (default: the renderer's).
          source: None (a square camera) or the (width, height) squeezed into the image, as for
            `Renderer` (default: the renderer's own; pass None for a map view such as
            `overhead_camera`).
        Returns (rgb uint8 [V,H,W,3], geom_id int32 [V,H,W]); row 0 is the top of the image.
        """
        f32 = jnp.float32
        n = self.image if image is None else int(image)
        source = self.source if source is _OWN else _check_source(source)
        X, Y, inv_dd = _pixel_rays(n, self.fovy if fovy is None else float(fovy), source)
        eye = jnp.asarray(eye, f32).reshape(-1, 3)
        cam = jnp.asarray(cam, f32).reshape(-1, 3, 3)
        gpos = jnp.asarray(data.geom_xpos, f32)[self._gids]  # [P,3]
        gmat = jnp.asarray(data.geom_xmat, f32).reshape(-1, 3, 3)[self._gids]  # [P,3,3] local -> world
        # Per view and primitive: the eye in the primitive's frame, o = R^T (eye - c), and the
        # camera axes in that frame, A = R^T C; a pixel ray is then d = A (x, y, -1).
        rel = eye[:, None, :] - gpos[None, :, :]  # [V,P,3]
        o = _rt_times(gmat[None], rel)  # [V,P,3]
        axes = [_rt_times(gmat[None], cam[:, None, :, j]) for j in range(3)]  # 3 x [V,P,3]
        # Direction towards the sun in each primitive's frame, for n . l. The headlight shines
        # along the view axis: towards it is the camera's back axis, axes[2].
        sun = _rt_times(gmat, jnp.broadcast_to(jnp.asarray(self._sun[0]), gpos.shape))  # [P,3]
        X, Y = jnp.asarray(X), jnp.asarray(Y)  # inv_dd stays numpy: a compile-time constant
        n_views, n_rays = eye.shape[0], X.shape[0]
        if hidden is not None and np.shape(hidden) != (n_views, len(self._prims)):
            raise ValueError(f"hidden has shape {np.shape(hidden)}; expected {(n_views, len(self._prims))}")

        # Running nearest hit and its payload. Starting t at `far` clips everything beyond it.
        t_best = jnp.full((n_views, n_rays), self.far, f32)
        shade_best = jnp.zeros((n_views, n_rays), f32)
        texel_best = jnp.full((n_views, n_rays), self._sky_texel, jnp.int32)

        for p, prim in enumerate(self._prims):
            op = [o[:, p, i][:, None] for i in range(3)]  # [V,1] each
            a = [[axes[j][:, p, i][:, None] for i in range(3)] for j in range(3)]  # [V,1] each
            d = [a[0][i] * X + a[1][i] * Y - a[2][i] for i in range(3)]  # [V,R] each
            t, ndot, texel = _INTERSECT[prim.type](prim, op, d, inv_dd, self.near)
            shade = self._ambient + self._sun[1] * jnp.maximum(ndot([sun[p, i] for i in range(3)]), 0.0)
            if self._head > 0:
                shade = shade + self._head * jnp.maximum(ndot(a[2]), 0.0)
            if hidden is not None and np.any(hidden[:, p]):
                t = jnp.where(jnp.asarray(hidden[:, p])[:, None], jnp.inf, t)
            better = t < t_best
            t_best = jnp.where(better, t, t_best)
            shade_best = jnp.where(better, shade, shade_best)
            texel_best = jnp.where(better, texel, texel_best)

        # The whole loop above is one elementwise expression per ray: XLA compiles it into one
        # fused, vectorised loop. Its result leaves as ONE int32 per ray (the texel, which also
        # identifies the geom, and the quantised shade), written to memory by `_materialize`:
        # without that, XLA fuses (i.e. recomputes) the whole loop into each consumer below,
        # once for the geom ids and once per colour channel, which made it 8x slower.
        levels = (1 << self._shade_bits) - 1
        q = jnp.round(jnp.clip(shade_best * (1.0 / self._shade_max), 0.0, 1.0) * levels).astype(jnp.int32)
        packed = _materialize((texel_best << self._shade_bits) | q)

        texel = packed >> self._shade_bits  # always a valid table index: no bounds handling
        gid = jnp.asarray(self._texel_gid).at[texel].get(mode="promise_in_bounds")
        shade = (packed & levels).astype(f32) * (self._shade_max / levels)
        shade = jnp.where(texel == self._sky_texel, 1.0, shade)  # the sky is not lit
        colour = jnp.asarray(self._table).at[texel].get(mode="promise_in_bounds")
        colour = colour * shade[..., None]  # [V,R,3], 0..255
        rgb = jnp.clip(jnp.round(colour), 0, 255).astype(jnp.uint8)
        return rgb.reshape(n_views, n, n, 3), gid.reshape(n_views, n, n)

    def hide_bodies(self, bodies_per_view) -> np.ndarray:
        """The `hidden` mask for `view` that leaves out, in view v, the geoms of the bodies
        `bodies_per_view[v]`."""
        return np.asarray([[p.body in {int(b) for b in bodies} for p in self._prims] for bodies in bodies_per_view])


def _check_source(source):
    if source is None:
        return None
    w, h = (int(v) for v in source)
    if w < 1 or h < 1 or (w, h) != tuple(source):
        raise ValueError(f"source={source!r} must be None or (width, height), two positive integers")
    return (w, h)


def source_pixels(n: int, size: int) -> np.ndarray:
    """The source pixels [n] that nearest-pixel resizing of `size` pixels to `n` keeps: output
    pixel k takes floor((k + 0.5) * size / n), the source pixel under its centre (PIL's NEAREST
    and torch's "nearest-exact"). Integer arithmetic, so exact at any size."""
    k = np.arange(n, dtype=np.int64)
    return (2 * k + 1) * int(size) // (2 * int(n))


def _pixel_rays(n: int, fovy: float, source=None):
    """The rays of an n x n image in camera coordinates (x right, y up, looking along -z), ray
    r = row * n + column, row 0 on top: x [R], y [R] and 1/|d|^2 [R] (float32 numpy).

    source None: a square camera, one ray through each pixel's centre, the horizontal
    half-extent equal to the vertical one. source (width, height): the rays through the centres
    of the source pixels that nearest-pixel resizing of a width x height picture (horizontal
    half-extent tan(fovy / 2) * width / height) to n x n keeps (`source_pixels`)."""
    half = math.tan(math.radians(fovy) / 2.0)
    if source is None:
        cx = cy = (np.arange(n) + 0.5) / n * 2.0 - 1.0
        half_x = half
    else:
        w, h = source
        cx = (2.0 * source_pixels(n, w) + 1.0) / w - 1.0  # source pixel centres, -1 .. 1
        cy = (2.0 * source_pixels(n, h) + 1.0) / h - 1.0
        half_x = half * w / h
    x = np.tile(half_x * cx, n).astype(np.float32)
    y = np.repeat(-half * cy, n).astype(np.float32)
    # 1/|d|^2 of (x, y, -1): rotations keep |d|, so it is the same in every local frame.
    inv_dd = (1.0 / (x.astype(np.float64) ** 2 + y**2 + 1.0)).astype(np.float32)
    return x, y, inv_dd


def make_renderer(mj_model, image: int, fovy: float = 90.0, agent_body_ids=None, **kw) -> Renderer:
    """Same as `Renderer(...)`."""
    return Renderer(mj_model, image, fovy, agent_body_ids, **kw)


# ----------------------------------------------------------------------------- intersections
# Each takes the primitive, the eye in its frame `o` (3 x [V,1]), the ray directions in its
# frame `d` (3 x [V,R]), 1/|d|^2 `inv_dd` [R] and the near depth. It returns the hit depth t
# ([V,R], inf on a miss), `ndot(v)` giving the outward normal's dot product with a vector v
# given in the same frame (3 components broadcastable to [V,R]), and the colour-table index.
# Every divide and square root is `_recip` / `_sqrt`: see their docstrings for why.


def _plane(prim, o, d, inv_dd, near):
    # z = 0 in the local frame, seen from its front (+z) side only, as MuJoCo draws it.
    t = -o[2] * _recip(d[2])
    hit = (o[2] > 0) & (d[2] < 0) & (t >= near)
    qx, qy = o[0] + t * d[0], o[1] + t * d[1]
    sx, sy = prim.size[0], prim.size[1]
    if sx > 0:  # size 0 means infinite
        hit &= jnp.abs(qx) <= sx
    if sy > 0:
        hit &= jnp.abs(qy) <= sy
    t = jnp.where(hit, t, jnp.inf)

    def ndot(v):
        return jnp.broadcast_to(v[2], t.shape)

    if prim.tex is None:
        return t, ndot, jnp.full(t.shape, prim.texel, jnp.int32)
    w, h, rep_u, rep_v, uniform = prim.tex
    # Texture coordinates start at the plane's (-x, -y) corner. texuniform: `repeat` copies
    # per 2 m (what MuJoCo draws: texrepeat 1 gives 1 m checker squares); otherwise `repeat`
    # copies across the plane.
    su = rep_u / 2 if uniform or sx <= 0 else rep_u / (2 * sx)
    sv = rep_v / 2 if uniform or sy <= 0 else rep_v / (2 * sy)
    return t, ndot, _texel(prim, (qx + sx) * su, (qy + sy) * sv)


def _box(prim, o, d, inv_dd, near):
    # Slab method: the ray is inside the box between the largest entry and smallest exit depth.
    s = prim.size
    tn, tf = [], []
    for i in range(3):
        inv = _recip(d[i])
        ta = (-s[i] - o[i]) * inv
        tb = (s[i] - o[i]) * inv
        tn.append(jnp.minimum(ta, tb))
        tf.append(jnp.maximum(ta, tb))
    t_in = jnp.maximum(jnp.maximum(tn[0], tn[1]), tn[2])
    t_out = jnp.minimum(jnp.minimum(tf[0], tf[1]), tf[2])
    t = jnp.where((t_in <= t_out) & (t_in >= near), t_in, jnp.inf)
    # The face entered is on the axis whose entry depth is the largest; its outward normal
    # points against the ray along that axis.
    on_x = tn[0] >= jnp.maximum(tn[1], tn[2])
    on_y = ~on_x & (tn[1] >= tn[2])
    on_z = ~on_x & ~on_y

    def ndot(v):
        face = [jnp.where(d[i] < 0, v[i], -v[i]) for i in range(3)]
        return jnp.where(on_x, face[0], jnp.where(on_y, face[1], face[2]))

    if prim.tex is None:
        return t, ndot, jnp.full(t.shape, prim.texel, jnp.int32)
    # MuJoCo's mapping of a 2D texture on a box face (measured against its renderer): u runs
    # along the face's first other axis and v along its second (x faces: y, z; y faces: x, z;
    # z faces: x, y), from the face's corner, `repeat` copies across the face; the same on
    # opposite faces. For a wall: u along the wall, v up its height.
    w, h, rep_u, rep_v, uniform = prim.tex
    q = [o[i] + t_in * d[i] for i in range(3)]
    # texuniform on a box: `repeat` copies per 2 m like a plane (MuJoCo's own scale differs).
    su = [rep_u / 2 if uniform else rep_u / (2 * s[i]) for i in range(3)]
    sv = [rep_v / 2 if uniform else rep_v / (2 * s[i]) for i in range(3)]
    u = jnp.where(on_x, (q[1] + s[1]) * su[1], (q[0] + s[0]) * su[0])
    v = jnp.where(on_z, (q[1] + s[1]) * sv[1], (q[2] + s[2]) * sv[2])
    return t, ndot, _texel(prim, u, v)


def _sphere(prim, o, d, inv_dd, near):
    r = prim.size[0]
    b = o[0] * d[0] + o[1] * d[1] + o[2] * d[2]
    c = o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - r * r  # [V,1]
    disc = b * b - c * (1.0 / inv_dd)
    t = (-b - _sqrt(jnp.maximum(disc, 0.0))) * inv_dd
    t = jnp.where((disc >= 0) & (t >= near), t, jnp.inf)

    def ndot(v):
        return sum((o[i] + t * d[i]) * v[i] for i in range(3)) * (1.0 / r)

    return t, ndot, jnp.full(t.shape, prim.texel, jnp.int32)


def _cylinder(prim, o, d, inv_dd, near):
    r, h = prim.size[0], prim.size[1]
    # Side: entry into the infinite cylinder x^2 + y^2 = r^2, kept if within |z| <= h.
    a = d[0] * d[0] + d[1] * d[1]
    b = o[0] * d[0] + o[1] * d[1]
    c = o[0] * o[0] + o[1] * o[1] - r * r
    disc = b * b - a * c
    ts = (-b - _sqrt(jnp.maximum(disc, 0.0))) * _recip(a)
    side = (disc >= 0) & (jnp.abs(o[2] + ts * d[2]) <= h) & (ts >= near)
    # Cap: the one facing the ray (the top one for a ray going down), kept if within radius.
    zc = jnp.where(d[2] < 0, h, -h)
    tc = (zc - o[2]) * _recip(d[2])
    xc, yc = o[0] + tc * d[0], o[1] + tc * d[1]
    cap = (xc * xc + yc * yc <= r * r) & (tc >= near)
    ts = jnp.where(side, ts, jnp.inf)
    tc = jnp.where(cap, tc, jnp.inf)
    on_cap = tc < ts
    t = jnp.minimum(ts, tc)

    def ndot(v):
        side_dot = ((o[0] + ts * d[0]) * v[0] + (o[1] + ts * d[1]) * v[1]) * (1.0 / r)
        return jnp.where(on_cap, jnp.where(d[2] < 0, v[2], -v[2]), side_dot)

    return t, ndot, jnp.full(t.shape, prim.texel, jnp.int32)


def _mesh(prim, o, d, inv_dd, near):
    # Convex hull as half-spaces n.x <= b: the ray is inside between the largest depth at which
    # it crosses a face it is entering (n.d < 0) and the smallest at which it leaves (n.d > 0).
    t_in = jnp.full(d[0].shape, -jnp.inf, jnp.float32)
    t_out = jnp.full(d[0].shape, jnp.inf, jnp.float32)
    face = jnp.zeros(d[0].shape, jnp.int32)
    planes = [tuple(float(x) for x in plane) for plane in prim.planes]
    for f, (nx, ny, nz, b) in enumerate(planes):
        den = nx * d[0] + ny * d[1] + nz * d[2]
        num = b - (nx * o[0] + ny * o[1] + nz * o[2])  # [V,1]
        tf = num * _recip(den)
        enter = (den < 0) & (tf > t_in)
        t_in = jnp.where(enter, tf, t_in)
        face = jnp.where(enter, f, face)
        t_out = jnp.where(den > 0, jnp.minimum(t_out, tf), t_out)
    t = jnp.where((t_in <= t_out) & (t_in >= near), t_in, jnp.inf)

    def ndot(v):
        out = jnp.zeros(t.shape, jnp.float32)
        for f, (nx, ny, nz, _) in enumerate(planes):
            out = jnp.where(face == f, nx * v[0] + ny * v[1] + nz * v[2], out)
        return out

    return t, ndot, jnp.full(t.shape, prim.texel, jnp.int32)


_INTERSECT = {PLANE: _plane, SPHERE: _sphere, CYLINDER: _cylinder, BOX: _box, MESH: _mesh}


def _texel(prim, su, sv):
    """Colour-table index of the nearest texel at texture coordinates (su, sv), in texture
    copies (the texture repeats every 1). Texture row 0 is the top: v grows upwards."""
    w, h = prim.tex[0], prim.tex[1]
    fu = su - jnp.floor(su)
    fv = sv - jnp.floor(sv)
    col = jnp.minimum((fu * w).astype(jnp.int32), w - 1)
    row = jnp.minimum(((1.0 - fv) * h).astype(jnp.int32), h - 1)
    return prim.texel + row * w + col


def _recip(x):
    """1/x from cheap elementwise ops: a bit-trick first guess and 3 Newton steps (~1 ulp).

    XLA counts divides and square roots as expensive and will not fuse an expensive op into
    more than one consumer; it writes each to memory instead, which split the caster into ~30
    loops over all rays and made it 6x slower. Multiplies, adds and bit casts fuse freely.
    """
    a = jnp.abs(x)
    y = lax.bitcast_convert_type(jnp.int32(0x7EF311C3) - lax.bitcast_convert_type(a, jnp.int32), jnp.float32)
    for _ in range(3):
        y = y * (2.0 - a * y)
    return jnp.where(x < 0, -y, y)  # 1/0 overflows to inf, as a divide would


def _sqrt(x):
    """sqrt(x) for x >= 0 from cheap elementwise ops (1/sqrt by bit trick + 3 Newton steps)."""
    y = lax.bitcast_convert_type(jnp.int32(0x5F3759DF) - (lax.bitcast_convert_type(x, jnp.int32) >> 1), jnp.float32)
    h = 0.5 * x
    for _ in range(3):
        y = y * (1.5 - h * y * y)
    return x * y


def _materialize(x):
    """x, computed once and stored, so XLA cannot fuse its computation into several consumers.

    `lax.optimization_barrier` did not stop that fusion here (jax 0.10.2, XLA CPU); a scatter
    is never fused into its consumers, so an identity scatter of whole rows (a cheap copy that
    keeps the ray axis contiguous) is the barrier.
    """
    idx = jnp.arange(x.shape[0], dtype=jnp.int32)  # whole rows: the row stays the fast axis
    return jnp.zeros_like(x).at[idx].set(x, unique_indices=True, indices_are_sorted=True)


def _rt_times(r, v):
    """R^T v for rotation matrices r [..., 3, 3] and vectors v [..., 3], by explicit products.

    Written out (not einsum / dot) so each element is computed by the same arithmetic whatever
    the batch shape: a world renders bit-identically alone and inside a vmapped batch.
    """
    return jnp.stack(
        [r[..., 0, i] * v[..., 0] + r[..., 1, i] * v[..., 1] + r[..., 2, i] * v[..., 2] for i in range(3)],
        axis=-1,
    )


# ----------------------------------------------------------------------------- model extraction


def _scene_lights(m):
    """The model's lighting reduced to what the caster draws: (ambient, sun, headlight).

    ambient: grey intensity, the sum of the lights' ambient (the headlight's ambient is left
    out: with it, every lit surface came out brighter than in MuJoCo's own images, which also
    attenuate lighting in ways not modelled here);
    sun: (direction towards the light in world coordinates, diffuse intensity) of the first
    directional light (else the first light; else a default sun like the scene's);
    headlight: diffuse intensity of MuJoCo's headlight, a directional light along the view
    axis (0 if inactive). Colours are averaged to grey; specular highlights are not drawn.
    """
    ambient = 0.0
    if m.nlight == 0:
        direction, diffuse = np.array([0.3, 0.2, -1.0]), 0.7
        ambient += 0.35
    else:
        kinds = np.asarray(getattr(m, "light_type", np.zeros(m.nlight))).reshape(-1)
        directional = [i for i in range(m.nlight) if int(kinds[i]) == 1]
        i = directional[0] if directional else 0
        direction = np.asarray(m.light_dir[i], np.float64)
        diffuse = float(np.mean(m.light_diffuse[i]))
        ambient += float(np.sum(np.mean(m.light_ambient, axis=1)))
    head = 0.0
    if m.vis.headlight.active:
        head = float(np.mean(m.vis.headlight.diffuse))
    towards = -direction / np.linalg.norm(direction)
    return float(ambient), (towards.astype(np.float32), float(diffuse)), float(head)


def _extract_prims(m):
    """The drawn geoms as `_Prim`s, the colour table [N, 3] (0..255) they index into, and the
    geom id of each table entry [N]."""
    table: list[np.ndarray] = []  # one block per drawn geom, so a texel identifies its geom
    texel_gid: list[np.ndarray] = []
    size_of = [0]

    def add(entries: np.ndarray, g: int) -> int:
        start = size_of[0]
        table.append(entries.astype(np.float32))
        texel_gid.append(np.full(len(entries), g, np.int32))
        size_of[0] += len(entries)
        return start

    prims = []
    for g in range(m.ngeom):
        rgba = _effective_rgba(m, g)
        if m.geom_group[g] >= _INVISIBLE_GROUP or rgba[3] <= 0:
            continue
        gtype = int(m.geom_type[g])
        if gtype not in _SUPPORTED:
            name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g)
            kind = mujoco.mjtGeom(gtype).name.removeprefix("mjGEOM_").lower()
            raise NotImplementedError(
                f"render.py cannot draw geom {g} ({name!r}) of type {kind}; "
                f"supported: {', '.join(_SUPPORTED.values())}. Put it in group 3 to hide it."
            )
        rgb = rgba[:3].astype(np.float64)
        texid = _rgb_texture(m, g)
        tex = None
        if texid >= 0:
            texels = _texels(m, texid) * rgb  # [h*w, 3], premultiplied by the material colour
            if m.tex_type[texid] == _TEX_2D and gtype in (PLANE, BOX):
                matid = m.geom_matid[g]
                rep = m.mat_texrepeat[matid]
                tex = (int(m.tex_width[texid]), int(m.tex_height[texid]), float(rep[0]), float(rep[1]),
                       bool(m.mat_texuniform[matid]))
                texel = add(texels, g)
            else:  # no texture mapping for this type: its mean colour
                texel = add(texels.mean(axis=0, keepdims=True), g)
        else:
            texel = add(rgb[None] * 255.0, g)
        planes = _mesh_planes(m, int(m.geom_dataid[g])) if gtype == MESH else None
        size = tuple(float(x) for x in m.geom_size[g])
        prims.append(_Prim(g, gtype, int(m.geom_bodyid[g]), size, texel, tex, planes))
    if not table:
        return prims, np.zeros((0, 3), np.float32), np.zeros((0,), np.int32)
    return prims, np.concatenate(table, axis=0), np.concatenate(texel_gid)


def _effective_rgba(m, g) -> np.ndarray:
    """MuJoCo's rule: a geom with a material uses the material's rgba unless its own rgba was set
    (i.e. differs from the default 0.5 0.5 0.5 1)."""
    rgba = np.asarray(m.geom_rgba[g], np.float64)
    matid = m.geom_matid[g]
    if matid >= 0 and np.allclose(rgba, [0.5, 0.5, 0.5, 1.0]):
        rgba = np.asarray(m.mat_rgba[matid], np.float64)
    return rgba


def _rgb_texture(m, g) -> int:
    matid = m.geom_matid[g]
    if matid < 0:
        return -1
    texid = np.asarray(m.mat_texid[matid]).reshape(-1)
    return int(texid[_TEXROLE_RGB]) if texid.size > _TEXROLE_RGB else int(texid[0])


def _texels(m, texid) -> np.ndarray:
    """A texture's texels as float [h*w, 3] (0..255), row 0 first (the top of the image)."""
    w, h, nc = int(m.tex_width[texid]), int(m.tex_height[texid]), int(m.tex_nchannel[texid])
    adr = int(m.tex_adr[texid])
    data = np.asarray(m.tex_data[adr : adr + w * h * nc], np.float64).reshape(w * h, nc)
    if nc >= 3:
        return data[:, :3]
    return np.repeat(data[:, :1], 3, axis=1)  # grey texture


def _mesh_planes(m, mesh_id) -> np.ndarray:
    """The mesh's convex hull as planes [F, 4]: outward unit normal n and offset b (n.x <= b),
    in the geom frame (MuJoCo stores mesh vertices already re-centred into that frame).

    The hull's triangles come from MuJoCo's own convex hull (`mesh_graph`) when it computed
    one, else from a brute-force search over vertex triples (fine for small meshes).
    """
    adr, num = int(m.mesh_vertadr[mesh_id]), int(m.mesh_vertnum[mesh_id])
    verts = np.asarray(m.mesh_vert[adr : adr + num], np.float64)
    scale = max(float(np.abs(verts).max()), 1e-9)
    eps = 1e-6 * scale
    triangles = None
    gadr = int(m.mesh_graphadr[mesh_id]) if m.nmeshgraph else -1
    if gadr >= 0:
        graph = np.asarray(m.mesh_graph)
        nv, nf = int(graph[gadr]), int(graph[gadr + 1])
        start = gadr + 2 + nv + nv + (nv + 3 * nf)
        triangles = graph[start : start + 3 * nf].reshape(nf, 3)
    elif num <= 64:
        triangles = np.asarray(list(itertools.combinations(range(num), 3)))
    else:
        raise NotImplementedError(f"mesh {mesh_id} has {num} vertices and no convex hull from MuJoCo")

    planes = []
    centre = verts.mean(axis=0)
    for i, j, k in triangles:
        n = np.cross(verts[j] - verts[i], verts[k] - verts[i])
        length = np.linalg.norm(n)
        if length < eps * scale:
            continue  # degenerate triple
        n = n / length
        b = n @ verts[i]
        if n @ centre > b:  # orient outwards
            n, b = -n, -b
        if np.all(verts @ n <= b + eps):  # a supporting plane: every vertex on its inner side
            planes.append(np.append(n, b))
    planes = np.asarray(planes)
    # Coplanar triangles (e.g. the two halves of a square base) give the same plane once.
    _, keep = np.unique(np.round(planes / np.array([1, 1, 1, scale]), 5), axis=0, return_index=True)
    return planes[np.sort(keep)].astype(np.float32)


# ----------------------------------------------------------------------------- a map view
OVERHEAD_HEIGHT = 7.5  # metres: with OVERHEAD_FOVY the whole 7.7 m room fits in the picture
OVERHEAD_FOVY = 60.0


def overhead_camera(height: float = OVERHEAD_HEIGHT, centre=(0.0, 0.0)):
    """A camera `height` metres above `centre` (x, y) looking straight down, image up = world +y,
    image right = world +x (a map view): pos `[1, 3]` and frame `[1, 3, 3]` for `Renderer.view`."""
    return np.asarray([[centre[0], centre[1], height]], np.float32), np.eye(3, dtype=np.float32)[None]


def project_overhead(points, height: float = OVERHEAD_HEIGHT, fovy: float = OVERHEAD_FOVY, image: int = 128,
                     centre=(0.0, 0.0)):
    """Pixel (row, column) of world points `[..., 3]` in `overhead_camera(height, centre)`'s image
    of side `image` (floats; pixel centres at k + 0.5). NumPy, for drawing on such images."""
    p = np.asarray(points, np.float64)
    half = math.tan(math.radians(fovy) / 2.0)
    depth = height - p[..., 2]
    u = (p[..., 0] - centre[0]) / (depth * half)  # -1 .. 1 across the image
    v = (p[..., 1] - centre[1]) / (depth * half)
    return (1.0 - v) / 2.0 * image, (u + 1.0) / 2.0 * image
