"""python -m mjx_curio.video sweep=<dir> run=<index> step=<checkpoint> frames=<n> out=<file>

Replays one run of a sweep from one of its checkpoints and films it: every agent's egocentric
view (low resolution, as the agents see it, magnified with square pixels) with its curiosity
reward drawn underneath (the value, and a sparkline of the recent rewards), and a top-down view
of the arena from a camera above its centre, rendered by the project's own ray caster
(render.Renderer.view), so it works wherever JAX does.

The run is restored whole from the checkpoint (networks, optimiser states, memory, arena,
RNG key, and the replay buffer when the checkpoint kept it) and stepped exactly as the sweep
steps it: `update_every` calls of run.act, then run.learn, and again. From the newest checkpoint
(whose replay buffer is kept) the video therefore shows what the sweep itself did next, had it
gone on; from a checkpoint without its replay buffer (older ones: the sweep keeps only the
newest) learning restarts from an empty buffer, so the run departs from the sweep's after
`seq_len` steps. `step=0` starts the run afresh, exactly as the sweep did (no checkpoint
needed): the video then shows the sweep's own first steps. `learn=false` freezes the networks.

Output: MP4 (H.264) when an encoder is available: an `ffmpeg` on PATH, the one bundled with the
`imageio-ffmpeg` package, or PyAV (`av`); else an animated GIF (Pillow, which comes with
matplotlib). `split=true` writes one file per agent and one for the top-down view instead of
one side-by-side video.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import math
import pathlib
import shutil
import subprocess
import sys
from typing import Sequence

import numpy as np

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)
from mjx_curio import cli
from mjx_curio.cli import Key, as_bool, as_int, as_str

PROG = "mjx_curio.video"
SUMMARY = ("Film one run of a sweep from a checkpoint: egocentric views with their curiosity reward, and a "
           "top-down view of the arena (MP4 when an encoder is available, else GIF).")

KEYS = (
    Key("sweep", "", "sweep directory", as_str, shown="required"),
    Key("run", "0", "run index (the manifest's order) or run name", as_str),
    Key("step", -1, "checkpoint to start from: -1 the newest, 0 the run's start (no checkpoint needed)", as_int(-1)),
    Key("frames", 300, "agent steps to film, one video frame each", as_int(1)),
    Key("out", "", "output file, .mp4 or .gif (.gif without an MP4 encoder); one that exists is refused", as_str,
        shown="<sweep>/videos/<run>-from<step>.mp4"),
    Key("fps", 15, "video frames per second (the arena runs 60 steps per simulated second)", as_int(1, 100)),
    Key("scale", 0, "magnification of the egocentric views (0: to about 128 px)", as_int(0, 64)),
    Key("top", 192, "side of the top-down view in pixels (0: no top-down view)", as_int(0, 2048)),
    Key("split", False, "one file per agent and one for the top-down view instead of one side-by-side video", as_bool),
    Key("learn", True, "train the networks while filming, as the sweep does (false: frozen at the checkpoint)", as_bool),
    Key("compile_cache", "~/.cache/mjx_curio/xla", "persistent XLA compilation cache directory, or none", as_str),
)

BACKGROUND = (24, 24, 28)
STRIP = 44  # px of reward drawing under each egocentric view
HEADER = 14  # px of text above each panel
AGENT_RGB = ((30, 158, 60), (138, 63, 176))


class VideoError(ValueError):
    """A video cannot be made as asked; the message says why."""


# ------------------------------------------------------------------------------- the rollout


@dataclasses.dataclass
class Rollout:
    """What filming a run recorded, one entry per agent step."""

    run_name: str
    start_step: int  # the checkpoint's step
    exact: bool  # the replay buffer was restored (or step 0): the run continues as the sweep's would
    agent_names: list
    frames: np.ndarray  # uint8 [T, agents, H, W, 3]: every agent's view after each step
    curiosity: np.ndarray  # float [T, agents]: the curiosity reward of each step (eq. 3)
    actions: np.ndarray  # int [T, agents]
    pose: np.ndarray  # float [T, agents, 3]: x, y (m) and heading (rad) after each step
    steps: np.ndarray  # int [T]: the run's step count after each step
    top: np.ndarray | None  # uint8 [T, S, S, 3]: the top-down view after each step


def _abstract_states(cfg, n_total: int):
    """The sweep state's shapes (leading runs axis of n_total), on this process's first device."""
    import jax
    import jax.numpy as jnp
    from jax.sharding import SingleDeviceSharding

    from mjx_curio import policies
    from mjx_curio import run as run_lib

    def one():
        return run_lib.init_run(cfg, jnp.zeros((2,), jnp.uint32), policies.make_policy_params(0, 0.2, 1.0, 1.0))

    shapes = jax.eval_shape(one)
    sharding = SingleDeviceSharding(jax.local_devices()[0])
    return jax.tree.map(lambda s: jax.ShapeDtypeStruct((n_total,) + s.shape, s.dtype, sharding=sharding), shapes)


def restore_run(sweep, run, step: int):
    """Run `run` of `sweep` (an analysis.Sweep) as its `run.RunState` at checkpoint `step`
    (0: freshly initialised, as the sweep starts it). Returns (state, exact): exact is False when
    the checkpoint did not keep the replay buffer (it comes back empty). The checkpoint is
    restored whole (every run, replay buffers included) and one run kept, so this needs memory
    for the whole checkpoint (about 265 MB a run at 64 px with a 10,000-step buffer)."""
    import jax

    from mjx_curio import policies
    from mjx_curio import run as run_lib
    from mjx_curio.config import POLICY_IDS

    r = sweep.run(run)
    cfg = sweep.run_config()
    if step == 0:
        spec = sweep.run_specs()[r.index]
        pol = policies.make_policy_params(POLICY_IDS[spec.policy], spec.eps, spec.temperature, spec.ucb_c)
        state = jax.jit(run_lib.init_run, static_argnums=0)(cfg, run_lib.key_for_seed(spec.seed), pol)
        return _host(state), True
    from mjx_curio import analysis

    step = sweep.check_step(step)
    n_total = sweep.n_runs + int(sweep.manifest.get("padded_runs", 0))
    with analysis._quiet_orbax():
        states = sweep.checkpoints().restore(step, _abstract_states(cfg, n_total), with_replay=True)
        exact = step in sweep.replay_steps()
    state = jax.tree.map(lambda x: x[r.index], states)
    del states
    return _host(state), exact


def _host(state):
    """The state as uncommitted device arrays made from NumPy: a fresh and a restored state then
    look alike to jit (same dtypes, no weak types, no fixed placement), and like the programs'
    own outputs, so one compiled program serves them all."""
    import jax

    return jax.tree.map(lambda x: jax.device_put(np.asarray(x)), state)


_PROGRAMS: dict = {}


def programs(cfg, top: int):
    """The two compiled pieces of a learner period as the sweep runs it: `acts(state)` takes
    `update_every` agent steps (run.act), also returning each step's views, rewards, actions,
    poses and top-down image; `learn(state)` is one learner update (run.learn). Two programs
    rather than one compile faster (measured 57 s against 67 s on the 2-core CPU, 2 agents, 16
    px) and reproduce the sweep's rewards and actions (tests/test_video.py). Cached per config
    and top-down size."""
    key = (cfg, top)
    if key in _PROGRAMS:
        return _PROGRAMS[key]
    import jax
    from jax import lax

    from mjx_curio import render
    from mjx_curio import run as run_lib

    arena = cfg.arena
    cam_pos, cam_xmat = render.overhead_camera()

    def one(s, _):
        s, m = run_lib.act(cfg, s)
        out = {"frames": s.frames, "curiosity": m["curiosity"], "actions": m["action"], "pose": m["agent_pose"],
               "steps": s.step}
        if top:
            rgb, _ = arena.renderer.view(s.env.data, cam_pos, cam_xmat, image=top, fovy=render.OVERHEAD_FOVY,
                                         source=None)  # a square map view, whatever the agents' camera
            out["top"] = rgb[0]
        return s, out

    acts = jax.jit(lambda s: lax.scan(one, s, None, length=cfg.update_every))
    learn = jax.jit(lambda s: run_lib.learn(cfg, s)[0])
    _PROGRAMS[key] = (acts, learn)
    return acts, learn


def rollout(sweep, run=0, step: int = -1, n_frames: int = 300, top: int = 192, learn: bool = True) -> Rollout:
    """Restore run `run` at checkpoint `step` (-1: the newest; 0: the start) and step it
    `n_frames` times as the sweep does, recording what `Rollout` lists."""
    import jax

    r = sweep.run(run)
    if step < 0:
        steps = sweep.checkpoint_steps()
        if not steps:
            raise VideoError(f"{sweep.path} has no checkpoints (use step=0 to film the run from its start)")
        step = steps[-1]
    state, exact = restore_run(sweep, r.index, step)
    if bool(state.halted):
        print(f"note: run {r.name} is halted at step {int(state.halted_step)} (a non-finite loss or physics state); it does not move",
              file=sys.stderr)
    cfg = sweep.run_config()
    acts, learn_fn = programs(cfg, int(top))
    outs = []
    for _ in range(math.ceil(n_frames / cfg.update_every)):
        state, out = acts(state)
        if learn:
            state = learn_fn(state)
        outs.append(jax.device_get(out))
    cat = {k: np.concatenate([o[k] for o in outs])[:n_frames] for k in outs[0]}
    return Rollout(r.name, int(step), exact and bool(learn), list(sweep.agent_names), cat["frames"],
                   cat["curiosity"].astype(np.float32), cat["actions"], cat["pose"], cat["steps"], cat.get("top"))


# ------------------------------------------------------------------------------- drawing


def _font():
    from PIL import ImageFont

    return ImageFont.load_default()


def _upscale(img: np.ndarray, k: int) -> np.ndarray:
    return np.repeat(np.repeat(img, k, axis=0), k, axis=1) if k > 1 else img


def _text(img: np.ndarray, xy, text: str, fill=(235, 235, 235)) -> np.ndarray:
    from PIL import Image, ImageDraw

    im = Image.fromarray(img)
    ImageDraw.Draw(im).text(xy, text, fill=fill, font=_font())
    return np.asarray(im)


def agent_panels(ro: Rollout, scale: int = 0) -> list[np.ndarray]:
    """Per agent, uint8 [T, h, w, 3]: a header (agent, step), the view magnified `scale` times
    (0: to about 128 px) and under it the curiosity reward: its value and a sparkline of the
    last steps (height: reward / the clip's 99th percentile, clipped)."""
    from PIL import Image, ImageDraw

    T, n, H, W, _ = ro.frames.shape
    k = scale or max(1, round(128 / W))
    w = W * k
    r = np.nan_to_num(ro.curiosity.astype(float))
    top_r = float(np.percentile(r, 99)) if r.size else 1.0
    top_r = top_r if top_r > 0 else 1.0
    hist = w - 8  # steps shown in the sparkline, one pixel each
    font = _font()
    panels = []
    for a in range(n):
        name = ro.agent_names[a] if n > 1 else "agent"
        colour = AGENT_RGB[a % 2] if n > 1 else (70, 130, 230)
        out = np.empty((T, HEADER + W * k + STRIP, w, 3), np.uint8)
        for t in range(T):
            im = Image.new("RGB", (w, HEADER + W * k + STRIP), BACKGROUND)
            im.paste(Image.fromarray(_upscale(ro.frames[t, a], k)), (0, HEADER))
            d = ImageDraw.Draw(im)
            d.text((2, 1), f"{name}  step {int(ro.steps[t]):,}", fill=(235, 235, 235), font=font)
            y0 = HEADER + W * k
            d.text((2, y0 + 1), f"curiosity {r[t, a]:.3f}", fill=(235, 235, 235), font=font)
            # Sparkline of the last `hist` rewards, the newest at the right.
            base, height = y0 + STRIP - 3, STRIP - 17
            seg = r[max(0, t + 1 - hist): t + 1, a]
            xs = w - 4 - (len(seg) - 1) + np.arange(len(seg))
            ys = base - np.clip(seg / top_r, 0, 1) * height
            d.line([(4, base), (w - 4, base)], fill=(90, 90, 90))
            if len(seg) > 1:
                d.line(list(zip(xs.tolist(), ys.tolist())), fill=colour, width=1)
            d.ellipse([xs[-1] - 2, ys[-1] - 2, xs[-1] + 2, ys[-1] + 2], fill=(255, 255, 255))
            out[t] = np.asarray(im)
        panels.append(out)
    return panels


def top_panel(ro: Rollout) -> np.ndarray | None:
    """uint8 [T, HEADER + S, S, 3]: the top-down view with a header and a short white line
    pointing from each agent's front face along its heading."""
    if ro.top is None:
        return None
    from PIL import Image, ImageDraw

    from mjx_curio import render

    T, S = ro.top.shape[:2]
    out = np.empty((T, HEADER + S, S, 3), np.uint8)
    font = _font()
    for t in range(T):
        im = Image.new("RGB", (S, HEADER + S), BACKGROUND)
        im.paste(Image.fromarray(ro.top[t]), (0, HEADER))
        d = ImageDraw.Draw(im)
        d.text((2, 1), f"top-down  step {int(ro.steps[t]):,}", fill=(235, 235, 235), font=font)
        for a in range(ro.pose.shape[1]):
            x, y, yaw = ro.pose[t, a]
            c, sn = math.cos(yaw), math.sin(yaw)  # from the cube's front face outwards
            p0 = render.project_overhead([x + 0.2 * c, y + 0.2 * sn, 0.4], image=S)
            p1 = render.project_overhead([x + 0.6 * c, y + 0.6 * sn, 0.4], image=S)
            d.line([(p0[1], HEADER + p0[0]), (p1[1], HEADER + p1[0])], fill=(255, 255, 255), width=2)
        out[t] = np.asarray(im)
    return out


def side_by_side(panels: Sequence[np.ndarray], gap: int = 4) -> np.ndarray:
    """Panels [T, h_i, w_i, 3] next to each other, top-aligned, on the background colour."""
    T = panels[0].shape[0]
    h = max(p.shape[1] for p in panels)
    w = sum(p.shape[2] for p in panels) + gap * (len(panels) - 1)
    out = np.empty((T, h, w, 3), np.uint8)
    out[...] = BACKGROUND
    x = 0
    for p in panels:
        out[:, : p.shape[1], x : x + p.shape[2]] = p
        x += p.shape[2] + gap
    return out


# ------------------------------------------------------------------------------- writing


def mp4_encoder() -> tuple[str, str] | None:
    """("ffmpeg", path) for an ffmpeg executable (PATH, or imageio-ffmpeg's), ("av", "") for
    PyAV, or None when MP4 cannot be written here."""
    exe = shutil.which("ffmpeg")
    if exe:
        return "ffmpeg", exe
    if importlib.util.find_spec("imageio_ffmpeg") is not None:
        try:
            import imageio_ffmpeg

            return "ffmpeg", imageio_ffmpeg.get_ffmpeg_exe()
        except Exception:  # noqa: BLE001  (a broken install: try the next)
            pass
    if importlib.util.find_spec("av") is not None:
        return "av", ""
    return None


def write_video(frames: np.ndarray, path: str | pathlib.Path, fps: int = 15) -> pathlib.Path:
    """Write uint8 frames [T, H, W, 3] to `path` (.mp4 or .gif). An .mp4 without an encoder is
    written as .gif next to it (same name), with a note on stderr. Returns the path written. A
    file already there is a VideoError: nothing is overwritten."""
    target = written_path(path)
    refuse_existing([target])
    target.parent.mkdir(parents=True, exist_ok=True)
    frames = np.asarray(frames, np.uint8)
    if target.suffix.lower() == ".mp4":
        _write_mp4(frames, target, fps, mp4_encoder())
        return target
    if target.suffix.lower() != pathlib.Path(path).suffix.lower():
        print(f"note: no MP4 encoder (ffmpeg, imageio-ffmpeg or PyAV) is installed; writing {target}", file=sys.stderr)
    _write_gif(frames, target, fps)
    return target


def written_path(path: str | pathlib.Path) -> pathlib.Path:
    """Where `write_video(..., path)` writes: `path`, or for an .mp4 with no encoder here the .gif
    beside it. Any other ending is a VideoError."""
    path = pathlib.Path(path)
    ext = path.suffix.lower()
    if ext not in (".mp4", ".gif"):
        raise VideoError(f"out={path}: the file must end in .mp4 or .gif")
    return path.with_suffix(".gif") if ext == ".mp4" and mp4_encoder() is None else path


def video_paths(out: str | pathlib.Path, split: bool, agent_names: Sequence[str], top: bool) -> list[pathlib.Path]:
    """The files `film` writes for `out`: `out` itself, or with `split` one per agent
    (`<out>-<agent>.<ext>`, `<out>-agent.<ext>` for a lone agent) and `<out>-top.<ext>` with a
    top-down view."""
    out = pathlib.Path(out)
    if not split:
        return [out]
    names = list(agent_names) if len(agent_names) > 1 else ["agent"]
    return [out.with_name(f"{out.stem}-{name}{out.suffix}") for name in names + (["top"] if top else [])]


def refuse_existing(paths: Sequence[pathlib.Path]) -> None:
    """A VideoError if any of `paths` exists: a video never replaces a file."""
    there = [str(p) for p in paths if p.exists()]
    if there:
        raise VideoError(f"{', '.join(there)} already exist{'s' if len(there) == 1 else ''}; nothing is "
                         "overwritten: choose another out=, or move the file away")


def _write_gif(frames: np.ndarray, path: pathlib.Path, fps: int) -> None:
    """Pillow stores a frame identical to the one before it as a longer display time of that
    one, so a GIF may hold fewer frames than given while playing for the same time."""
    from PIL import Image

    ims = [Image.fromarray(f) for f in frames]
    ims[0].save(path, save_all=True, append_images=ims[1:], duration=max(20, round(1000 / fps)), loop=0,
                optimize=False, disposal=1)


def _write_mp4(frames: np.ndarray, path: pathlib.Path, fps: int, enc: tuple[str, str]) -> None:
    T, H, W, _ = frames.shape
    if H % 2 or W % 2:  # H.264 in yuv420p needs even sides
        frames = np.pad(frames, ((0, 0), (0, H % 2), (0, W % 2), (0, 0)), mode="edge")
        T, H, W, _ = frames.shape
    kind, exe = enc
    if kind == "ffmpeg":
        cmd = [exe, "-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", f"{W}x{H}", "-r", str(fps),
               "-i", "-", "-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", "18", str(path)]
        proc = subprocess.run(cmd, input=frames.tobytes(), capture_output=True)
        if proc.returncode != 0:
            raise VideoError(f"ffmpeg failed writing {path}: {proc.stderr.decode(errors='replace')[-2000:]}")
        return
    import av

    with av.open(str(path), mode="w") as container:
        stream = container.add_stream("libx264", rate=fps)
        stream.width, stream.height, stream.pix_fmt = W, H, "yuv420p"
        for f in frames:
            for packet in stream.encode(av.VideoFrame.from_ndarray(f, format="rgb24")):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)


