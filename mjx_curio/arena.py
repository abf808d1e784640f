"""The paper's arena in MJX: load a scene, reset, step with the 7 actions, contact flags.

    arena = make(walls="different", n_agents=2, image=64)
    state = arena.reset(jax.random.key(0))
    state = arena.step(state, jnp.array([0, 4]))     # green forward, purple rotate_left
    rgb, geom_id = arena.render(state)                # [n_agents, H, W, 3], [n_agents, H, W]

`reset`, `step` and `render` are pure functions of explicit state: jit them, vmap
them over worlds, scan them over steps. The `Arena` object itself only holds
constants (the MuJoCo model, index tables) and is hashable by identity, so it can
be closed over or passed as a static argument.

Actions (paper 3.3; docs/paper_setup.md), all in the agent's own frame and applied to every
agent at the same instant before physics advances one 1/60 s step:
forward/backward push 50 N along the heading, left/right push 50 N to the agent's
left/right, rotate_left/rotate_right turn at 5 rad/s (counter-clockwise seen from
above is left), stop zeroes the agent's linear velocity. Linear speed is capped at
2 m/s. An agent's yaw rate is 5 rad/s only while it rotates, otherwise zero, as
in the paper's code that set angular velocity directly.

Each agent sees through the authors' camera by default (`camera="authors"`): their 640 x 480
picture at a vertical field of view of 90 degrees, resized to the square image, so the view is
squeezed sideways (`Arena.aspect` = 4/3; render.py); `camera="square"` is a square 90-degree
view (aspect 1). Contacts have the friction MuJoCo would give the two geoms (`friction="geoms"`,
sliding 0.6), or MuJoCo's <pair> default of 1.0 (`friction="unit"`, sweeps made before).
"""

from __future__ import annotations

import contextlib
import dataclasses
import importlib.resources
import io
import pathlib
from typing import Any

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
from flax import struct

with contextlib.redirect_stdout(io.StringIO()):
    # mujoco.mjx prints "Failed to import warp" on stdout when the optional MuJoCo Warp (CUDA)
    # backend is absent, as it always is on a CPU; this project uses MJX's JAX backend only.
    from mujoco import mjx

from mjx_curio import render as render_lib
from mjx_curio.config import CAMERAS, FRICTIONS, MAX_JITTER, N_AGENTS, WALLS, ConfigError, check_choice, check_float, check_int


def _scenes_dir() -> pathlib.Path:
    """The directory of the MJCF scenes and their textures: the package `mjx_curio.scenes`, which
    pyproject.toml maps to the repository's top-level scenes/ directory, so any install (wheel,
    `pip install .`, editable) carries it. MuJoCo needs real files (the scenes include each other
    and name their textures by relative path): setuptools installs package data as real files;
    anything else (a zipped install) is extracted once for the process."""
    try:
        res = importlib.resources.files("mjx_curio.scenes")
    except ModuleNotFoundError:  # a source checkout put on sys.path without installing it
        return pathlib.Path(__file__).resolve().parent.parent / "scenes"
    if isinstance(res, pathlib.Path):
        return res
    return pathlib.Path(_RESOURCES.enter_context(importlib.resources.as_file(res)))


_RESOURCES = contextlib.ExitStack()
SCENES = _scenes_dir()

ACTIONS = ("forward", "backward", "left", "right", "rotate_left", "rotate_right", "stop")
OBJECTS = ("pyramid", "cylinder", "sphere", "disc")
AGENT_NAMES = ("agent_green", "agent_purple")

FORCE = 50.0  # N, forward/backward/sideways push
YAW_RATE = 5.0  # rad/s while rotating
MAX_SPEED = 2.0  # m/s, planar speed cap
FOVY = 90.0  # degrees, vertical field of view of every agent's camera
# The authors' camera renders this many pixels (width, height) and the picture is resized to the
# square image: aspect 4:3, about 106 degrees horizontally (render.py; docs/paper_setup.md).
AUTHORS_SOURCE = (640, 480)
# MuJoCo's default friction of a <pair> (sliding, sliding, torsional, rolling, rolling): what
# every contact of the scenes had before `friction="geoms"` (see `_pair_friction`).
UNIT_PAIR_FRICTION = (1.0, 1.0, 0.005, 0.0001, 0.0001)
# A contact counts as touching when its distance is below this (metres). MJX's
# box-box, box-sphere and box-capsule functions report a contact only once the
# shapes overlap (soft contacts rest slightly inside each other), so for those
# pairs touching means overlapping; the agents' round proxy against the disc
# reports true gaps, so there a cube within 5 mm of the disc counts as touching.
TOUCH_TOL = 5e-3
# Objects start at most MAX_JITTER (config.py) from the paper's layout: up to 0.4 m no two bodies
# can start overlapping (measured over 4,000 resets; at 0.5 m, 8 % of layouts overlapped).

