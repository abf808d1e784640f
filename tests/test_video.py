"""Videos of a run replayed from a checkpoint (mjx_curio/video.py), on the session's tiny sweep.

The replay steps a run exactly as the sweep does: filmed from the start (step=0) its curiosity
rewards and actions are the sweep's own recorded metrics. Every video is read back (GIF with
Pillow; MP4 with ffprobe, imageio-ffmpeg or PyAV) for its frame count and size. With the dev
extras installed (imageio-ffmpeg, which bundles its own ffmpeg) videos are MP4.
One compiled pair of programs (acts + top-down render, learn; this sweep's config) serves every test.
"""

import pathlib
import shutil
import subprocess

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from PIL import Image  # noqa: E402

from mjx_curio import analysis as an  # noqa: E402
from mjx_curio import video  # noqa: E402
from mjx_curio.arena import ACTIONS  # noqa: E402

TOP = 32  # top-down view side in the tests
EGO = 16 * 8  # a 16 px view magnified to about 128 px
PANEL_H = video.HEADER + EGO + video.STRIP


@pytest.fixture(scope="module")
def sweep(tiny_sweep):
    return an.load(tiny_sweep)


def _frames(path, fps):
    """(frame count, (width, height)) of a GIF or MP4 file. A GIF stores a frame identical to the
    one before it (nothing moved) by lengthening that one's display time, so its frames are
    counted in display time."""
    if path.suffix == ".gif":
        with Image.open(path) as im:
            total = 0
            for i in range(im.n_frames):
                im.seek(i)
                total += im.info["duration"]
            return round(total * fps / 1000), im.size
    if shutil.which("ffprobe"):
        out = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
                              "stream=nb_read_frames,width,height", "-of", "csv=p=0", str(path)],
                             capture_output=True, text=True, check=True).stdout.strip().split(",")
        w, h, n = map(int, out)
        return n, (w, h)
    try:
        import imageio_ffmpeg
    except ImportError:
        pass
    else:
        reader = imageio_ffmpeg.read_frames(str(path))
        meta = next(reader)
        return sum(1 for _ in reader), tuple(meta["size"])
    import av  # the last encoder video.py can use

    with av.open(str(path)) as c:
        frames = list(c.decode(video=0))
        return len(frames), (frames[0].width, frames[0].height)


def test_rollout_from_start_is_the_sweep(sweep, tmp_path):
    run = 7  # UCB, seed 1
    ro = video.rollout(sweep, run, step=0, n_frames=40, top=TOP)
    assert ro.exact and ro.start_step == 0
    assert ro.frames.shape == (40, 2, 16, 16, 3) and ro.frames.dtype == np.uint8
    assert ro.top.shape == (40, TOP, TOP, 3) and ro.curiosity.shape == (40, 2)
    np.testing.assert_array_equal(ro.steps, np.arange(1, 41))
    # The sweep's first two windows (steps 1-20, 21-40) of this run, as it recorded them. The
    # learner first updates after step 20 (the replay buffer then holds a sequence), so the
    # updates after steps 20, 24, ..., 36 shape the second window: the video learns as the sweep did.
    m = sweep.metrics
    assert m["updates"][run, :2].tolist() == [1, 5]
    for w in range(2):
        part = slice(20 * w, 20 * w + 20)
        np.testing.assert_allclose(ro.curiosity[20 * w + 19], m["curiosity_sample"][run, w], rtol=1e-5)
        np.testing.assert_allclose(ro.curiosity[part].mean(axis=0), m["curiosity"][run, w], rtol=1e-5)
        counts = np.stack([np.bincount(ro.actions[part, a], minlength=7) for a in range(2)])
        np.testing.assert_array_equal(counts, m["action_counts"][run, w])
        # turning the other way than the step before, counted from the actions as they came
        acts, left, right = ro.actions[part], ACTIONS.index("rotate_left"), ACTIONS.index("rotate_right")
        back = ((acts[1:] == left) & (acts[:-1] == right)) | ((acts[1:] == right) & (acts[:-1] == left))
        np.testing.assert_array_equal(back.sum(axis=0), m["rotation_reversals"][run, w])
        np.testing.assert_allclose(ro.pose[20 * w + 19], m["agent_pose"][run, w], atol=1e-5)

    path = video.film(ro, tmp_path / "start.gif", fps=10)[0]
    n, size = _frames(path, 10)
    assert n == 40 and size == (2 * EGO + TOP + 2 * 4, PANEL_H)
    with Image.open(path) as im:
        im.seek(10)
        assert np.asarray(im.convert("RGB")).std() > 10