def film(ro: Rollout, out: str | pathlib.Path, fps: int = 15, scale: int = 0, split: bool = False) -> list[pathlib.Path]:
    """Draw a rollout and write it: one side-by-side video (every agent, then the top-down view),
    or with `split` one file per agent (`<out>-<agent>.<ext>`) and one for the top-down view
    (`<out>-top.<ext>`). Returns the paths written."""
    paths = video_paths(out, split, ro.agent_names, ro.top is not None)
    refuse_existing([written_path(p) for p in paths])  # before any is written
    agents = agent_panels(ro, scale)
    top = top_panel(ro)
    panels = [side_by_side(agents + ([top] if top is not None else []))] if not split else \
        agents + ([top] if top is not None else [])
    return [write_video(p, path, fps) for p, path in zip(panels, paths)]


def make_video(sweep_dir, run="0", step: int = -1, frames: int = 300, out: str = "", fps: int = 15, scale: int = 0,
               top: int = 192, split: bool = False, learn: bool = True,
               compile_cache: str | None = None) -> list[pathlib.Path]:
    """Everything `python -m mjx_curio.video` does, as a function. Returns the paths written.
    Every check (the run, the step, files already at the output paths, `compile_cache`: a
    ConfigError) comes before anything is compiled or written; `compile_cache` None leaves JAX's
    cache setting as it is."""
    from mjx_curio import analysis, distributed

    sweep = analysis.load(sweep_dir)
    r = sweep.run(int(run) if str(run).lstrip("-").isdigit() else str(run))
    if step > 0:
        sweep.check_step(step)
    elif step < 0:
        steps = sweep.checkpoint_steps()
        if not steps:
            raise VideoError(f"{sweep.path} has no checkpoints (use step=0 to film the run from its start)")
        step = steps[-1]
    if not out:  # the first free name: a second video of the same start goes beside the first
        ext = ".mp4" if mp4_encoder() else ".gif"
        stem, n = f"{r.name}-from{step}", 1
        out = sweep.path / "videos" / f"{stem}{ext}"
        while any(written_path(p).exists() for p in video_paths(out, split, sweep.agent_names, top > 0)):
            n += 1
            out = out.with_name(f"{stem}-{n}{ext}")
    refuse_existing([written_path(p) for p in video_paths(out, split, sweep.agent_names, top > 0)])
    cache = distributed.compile_cache_dir(compile_cache) if compile_cache is not None else None
    distributed.use_compile_cache(cache)
    ro = rollout(sweep, r.index, step, frames, top, learn)
    return film(ro, out, fps, scale, split)


def main(argv=None) -> int:
    v = cli.main_guard(argv, PROG, SUMMARY, KEYS)
    if v is None:
        return 0
    if not v["sweep"]:
        print("error: sweep=<directory> is required", file=sys.stderr)
        return 2
    if v["out"] and pathlib.Path(v["out"]).suffix.lower() not in (".mp4", ".gif"):
        print(f"error: out={v['out']}: the file must end in .mp4 or .gif", file=sys.stderr)
        return 2
    from mjx_curio import analysis
    from mjx_curio.config import ConfigError

    try:
        paths = make_video(v["sweep"], v["run"], v["step"], v["frames"], v["out"], v["fps"], v["scale"], v["top"],
                           v["split"], v["learn"], v["compile_cache"])
    except (analysis.SweepError, VideoError, ConfigError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    for p in paths:
        print(p)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