# Per action: (force along heading, force to the left, yaw rate, stop?)
_ACTION_TABLE = np.array(
    [
        [FORCE, 0.0, 0.0, 0.0],  # forward
        [-FORCE, 0.0, 0.0, 0.0],  # backward
        [0.0, FORCE, 0.0, 0.0],  # left
        [0.0, -FORCE, 0.0, 0.0],  # right
        [0.0, 0.0, YAW_RATE, 0.0],  # rotate_left
        [0.0, 0.0, -YAW_RATE, 0.0],  # rotate_right
        [0.0, 0.0, 0.0, 1.0],  # stop
    ],
    np.float32,
)

# Start headings: green faces +x, purple faces -x, as in the authors' code (docs/paper_setup.md).
_START_YAW = (0.0, np.pi)


@struct.dataclass
class EnvState:
    """One world. `touch[i, k]`: agent i touched OBJECTS[k] during the last step;
    `touch_agent[i]`: agent i touched another agent during the last step."""

    data: mjx.Data
    step: jax.Array  # int32 scalar, agent steps since reset
    touch: jax.Array  # bool [n_agents, len(OBJECTS)]
    touch_agent: jax.Array  # bool [n_agents]


def scene_path(walls: str, n_agents: int) -> pathlib.Path:
    """The file of scene `arena_<walls>_<n_agents>.xml` (in the package mjx_curio.scenes)."""
    return SCENES / f"arena_{walls}_{n_agents}.xml"


