"""Rendering from any camera (mjx_curio/render.py: Renderer.view, overhead_camera, project_overhead).

1. Given the agents' own eye poses, hidden own bodies and the renderer's image size and field of
   view, `Renderer.view` gives exactly `Renderer.__call__`'s images.
2. The overhead camera looks straight down: every object at its start position shows at the pixel
   where `project_overhead` puts it, the room's centre is floor, and the agents are seen from
   above (their cube tops).
3. A renderer of the authors' camera (640 x 480 squeezed into the square image) renders its agents
   squeezed, and `view(..., source=None)` (video.py's map view) is the square camera's.

Plain `mujoco.MjData` states (no MJX compile): the renderer reads only poses.
"""

import types
from pathlib import Path

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

import jax  # noqa: E402
import mujoco  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from mjx_curio import render  # noqa: E402

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "arena_same_2.xml"
OBJECTS = ("pyramid", "cylinder", "sphere", "disc")


@pytest.fixture(scope="module")
def world():
    m = mujoco.MjModel.from_xml_path(str(SCENE))
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    arrays = {k: np.asarray(getattr(d, k), np.float32) for k in ("xpos", "xmat", "geom_xpos", "geom_xmat")}
    return m, d, arrays


def _data(arrays):
    return types.SimpleNamespace(**arrays)


def test_agent_cameras_match_renderer(world):
    m, _, arrays = world
    r = render.Renderer(m, image=16)
    expected = jax.jit(lambda a: r(_data(a)))(arrays)
    pos, xmat = render.camera_poses(_data(arrays), r.agent_body_ids)
    hide = r.hide_bodies([(b,) for b in r.agent_body_ids])
    got = jax.jit(lambda a, p, x: r.view(_data(a), p, x, hidden=hide))(arrays, pos, xmat)
    np.testing.assert_array_equal(np.asarray(got[0]), np.asarray(expected[0]))
    np.testing.assert_array_equal(np.asarray(got[1]), np.asarray(expected[1]))


@pytest.mark.slow
def test_overhead_view(world):
    m, d, arrays = world
    image = 96
    r = render.Renderer(m, image=16)
    pos, xmat = render.overhead_camera()
    rgb, gid = jax.jit(lambda a: r.view(_data(a), pos, xmat, image=image, fovy=render.OVERHEAD_FOVY))(arrays)
    rgb, gid = np.asarray(rgb)[0], np.asarray(gid)[0]
    assert rgb.shape == (image, image, 3) and gid.shape == (image, image)
    gname = lambda g: mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, int(g))  # noqa: E731
    # The disc lies flat near the centre top; the floor elsewhere at the centre.
    for name in OBJECTS + ("agent_green", "agent_purple"):
        g = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, name)
        top = d.geom_xpos[g] + [0.0, 0.0, 0.05]  # just above the body centre: its upper surface
        row, col = render.project_overhead(top, image=image)
        assert gname(gid[int(row), int(col)]) == name, (name, row, col, gname(gid[int(row), int(col)]))
    # Walls frame the picture: the four wall boxes are all seen, and the floor fills the middle.
    seen = {gname(g) for g in np.unique(gid) if g >= 0}
    assert {"wall_north", "wall_east", "wall_south", "wall_west", "floor"} <= seen
    assert rgb.std() > 10


@pytest.mark.slow
def test_authors_camera_renderer_and_square_views(world):
    """The agents' views of an authors'-camera renderer (source=(640, 480)) are its own rays, not
    a square camera's; `view` with source=None from the same renderer, as video.py draws its
    top-down map, is exactly a square renderer's view; and the arena builds its renderer from
    its `camera` (authors by default, aspect 4/3; square: aspect 1)."""
    from mjx_curio import arena as arena_lib

    m, _, arrays = world
    authors = render.Renderer(m, image=16, source=(640, 480))
    square = render.Renderer(m, image=16)
    pos, xmat = render.overhead_camera()
    hide = authors.hide_bodies([(b,) for b in authors.agent_body_ids])

    @jax.jit
    def views(a):  # one program for all of them
        d = _data(a)
        eye, cam = render.camera_poses(d, authors.agent_body_ids)
        return (authors(d), square(d), authors.view(d, eye, cam, hidden=hide),
                authors.view(d, pos, xmat, image=24, fovy=render.OVERHEAD_FOVY, source=None),
                square.view(d, pos, xmat, image=24, fovy=render.OVERHEAD_FOVY))

    own_a, own_s, view_a, top_a, top_s = jax.tree.map(np.asarray, views(arrays))
    assert not np.array_equal(own_a[1], own_s[1])  # the squeeze shows
    for x, y in zip(top_a, top_s):  # the map view is square whatever the agents' camera
        np.testing.assert_array_equal(x, y)
    for x, y in zip(view_a, own_a):  # by default `view` is the renderer's own camera
        np.testing.assert_array_equal(x, y)

    a = arena_lib.make("same", n_agents=2, image=8)
    assert (a.camera, a.aspect, a.fovy, a.renderer.source) == ("authors", 4 / 3, 90.0, (640, 480))
    b = arena_lib.make("same", n_agents=2, image=8, camera="square")
    assert (b.camera, b.aspect, b.renderer.source) == ("square", 1.0, None)
