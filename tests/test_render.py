"""The ray-cast egocentric cameras (mjx_curio/render.py).

1. Against MuJoCo's own OpenGL renderer: the geom id of every pixel, for random states of all
   four scenes, must agree on >= 95% of the pixels of every view (measured: min 99.7%, mean 99.98%).
   The authors' camera (640 x 480 at fovy 90, resized to the square image by nearest-pixel
   sampling): our image against MuJoCo's 640 x 480 segmentation squeezed the same way, >= 98%
   of the pixels of every view.
2. A world renders bit-identically alone and inside a vmapped batch.
3. Behaviour: sky on top and floor below, a sphere in front is seen and yellow, turning moves
   the view, an agent never sees itself, the floor shows both checker colours.

MuJoCo's renderer needs an off-screen GL: `apt-get install -y libosmesa6` and
MUJOCO_GL=osmesa. mujoco picks its GL backend when it is first imported, so tests/conftest.py
sets the variable, where OSMesa is installed, before any test module imports mujoco. Without GL
the ground-truth test is skipped, saying so.
"""

import os

import mjx_curio  # noqa: E402,F401  (XLA flags before JAX initialises)

from pathlib import Path  # noqa: E402

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import mujoco  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from mujoco import mjx  # noqa: E402

from mjx_curio.render import FAR, NEAR, SKY_RGB, Renderer, camera_poses  # noqa: E402

SCENES = Path(__file__).resolve().parents[1] / "scenes"
GT_IMAGE = 64
SMALL = 16


def _model(name: str) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(str(SCENES / f"{name}.xml"))


def _gid(m, name: str) -> int:
    return mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, name)


def _set_agent(m, d, name, x, y, yaw):
    """Put agent body `name` at world (x, y) with heading `yaw` (its joints are x, y slides + yaw)."""
    b = m.body(name)
    d.qpos[m.joint(f"{name}_x").qposadr[0]] = x - b.pos[0]
    d.qpos[m.joint(f"{name}_y").qposadr[0]] = y - b.pos[1]
    d.qpos[m.joint(f"{name}_yaw").qposadr[0]] = yaw


def _set_free(m, d, name, pos, quat=(1.0, 0.0, 0.0, 0.0)):
    adr = m.joint(name).qposadr[0]
    d.qpos[adr : adr + 3] = pos
    d.qpos[adr + 3 : adr + 7] = np.asarray(quat) / np.linalg.norm(quat)


def _axis_angle(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    return np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * axis])


def _random_state(m, rng, topple):
    """Agents and objects at random non-overlapping places inside the room, random headings and
    orientations; the cylinder lying on its side when `topple`."""
    d = mujoco.MjData(m)
    placed = []

    def place(radius):
        for _ in range(10_000):
            p = rng.uniform(-3.1, 3.1, size=2)
            if all(np.linalg.norm(p - q) > radius + r + 0.05 for q, r in placed):
                placed.append((p, radius))
                return p
        raise RuntimeError("could not place an object")

    for b in range(1, m.nbody):
        name = m.body(b).name
        yaw_q = _axis_angle([0, 0, 1], rng.uniform(-np.pi, np.pi))
        if name.startswith("agent_"):
            x, y = place(0.3)
            _set_agent(m, d, name, x, y, rng.uniform(-np.pi, np.pi))
        elif name == "cylinder" and topple:
            x, y = place(0.55)
            q = np.zeros(4)
            mujoco.mju_mulQuat(q, yaw_q, _axis_angle(rng.normal(size=3) * [1, 1, 0.1], np.pi / 2))
            _set_free(m, d, name, (x, y, 0.2), q)
        elif name == "cylinder":
            x, y = place(0.25)
            _set_free(m, d, name, (x, y, 0.5), yaw_q)
        elif name == "sphere":
            x, y = place(0.35)
            _set_free(m, d, name, (x, y, 0.3), rng.normal(size=4))
        elif name == "disc":
            x, y = place(0.75)
            _set_free(m, d, name, (x, y, 0.05), yaw_q)
        elif name == "pyramid":
            x, y = place(0.75)
            _set_free(m, d, name, (x, y, 0.0), yaw_q)
        else:
            raise AssertionError(f"unexpected body {name!r}: update this test")
    mujoco.mj_forward(m, d)
    return d


def _stack(datas):
    """A batch of mjx.Data, stacked on the host (op-by-op jnp.stack of every field is slow)."""
    return jax.tree.map(lambda *xs: np.stack([np.asarray(x) for x in xs]), *datas)