@dataclasses.dataclass(frozen=True, eq=False)
class Arena:
    """Constants of one arena configuration. Build with `make`."""

    walls: str
    n_agents: int
    image: int
    jitter: float
    mj_model: mujoco.MjModel
    model: mjx.Model
    fovy: float
    camera: str  # "authors" (640 x 480 squeezed into the square image) or "square"
    aspect: float  # width / height of the agents' camera before the squeeze: 4/3 or 1
    friction: str  # "geoms" or "unit" (`make`)
    # numpy index tables, fixed at construction
    agent_bodies: np.ndarray  # [n_agents] body ids
    agent_geoms: np.ndarray  # [n_agents] geom ids of the cubes
    object_geoms: np.ndarray  # [len(OBJECTS)] geom ids of the visible objects
    qpos_xy: np.ndarray  # [n_agents, 2] qpos addresses of the agents' x, y slides
    qpos_yaw: np.ndarray  # [n_agents]
    dof_xy: np.ndarray  # [n_agents, 2] dof addresses of x, y
    dof_yaw: np.ndarray  # [n_agents]
    object_qpos: np.ndarray  # [len(OBJECTS)] qpos address of each free joint
    qpos0: np.ndarray  # start layout
    contact_object: np.ndarray  # [n_contacts, n_agents * len(OBJECTS)] 0/1
    contact_agent: np.ndarray  # [n_contacts, n_agents] 0/1
    renderer: Any

    def __post_init__(self):
        # reset/step always run compiled: MJX's Data carries static numpy metadata in its
        # pytree structure, and an eagerly built state gets metadata objects that differ
        # from those of a compiled step's output, so a jitted loop fed an eager reset
        # compiles twice (measured: ~35 s wasted). Inside a trace these jits just inline.
        object.__setattr__(self, "_reset", jax.jit(self._reset_impl))
        object.__setattr__(self, "_step", jax.jit(self._step_impl))

    def reset(self, key: jax.Array) -> EnvState:
        """The paper's start layout; objects moved by up to `jitter` metres in x and y
        (seeded by `key`; the key is unused when jitter is 0)."""
        return self._reset(key)

    def step(self, state: EnvState, actions: jax.Array) -> EnvState:
        """All agents act at once (actions int [n_agents], indices into ACTIONS), then
        physics advances one step."""
        return self._step(state, actions)

    def _reset_impl(self, key: jax.Array) -> EnvState:
        qpos = jnp.asarray(self.qpos0)
        if self.jitter > 0:
            offsets = jax.random.uniform(
                key, (len(OBJECTS), 2), minval=-self.jitter, maxval=self.jitter
            )
            adr = self.object_qpos[:, None] + np.arange(2)[None, :]
            qpos = qpos.at[adr].add(offsets)
        # Kinematics (poses for the renderer) rather than a full forward: mjx.step runs its own
        # forward first, and kinematics compiles in ~2 s where forward's collision and solver
        # take ~25 s on the CPU.
        data = mjx.kinematics(self.model, mjx.make_data(self.model, device=jax.local_devices()[0]).replace(qpos=qpos))
        return EnvState(
            data=data,
            step=jnp.zeros((), jnp.int32),
            touch=jnp.zeros((self.n_agents, len(OBJECTS)), bool),
            touch_agent=jnp.zeros((self.n_agents,), bool),
        )

    def _step_impl(self, state: EnvState, actions: jax.Array) -> EnvState:
        table = jnp.asarray(_ACTION_TABLE)[actions]  # [n_agents, 4]
        data = state.data
        yaw = data.qpos[self.qpos_yaw]
        cos, sin = jnp.cos(yaw), jnp.sin(yaw)
        fx = table[:, 0] * cos - table[:, 1] * sin
        fy = table[:, 0] * sin + table[:, 1] * cos
        qfrc = jnp.zeros_like(data.qfrc_applied)
        qfrc = qfrc.at[self.dof_xy].set(jnp.stack([fx, fy], -1))
        stop = table[:, 3:4] > 0
        qvel = data.qvel
        qvel = qvel.at[self.dof_xy].set(jnp.where(stop, 0.0, qvel[self.dof_xy]))
        qvel = qvel.at[self.dof_yaw].set(table[:, 2])
        data = mjx.step(self.model, data.replace(qfrc_applied=qfrc, qvel=qvel))
        v = data.qvel[self.dof_xy]
        speed = jnp.linalg.norm(v, axis=-1, keepdims=True)
        v = v * jnp.minimum(1.0, MAX_SPEED / jnp.maximum(speed, 1e-9))
        data = data.replace(qvel=data.qvel.at[self.dof_xy].set(v))
        # mjx.step leaves poses (xpos, geom_xpos, ...) as they were before integrating: refresh
        # them, or every rendered view and agent_pose would lag the physics by one step, and an
        # action's effect would show only in the view after next.
        data = mjx.kinematics(self.model, data)
        touch, touch_agent = self._touching(data)
        return EnvState(data=data, step=state.step + 1, touch=touch, touch_agent=touch_agent)

    def _touching(self, data: mjx.Data) -> tuple[jax.Array, jax.Array]:
        # The contact list has a fixed layout (one block per <pair>), so which
        # (agent, object) each slot belongs to is a constant matrix.
        close = (data._impl.contact.dist < TOUCH_TOL).astype(jnp.float32)
        touch = (close @ self.contact_object > 0).reshape(self.n_agents, len(OBJECTS))
        touch_agent = close @ self.contact_agent > 0
        return touch, touch_agent

    def render(self, state: EnvState) -> tuple[jax.Array, jax.Array]:
        """Every agent's egocentric view: rgb uint8 [n, H, W, 3], geom id int32 [n, H, W]."""
        return self.renderer(state.data)

    def agent_pose(self, state: EnvState) -> tuple[jax.Array, jax.Array]:
        """World position [n, 2] of every agent's centre and its heading (yaw) [n] in
        radians, counter-clockwise from +x."""
        return state.data.xpos[self.agent_bodies, :2], state.data.qpos[self.qpos_yaw]

    def object_pos(self, state: EnvState) -> jax.Array:
        """World position [len(OBJECTS), 3] of every object's body origin."""
        return state.data.qpos[self.object_qpos[:, None] + np.arange(3)[None, :]]


def camera(state: EnvState, agent: int) -> tuple[jax.Array, jax.Array]:
    """Agent `agent`'s camera: position [3] and orientation [3, 3] in world
    coordinates, MuJoCo's convention (looks along -z of xmat, +y up).

    Needs no Arena: every scene lists its agents' bodies last (agents_<n>.xml is
    included last; `make` checks it), so agent i is body nbody - n_agents + i."""
    n_agents = state.touch_agent.shape[0]
    n_body = state.data.xpos.shape[0]
    bodies = np.arange(n_body - n_agents, n_body)
    pos, xmat = render_lib.camera_poses(state.data, bodies)
    return pos[agent], xmat[agent]