def test_rollout_from_checkpoints(sweep):
    newest = video.rollout(sweep, 3, step=-1, n_frames=6, top=TOP)
    assert newest.start_step == 200 and newest.exact  # the newest checkpoint keeps its replay buffer
    np.testing.assert_array_equal(newest.steps, np.arange(201, 207))
    acts, learn = video.programs(sweep.run_config(), TOP)
    assert acts._cache_size() == learn._cache_size() == 1  # compiled once for fresh and restored runs
    state, exact = video.restore_run(sweep, 3, 100)
    assert not exact  # older checkpoints do not keep the replay buffer
    raw = sweep.restore_raw(100)
    np.testing.assert_array_equal(state.frames, raw["frames"][3])
    np.testing.assert_array_equal(state.learner.vae["fc"]["kernel"], raw["learner"]["vae"]["fc"]["kernel"][3])
    assert int(state.step) == 100


def test_cli_split(sweep, tiny_sweep, tmp_path, capsys):
    out = tmp_path / "v.mp4"
    rc = video.main([f"sweep={tiny_sweep}", f"run={sweep.runs[7].name}", "step=200", "frames=6", f"out={out}",
                     "split=true", f"top={TOP}", "fps=10", "compile_cache=none"])
    assert rc == 0
    written = [pathlib.Path(s) for s in capsys.readouterr().out.split()]
    ext = ".mp4" if video.mp4_encoder() else ".gif"
    assert [p.name for p in written] == [f"v-green{ext}", f"v-purple{ext}", f"v-top{ext}"]
    for p, size in zip(written, [(EGO, PANEL_H), (EGO, PANEL_H), (TOP, video.HEADER + TOP)]):
        n, got = _frames(p, 10)
        assert n == 6
        if ext == ".gif":
            assert got == size
        else:  # H.264 pads odd sides to even
            assert got == (size[0] + size[0] % 2, size[1] + size[1] % 2)


def test_a_second_video_of_the_same_start_goes_beside_the_first(tiny_sweep, tmp_path, capsys):
    """The default name, <sweep>/videos/<run>-from<step>.<ext>, is taken: the next is -2, and the
    first video stays as it was (on a copy of the sweep, which the other tests share)."""
    copy = pathlib.Path(shutil.copytree(tiny_sweep, tmp_path / "sweep"))
    argv = [f"sweep={copy}", "run=1", "step=200", "frames=2", f"top={TOP}", "compile_cache=none"]
    assert video.main(argv) == 0
    first = pathlib.Path(capsys.readouterr().out.split()[0])
    before = first.read_bytes()
    assert video.main(argv) == 0
    second = pathlib.Path(capsys.readouterr().out.split()[0])
    ext = first.suffix
    assert first.name == f"{an.load(copy).runs[1].name}-from200{ext}" and first.parent == copy / "videos"
    assert second == first.with_name(f"{first.stem}-2{ext}") and first.read_bytes() == before


def _has_imageio_ffmpeg():
    try:
        import imageio_ffmpeg  # noqa: F401
    except ImportError:
        return False
    return True