# ----------------------------------------------------------------------------------------
# Ground truth: MuJoCo's own renderer
# ----------------------------------------------------------------------------------------


def _mujoco_geom_ids(m, d, gl, agent_body, pos, xmat, fovy=90.0):
    """Geom id per pixel from MuJoCo's segmentation render, through exactly our camera.

    The scene's camera is overwritten after `update_scene` with the pose from `camera_poses`
    and a frustum of the same fovy / near / far; MuJoCo sets the frustum's left and right from
    the viewport's aspect (`gl`'s width / height). Group 3 (invisible proxies) and the agent's
    own body (its eye sits on its own top face) are hidden, as in our renderer.
    """
    opt = mujoco.MjvOption()
    opt.geomgroup[:] = 0
    opt.geomgroup[:3] = 1
    own = np.flatnonzero(m.geom_bodyid == agent_body)
    saved = m.geom_group[own].copy()
    m.geom_group[own] = 5  # a hidden group, only while the scene is built
    try:
        gl.update_scene(d, camera=mujoco.MjvCamera(), scene_option=opt)
    finally:
        m.geom_group[own] = saved
    top = NEAR * np.tan(np.radians(fovy) / 2)
    for cam in gl.scene.camera:  # both eyes of the (mono) stereo pair
        cam.pos[:] = pos
        cam.forward[:] = -xmat[:, 2]
        cam.up[:] = xmat[:, 1]
        cam.frustum_near, cam.frustum_far = NEAR, FAR
        cam.frustum_top, cam.frustum_bottom = top, -top
        cam.frustum_center, cam.frustum_width = 0.0, top * gl.width / gl.height
        cam.orthographic = 0
    seg = gl.render()  # [H, W, 2]: object id, object type; background (-1, -1)
    return np.where(seg[..., 1] == int(mujoco.mjtObj.mjOBJ_GEOM), seg[..., 0], -1)


@pytest.fixture(scope="module")
def make_gl():
    """A factory of MuJoCo segmentation renderers; skips the test when no GL can be created."""
    made, unavailable = [], []

    def make(m, width=GT_IMAGE, height=GT_IMAGE):
        # A second failed GL context aborts the process (MuJoCo's fatal-error handler), so once
        # one has failed, every later test skips with the first one's reason, trying no more.
        if not unavailable:
            try:
                gl = mujoco.Renderer(m, height, width)
            except Exception as err:  # no display, no OSMesa, ...
                unavailable.append(
                    f"OSMesa/GL unavailable ({type(err).__name__}: {err}); install it with "
                    "`apt-get install -y libosmesa6` and run with MUJOCO_GL=osmesa "
                    f"(now MUJOCO_GL={os.environ.get('MUJOCO_GL')!r})")
        if unavailable:
            pytest.skip(unavailable[0])
        gl.enable_segmentation_rendering()
        made.append(gl)
        return gl

    yield make
    for gl in made:
        gl.close()


STATES_PER_SCENE = 6  # 4 scenes x 6 = 24 random states (+ 1 hand-checked each), 40 agent views


def _hand_checked_state(m):
    """agent_green at (0, -1) facing +x, everything else where the scene puts it."""
    d = mujoco.MjData(m)
    _set_agent(m, d, "agent_green", 0.0, -1.0, 0.0)
    mujoco.mj_forward(m, d)
    return d


# The quick tier checks one scene of each agent count; the full suite all four.
@pytest.mark.parametrize("scene", ["arena_same_1", pytest.param("arena_different_1", marks=pytest.mark.slow),
                                   pytest.param("arena_same_2", marks=pytest.mark.slow), "arena_different_2"])