def make(walls: str = "same", n_agents: int = 2, image: int = 64, jitter: float = 0.0,
         camera: str = "authors", friction: str = "geoms") -> Arena:
    """Load `scene_path(walls, n_agents)` (scenes/arena_<walls>_<n_agents>.xml) into MJX and build the renderer.

    walls: "same" (one texture on all walls) or "different" (one per wall);
    n_agents: 1 or 2; image: side of each agent's square view in pixels;
    jitter: objects start up to this many metres from the paper's layout (0..MAX_JITTER);
    camera: "authors" (their 640 x 480 picture at fovy 90, resized to the square image, so the
      view is squeezed sideways) or "square" (90 degrees both ways);
    friction: "geoms" (every contact pair has the friction MuJoCo gives a contact of its two
      geoms) or "unit" (MuJoCo's pair default, sliding 1.0, as sweeps before this knob).
    """
    check_choice("walls", walls, WALLS)
    check_choice("n_agents", n_agents, N_AGENTS)
    check_int("image", image, 1)
    jitter = check_float("jitter", jitter, 0.0, MAX_JITTER)
    check_choice("camera", camera, CAMERAS)
    check_choice("friction", friction, FRICTIONS)
    return _make(walls, int(n_agents), int(image), jitter, camera, friction)


_CACHE: dict = {}


def _make(walls: str, n_agents: int, image: int, jitter: float, camera: str, friction: str) -> Arena:
    # One Arena per configuration, so jitted functions closing over it are
    # traced once per process (tests build the same arena many times).
    key = (walls, n_agents, image, jitter, camera, friction)
    if key not in _CACHE:
        # Built eagerly even when first asked for inside a jit trace (run.py builds it from its
        # config there): the contact tables below need concrete values.
        with jax.ensure_compile_time_eval():
            _CACHE[key] = _build(walls, n_agents, image, jitter, camera, friction)
    return _CACHE[key]


def _pair_friction(m: mujoco.MjModel, friction: str) -> np.ndarray:
    """The friction of every <pair> [npair, 5] for `friction`.

    Every contact of the scenes is an explicit <pair> (scenes/arena_room.xml), and a pair does
    not take its geoms' friction: it has its own, MuJoCo's pair default (1, 1, 0.005, 1e-4,
    1e-4) unless the XML sets one. "geoms": what MuJoCo gives a contact it generates itself
    between the same two geoms (equal priorities: the element-wise max of their friction
    vectors (sliding, torsional, rolling), sliding and rolling used for both tangent axes);
    "unit": the pair default, the physics of sweeps made before this choice existed."""
    if friction == "unit":
        return np.broadcast_to(np.asarray(UNIT_PAIR_FRICTION), (m.npair, 5)).copy()
    g1, g2 = m.pair_geom1, m.pair_geom2
    if np.any(m.geom_priority[g1] != m.geom_priority[g2]):
        raise NotImplementedError("geoms of different priority in a <pair>: "
                                  "MuJoCo would take the higher one's friction")
    mixed = np.maximum(m.geom_friction[g1], m.geom_friction[g2])  # [npair, 3]
    return mixed[:, [0, 0, 1, 2, 2]]