def test_write_video(tmp_path, capsys):
    rng = np.random.default_rng(0)
    frames = rng.integers(0, 255, size=(5, 21, 30, 3), dtype=np.uint8)
    gif = video.write_video(frames, tmp_path / "a.gif", fps=5)
    assert _frames(gif, 5) == (5, (30, 21))
    mp4 = video.write_video(frames, tmp_path / "m.mp4", fps=5)
    if _has_imageio_ffmpeg():  # part of the analysis and dev extras: MP4 with no system ffmpeg
        assert video.mp4_encoder() is not None
    if video.mp4_encoder() is None:
        assert mp4 == tmp_path / "m.gif" and "no MP4 encoder" in capsys.readouterr().err
    else:
        assert mp4 == tmp_path / "m.mp4" and mp4.read_bytes()[4:8] == b"ftyp"  # an MP4 (ISO BMFF) file
        assert _frames(mp4, 5) == (5, (30, 22))
    # Nothing is overwritten: the same path again is an error, and the file stays as it was.
    before = gif.read_bytes()
    with pytest.raises(video.VideoError, match="already exists"):
        video.write_video(frames[:2], gif, fps=5)
    assert gif.read_bytes() == before


@pytest.mark.skipif(not _has_imageio_ffmpeg(), reason="imageio-ffmpeg is not installed (pip install -e '.[dev]')")
def test_mp4_without_system_ffmpeg(tmp_path, monkeypatch):
    """With no ffmpeg on PATH, imageio-ffmpeg's bundled binary writes the MP4."""
    import imageio_ffmpeg

    monkeypatch.setattr(video.shutil, "which", lambda name, *a, **k: None)
    assert video.mp4_encoder() == ("ffmpeg", imageio_ffmpeg.get_ffmpeg_exe())
    frames = np.random.default_rng(1).integers(0, 255, size=(4, 16, 24, 3), dtype=np.uint8)
    mp4 = video.write_video(frames, tmp_path / "b.mp4", fps=5)
    assert mp4 == tmp_path / "b.mp4" and mp4.read_bytes()[4:8] == b"ftyp"
    assert _frames(mp4, 5) == (4, (24, 16))
    with pytest.raises(video.VideoError, match=".mp4 or .gif"):
        video.write_video(frames, tmp_path / "a.avi")


def test_cli_errors(tiny_sweep, tmp_path, capsys):
    def err(*argv):
        try:
            rc = video.main(list(argv) + ["compile_cache=none"])
        except SystemExit as exit_:  # cli.main_guard exits on a malformed command line
            rc = exit_.code
        assert rc == 2, argv
        return capsys.readouterr().err

    assert "sweep=<directory> is required" in err()
    assert "no manifest.json" in err(f"sweep={tmp_path}")
    assert ".mp4 or .gif" in err(f"sweep={tiny_sweep}", "out=x.avi")
    assert "no checkpoint at step 150" in err(f"sweep={tiny_sweep}", "step=150")
    assert "out of range" in err(f"sweep={tiny_sweep}", "run=8")
    assert "no run named" in err(f"sweep={tiny_sweep}", "run=nope")
    assert "unknown key" in err(f"sweep={tiny_sweep}", "colour=red")
    # A file at the output path is refused before anything is compiled, and left as it was; so
    # is one at any of split's paths.
    there = tmp_path / "there.gif"
    there.write_bytes(b"not a video")
    assert "already exists" in err(f"sweep={tiny_sweep}", f"out={there}")
    (tmp_path / "v-top.gif").write_bytes(b"")
    assert "v-top.gif already exists" in err(f"sweep={tiny_sweep}", f"out={tmp_path / 'v.gif'}", "split=true")
    assert there.read_bytes() == b"not a video" and not (tmp_path / "v-green.gif").exists()
    # compile_cache naming a file is an error naming the key; a bad run makes no cache directory.
    rc = video.main([f"sweep={tiny_sweep}", f"compile_cache={there}"])
    assert rc == 2 and "compile_cache=" in capsys.readouterr().err
    rc = video.main([f"sweep={tiny_sweep}", "run=8", f"compile_cache={tmp_path / 'cache'}"])
    assert rc == 2 and "out of range" in capsys.readouterr().err and not (tmp_path / "cache").exists()
    assert video.main(["--help"]) == 0 and "top-down" in capsys.readouterr().out