def test_geom_ids_match_mujoco_renderer(scene, make_gl):
    m = _model(scene)
    gl = make_gl(m)
    rng = np.random.default_rng(sum(map(ord, scene)))
    states = [_hand_checked_state(m)]
    states += [_random_state(m, rng, topple=k % 2 == 0) for k in range(STATES_PER_SCENE)]
    renderer = Renderer(m, GT_IMAGE)
    batch = _stack([mjx.put_data(m, d) for d in states])
    render = jax.jit(jax.vmap(lambda data: (renderer(data)[1], *camera_poses(data, renderer.agent_body_ids))))
    gids, pos, xmat = (np.asarray(x) for x in render(batch))

    truths = {}
    for k, d in enumerate(states):
        for a, body in enumerate(renderer.agent_body_ids):
            truths[k, a] = _mujoco_geom_ids(m, d, gl, body, pos[k, a], xmat[k, a])
            # Both renderers must see more than the floor: the views are informative.
            assert len(np.unique(truths[k, a])) >= 3
    agreement = [float(np.mean(truth == gids[k, a])) for (k, a), truth in truths.items()]
    print(f"{scene}: pixel agreement with MuJoCo min {min(agreement):.4f} mean {np.mean(agreement):.4f}")
    # Measured on an Intel Xeon: min 0.9968-0.9998, mean 0.9995-1.0000 over the four scenes; the
    # bounds leave two to three times the disagreement seen, and a missing or misplaced object
    # (hundreds of pixels of a 4096-pixel view) fails them.
    assert min(agreement) >= 0.99 and np.mean(agreement) >= 0.999, agreement

    # Hand-checked: from (0, -1) facing +x, the ray through the image centre runs along y = -1
    # at eye height 0.4 and meets only the east wall; the bottom row is floor, the top row sky.
    c = GT_IMAGE // 2
    for ids in (gids[0, 0], truths[0, 0]):
        assert ids[c, c] == ids[c - 1, c - 1] == _gid(m, "wall_east")
        assert np.all(ids[-1] == _gid(m, "floor"))
        assert np.all(ids[0] == -1)


AUTHORS = (640, 480)  # the authors' camera: rendered width x height, then resized to the image


def _nearest(n, size):
    """Source pixels that nearest-pixel resizing of `size` pixels to `n` keeps: the one under
    each output pixel's centre (PIL's NEAREST, torch's "nearest-exact")."""
    return np.floor((np.arange(n) + 0.5) * size / n).astype(int)


@pytest.mark.parametrize("scene", [pytest.param("arena_same_1", marks=pytest.mark.slow), "arena_different_2"])
def test_authors_camera_matches_mujoco_at_640x480_resized(scene, make_gl):
    """The authors' camera (their code renders 640 x 480 at fovy 90 and resizes to 64 x 64): our
    64 x 64 image, ray cast directly, against MuJoCo's segmentation render of the same camera
    at 640 x 480 reduced to 64 x 64 by nearest-pixel sampling. Every view agrees on >= 99.5% of
    its pixels and the views on >= 99.9% on average (measured: see the printed line). The square camera must fail the same
    comparison: the check sees the squeeze."""
    m = _model(scene)
    gl = make_gl(m, *AUTHORS)
    rng = np.random.default_rng(sum(map(ord, scene)) + 1)
    states = [_hand_checked_state(m)] + [_random_state(m, rng, topple=k % 2 == 0) for k in range(4)]
    authors = Renderer(m, GT_IMAGE, source=AUTHORS)
    square = Renderer(m, GT_IMAGE)
    assert authors.aspect == 4 / 3 and square.aspect == 1.0
    batch = _stack([mjx.put_data(m, d) for d in states])

    def both(data):
        return authors(data)[1], square(data)[1], *camera_poses(data, authors.agent_body_ids)

    gids, gids_square, pos, xmat = (np.asarray(x) for x in jax.jit(jax.vmap(both))(batch))
    rows, cols = _nearest(GT_IMAGE, AUTHORS[1]), _nearest(GT_IMAGE, AUTHORS[0])
    agreement, square_agreement = [], []
    for k, d in enumerate(states):
        for a, body in enumerate(authors.agent_body_ids):
            full = _mujoco_geom_ids(m, d, gl, body, pos[k, a], xmat[k, a])
            assert full.shape == (AUTHORS[1], AUTHORS[0])
            truth = full[rows][:, cols]
            assert len(np.unique(truth)) >= 3  # informative views
            agreement.append(float(np.mean(truth == gids[k, a])))
            square_agreement.append(float(np.mean(truth == gids_square[k, a])))
    print(f"{scene}: authors' camera vs MuJoCo 640x480 resized: min {min(agreement):.4f} "
          f"mean {np.mean(agreement):.4f} over {len(agreement)} views; the square camera: mean "
          f"{np.mean(square_agreement):.4f}")
    # The README's claim: >= 99.9 % of pixels (measured mean 0.9998-0.9999, min 0.9990).
    assert min(agreement) >= 0.995 and np.mean(agreement) >= 0.999, agreement
    assert min(square_agreement) < 0.98 and np.mean(square_agreement) < np.mean(agreement) - 0.02, square_agreement

    # Hand-checked: from (0, -1) facing +x the image centre sees the east wall; the bottom row
    # is floor, the top row sky.
    c = GT_IMAGE // 2
    assert gids[0, 0, c, c] == _gid(m, "wall_east")
    assert np.all(gids[0, 0, -1] == _gid(m, "floor")) and np.all(gids[0, 0, 0] == -1)