def _build(walls: str, n_agents: int, image: int, jitter: float, camera: str, friction: str) -> Arena:
    m = mujoco.MjModel.from_xml_path(str(scene_path(walls, n_agents)))
    m.pair_friction[:] = _pair_friction(m, friction)
    name = lambda kind, n: mujoco.mj_name2id(m, kind, n)  # noqa: E731
    B, G, J = mujoco.mjtObj.mjOBJ_BODY, mujoco.mjtObj.mjOBJ_GEOM, mujoco.mjtObj.mjOBJ_JOINT
    agents = AGENT_NAMES[:n_agents]
    joint = lambda a, s: name(J, f"{a}_{s}")  # noqa: E731
    qpos_xy = np.array([[m.jnt_qposadr[joint(a, "x")], m.jnt_qposadr[joint(a, "y")]] for a in agents])
    dof_xy = np.array([[m.jnt_dofadr[joint(a, "x")], m.jnt_dofadr[joint(a, "y")]] for a in agents])
    qpos_yaw = np.array([m.jnt_qposadr[joint(a, "yaw")] for a in agents])
    dof_yaw = np.array([m.jnt_dofadr[joint(a, "yaw")] for a in agents])
    object_qpos = np.array([m.jnt_qposadr[name(J, o)] for o in OBJECTS])
    qpos0 = m.qpos0.copy()
    for i in range(n_agents):
        qpos0[qpos_yaw[i]] = _START_YAW[i] if n_agents == 2 else 0.0

    # On this process's own first device: MJX's default, jax.devices()[0], belongs to process 0
    # under jax.distributed, and other processes could not use arrays placed there.
    model = mjx.put_model(m, device=jax.local_devices()[0])
    contact_object, contact_agent = _contact_tables(m, model, agents)
    agent_bodies = np.array([name(B, a) for a in agents])
    if not np.array_equal(agent_bodies, np.arange(m.nbody - n_agents, m.nbody)):
        raise RuntimeError(f"{scene_path(walls, n_agents)}: the agents must be the last bodies")
    source = AUTHORS_SOURCE if camera == "authors" else None
    renderer = render_lib.Renderer(m, image=image, fovy=FOVY, agent_body_ids=tuple(agent_bodies), source=source)
    arena = Arena(
        walls=walls,
        n_agents=n_agents,
        image=image,
        jitter=jitter,
        mj_model=m,
        model=model,
        fovy=FOVY,
        camera=camera,
        aspect=renderer.aspect,
        friction=friction,
        agent_bodies=agent_bodies,
        agent_geoms=np.array([name(G, a) for a in agents]),
        object_geoms=np.array([name(G, o) for o in OBJECTS]),
        qpos_xy=qpos_xy,
        qpos_yaw=qpos_yaw,
        dof_xy=dof_xy,
        dof_yaw=dof_yaw,
        object_qpos=object_qpos,
        qpos0=qpos0,
        contact_object=contact_object,
        contact_agent=contact_agent,
        renderer=renderer,
    )
    return arena


def _contact_tables(m: mujoco.MjModel, model: mjx.Model, agents) -> tuple[np.ndarray, np.ndarray]:
    """Which agent/object each slot of MJX's fixed contact list belongs to."""
    geoms = _contact_layout(m, model)  # [n_contacts, 2]
    body_of = m.geom_bodyid
    agent_of_body = {mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, a): i for i, a in enumerate(agents)}
    object_of_body = {mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, o): k for k, o in enumerate(OBJECTS)}
    n, k_obj = len(agents), len(OBJECTS)
    obj = np.zeros((len(geoms), n * k_obj), np.float32)
    other = np.zeros((len(geoms), n), np.float32)
    for c, (g1, g2) in enumerate(geoms):
        b1, b2 = body_of[g1], body_of[g2]
        for ba, bb in ((b1, b2), (b2, b1)):
            if ba in agent_of_body:
                i = agent_of_body[ba]
                if bb in object_of_body:
                    obj[c, i * k_obj + object_of_body[bb]] = 1
                if bb in agent_of_body:
                    other[c, i] = 1
    return obj, other


def _contact_layout(m: mujoco.MjModel, model: mjx.Model) -> np.ndarray:
    """The geom pair of every slot of MJX's contact list, [n_contacts, 2].

    MJX lays the list out from static model data (mjx/_src/collision_driver.py): geom pairs
    grouped by collision function, <pair> rows before others within a group, each repeated by its
    function's contact count, groups concatenated by condim. Reading that layout costs nothing;
    running a forward pass to observe it costs a ~25 s compile. If MJX's internals change, fall
    back to observing it (tests/test_arena.py checks the two agree).
    """
    try:
        from mujoco.mjx._src import collision_driver as cd

        by_condim: dict[int, list] = {}
        for key, rows in cd._geom_groups(m).items():
            rows = np.asarray(rows)
            geom, pair = rows[:, :2], rows[:, 2]
            geom = np.concatenate([geom[pair != -1], geom[pair == -1]])
            by_condim.setdefault(int(key.condim), []).append(np.repeat(geom, cd._COLLISION_FUNC[key.types].ncon, axis=0))
        return np.concatenate([g for k in sorted(by_condim) for g in by_condim[k]])
    except (ImportError, AttributeError, KeyError):
        data = jax.jit(mjx.forward)(model, mjx.make_data(model))
        return np.asarray(data._impl.contact.geom)


def validate(walls: str, n_agents: int, image: int) -> None:
    """The arena knobs' checks alone, for programs that check all input first."""
    check_choice("walls", walls, WALLS)
    check_choice("n_agents", n_agents, N_AGENTS)
    check_int("image", image, 1)


__all__ = ["ACTIONS", "OBJECTS", "WALLS", "Arena", "EnvState", "ConfigError", "camera", "make"]