def test_authors_camera_rays():
    """The authors' camera's rays, in camera coordinates: through the centres of source pixels
    10 j + 5 (of 640) and floor(7.5 i + 3.75) (of 480) for a 64 px image, the horizontal extent
    4/3 of the vertical one; the square camera's through its own pixel centres."""
    from mjx_curio.render import _pixel_rays, source_pixels

    np.testing.assert_array_equal(source_pixels(64, 640), 10 * np.arange(64) + 5)
    np.testing.assert_array_equal(source_pixels(64, 480), np.floor(7.5 * np.arange(64) + 3.75).astype(int))
    np.testing.assert_array_equal(source_pixels(64, 480), _nearest(64, 480))
    x, y, inv_dd = _pixel_rays(64, 90.0, AUTHORS)
    x, y = x.reshape(64, 64), y.reshape(64, 64)
    np.testing.assert_allclose(x[0], (4 / 3) * ((2 * (10 * np.arange(64) + 5) + 1) / 640 - 1), rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(y[:, 0], 1 - (2 * _nearest(64, 480) + 1) / 480, rtol=1e-6, atol=1e-7)
    assert np.all(x == x[:1]) and np.all(y == y[:, :1])  # rows share x, columns share y
    np.testing.assert_allclose(inv_dd, 1 / (x.ravel() ** 2 + y.ravel() ** 2 + 1), rtol=1e-6)
    xs, ys, _ = _pixel_rays(64, 90.0)
    np.testing.assert_allclose(xs[:64], (np.arange(64) + 0.5) / 32 - 1, rtol=1e-6, atol=1e-7)
    with pytest.raises(ValueError, match="source"):
        Renderer(_model("arena_same_1"), SMALL, source=(640, 0))


def test_camera_pose_convention():
    """Eye 0.2 above the body centre; MuJoCo camera frame, columns right, up, back (it looks
    along -z). Facing +x, right is -y; facing +y, right is +x. A tilted body does not tilt the
    camera."""
    m = _model("arena_same_2")
    d = mujoco.MjData(m)
    _set_agent(m, d, "agent_green", 1.0, -1.0, 0.0)
    _set_agent(m, d, "agent_purple", -2.0, 0.5, np.pi / 2)
    mujoco.mj_forward(m, d)
    ids = (m.body("agent_green").id, m.body("agent_purple").id)
    pos, xmat = (np.asarray(x) for x in camera_poses(mjx.put_data(m, d), ids))
    np.testing.assert_allclose(pos, [[1.0, -1.0, 0.4], [-2.0, 0.5, 0.4]], atol=1e-6)
    # rows below are the columns right, up, back
    np.testing.assert_allclose(xmat[0].T, [[0, -1, 0], [0, 0, 1], [-1, 0, 0]], atol=1e-6)
    np.testing.assert_allclose(xmat[1].T, [[1, 0, 0], [0, 0, 1], [0, -1, 0]], atol=1e-6)

    class Tilted:  # a body pitched by ~30 degrees while heading +x
        xpos = np.zeros((1, 3))
        xmat = np.array([[[np.cos(0.5), 0, np.sin(0.5)], [0, 1, 0], [-np.sin(0.5), 0, np.cos(0.5)]]])

    _, tilted = camera_poses(Tilted, (0,))
    np.testing.assert_allclose(np.asarray(tilted[0]), xmat[0], atol=1e-6)


# ----------------------------------------------------------------------------------------
# Batching and behaviour (16 px, arena_same_2; each jitted function compiled once)
# ----------------------------------------------------------------------------------------

BATCH = 4


@pytest.fixture(scope="module")
def arena():
    """arena_same_2, its 16 px renderer jitted alone and vmapped, and `state(...)` to pose it."""
    m = _model("arena_same_2")
    renderer = Renderer(m, SMALL)

    def state(green=(0.0, 0.0, 0.0), purple=(3.0, 3.0, 0.0), **objects):
        d = mujoco.MjData(m)
        _set_agent(m, d, "agent_green", *green)
        _set_agent(m, d, "agent_purple", *purple)
        for name, pos in objects.items():
            _set_free(m, d, name, pos)
        mujoco.mj_forward(m, d)
        return mjx.put_data(m, d)

    return m, jax.jit(renderer), jax.jit(jax.vmap(renderer)), state


def _view(arena, **placement):
    """rgb and geom ids of agent_green's view."""
    _, single, _, state = arena
    rgb, gid = single(state(**placement))
    return np.asarray(rgb[0]), np.asarray(gid[0])


def test_alone_and_in_a_vmapped_batch_render_identically(arena):
    m, single, batched, _ = arena
    rng = np.random.default_rng(7)
    datas = [mjx.put_data(m, _random_state(m, rng, topple=k == 1)) for k in range(BATCH)]
    rgb_b, gid_b = batched(_stack(datas))
    assert rgb_b.shape == (BATCH, 2, SMALL, SMALL, 3) and rgb_b.dtype == jnp.uint8
    assert gid_b.shape == (BATCH, 2, SMALL, SMALL) and gid_b.dtype == jnp.int32
    for k, data in enumerate(datas):
        rgb, gid = single(data)
        np.testing.assert_array_equal(np.asarray(rgb), np.asarray(rgb_b[k]))
        np.testing.assert_array_equal(np.asarray(gid), np.asarray(gid_b[k]))
    assert not np.array_equal(np.asarray(gid_b[0]), np.asarray(gid_b[1]))  # the states differ


# Objects parked in the room's -y half, out of a view along +x from y = 2.
PARKED = dict(pyramid=(-2.5, -2.5, 0.0), cylinder=(2.5, -2.5, 0.5), sphere=(0.0, -2.5, 0.3), disc=(-1.0, -1.5, 0.05))
OPEN_VIEW = dict(green=(-3.0, 2.0, 0.0), purple=(-3.0, -3.0, 0.0), **PARKED)  # across the empty half


def test_sky_on_top_floor_below(arena):
    m = arena[0]
    rgb, gid = _view(arena, **OPEN_VIEW)
    assert np.all(gid[0] == -1)
    assert np.all(rgb[0] == np.asarray(SKY_RGB, np.uint8))
    assert np.all(gid[-1] == _gid(m, "floor"))
    assert np.any(gid == _gid(m, "wall_east"))  # the far wall, at the horizon


def test_sphere_in_front_is_seen_and_yellow_and_turning_moves_the_view(arena):
    m = arena[0]
    placement = dict(OPEN_VIEW, green=(-1.0, 2.0, 0.0), sphere=(0.0, 2.0, 0.3))  # 1 m ahead
    rgb, gid = _view(arena, **placement)
    c = SMALL // 2
    assert np.all(gid[c - 1 : c + 1, c - 1 : c + 1] == _gid(m, "sphere"))
    r, g, b = rgb[gid == _gid(m, "sphere")].astype(float).mean(axis=0)
    assert r > 120 and g > 120 and b < 0.3 * min(r, g), (r, g, b)  # yellow

    placement["green"] = (-1.0, 2.0, np.pi / 2)  # turned left: now facing +y
    _, gid_turned = _view(arena, **placement)
    assert not np.any(gid_turned == _gid(m, "sphere"))
    assert np.any(gid_turned == _gid(m, "wall_north"))
    assert np.mean(gid_turned != gid) > 0.2


def test_agents_never_see_themselves_but_see_each_other(arena):
    m, _, batched, state = arena
    green, purple = _gid(m, "agent_green"), _gid(m, "agent_purple")
    facing = state(green=(-0.5, 0.0, 0.0), purple=(0.5, 0.0, np.pi))  # 1 m apart
    rng = np.random.default_rng(3)
    datas = [facing] + [mjx.put_data(m, _random_state(m, rng, topple=False)) for _ in range(BATCH - 1)]
    gids = np.asarray(batched(_stack(datas))[1])
    c = SMALL // 2
    assert gids[0, 0, c, c] == purple and gids[0, 1, c, c] == green
    assert not np.any(gids[:, 0] == green)
    assert not np.any(gids[:, 1] == purple)


def test_floor_shows_both_checker_colours(arena):
    m = arena[0]
    rgb, gid = _view(arena, **OPEN_VIEW)
    floor = rgb[gid == _gid(m, "floor")].astype(int)
    bluish = floor[:, 2] - floor[:, 0] > 60
    greyish = np.abs(floor[:, 2] - floor[:, 0]) < 20
    assert bluish.sum() >= 5 and greyish.sum() >= 5


def test_unsupported_visible_geom_is_refused():
    m = mujoco.MjModel.from_xml_string(
        '<mujoco><worldbody><geom type="capsule" size="0.1 0.2"/>'
        '<body name="agent_a"><geom type="box" size="0.2 0.2 0.2"/></body></worldbody></mujoco>'
    )
    with pytest.raises(NotImplementedError, match="capsule"):
        Renderer(m, SMALL)
