"""Every knob of the project, as frozen dataclasses: the one source of the sweep's keys,
`--help`, the manifest and the resume check.

A knob is a dataclass field made with `knob(default, help, kind)`. Its *kind* (`Int`, `Float`,
`Choice`, `Bool`, `Text`, `ListOf`, `AutoOr`) reads the text a user types after `key=` and checks a value;
the same check runs when a dataclass is built in code (`__post_init__` calls `check_knobs`), so
a value is judged by one rule wherever it comes from. Every check raises `ConfigError` naming the
knob and what is allowed, before any work starts or any file is written.

Three dataclasses hold the knobs of a sweep, from the bottom up:
- `LearnerConfig`: the world model (VAE + MDN-RNN), the self-models and their training;
- `RunConfig`: one run's arena, replay and schedule (and its `LearnerConfig`);
- `SweepConfig`: the grid of runs and the bookkeeping around it (output, checkpoints, devices).
The sweep's command line is their knobs, flat (`cli.keys_of`); a knob named `key="..."` takes
that name on the command line (`n_agents` is typed `agents=2`). Knobs with `cli=False` are
derived from others (the learner's image size is the arena's).

Nothing here imports JAX: a command line is checked before JAX starts.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Iterable


class ConfigError(ValueError):
    """A configuration value is not allowed. The message names the knob."""


# ----------------------------------------------------------------------------- basic checks


def check_choice(name: str, value: Any, allowed: Iterable[Any]) -> Any:
    allowed = tuple(allowed)
    if value not in allowed:
        raise ConfigError(
            f"{name}={value!r} is not allowed; choose one of: {', '.join(map(repr, allowed))}"
        )
    return value


def check_int(name: str, value: Any, lo: int | None = None, hi: int | None = None) -> int:
    if isinstance(value, bool) or not hasattr(value, "__index__"):
        raise ConfigError(f"{name}={value!r} must be an integer{_bounds(lo, hi)}")
    value = int(value)
    if (lo is not None and value < lo) or (hi is not None and value > hi):
        raise ConfigError(f"{name}={value!r} is out of range; allowed: an integer{_bounds(lo, hi)}")
    return value


def check_float(name: str, value: Any, lo: float | None = None, hi: float | None = None,
                lo_open: bool = False, hi_open: bool = False) -> float:
    try:
        if isinstance(value, bool):
            raise TypeError
        value = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{name}={value!r} must be a number{_fbounds(lo, hi, lo_open, hi_open)}") from None
    bad = not math.isfinite(value)
    if lo is not None:
        bad |= value <= lo if lo_open else value < lo
    if hi is not None:
        bad |= value >= hi if hi_open else value > hi
    if bad:
        raise ConfigError(f"{name}={value!r} is out of range; allowed: a number{_fbounds(lo, hi, lo_open, hi_open)}")
    return value


def _bounds(lo, hi) -> str:
    if lo is not None and hi is not None:
        return f" in [{lo}, {hi}]"
    if lo is not None:
        return f" >= {lo}"
    if hi is not None:
        return f" <= {hi}"
    return ""


def _fbounds(lo, hi, lo_open, hi_open) -> str:
    parts = []
    if lo is not None:
        parts.append(f"{'>' if lo_open else '>='} {lo}")
    if hi is not None:
        parts.append(f"{'<' if hi_open else '<='} {hi}")
    return (" " + " and ".join(parts)) if parts else ""


# ------------------------------------------------------------------------ kinds of knob value


@dataclass(frozen=True)
class Int:
    lo: int | None = None
    hi: int | None = None
    power_of_two: bool = False

    def check(self, name: str, value: Any) -> int:
        value = check_int(name, value, self.lo, self.hi)
        if self.power_of_two and value & (value - 1):
            raise ConfigError(f"{name}={value!r} is not allowed; allowed: a power of two{_bounds(self.lo, self.hi)}")
        return value

    def parse(self, name: str, text: str) -> int:
        try:
            value = int(text.replace("_", ""))
        except ValueError:
            raise ConfigError(f"{name}={text!r} must be an integer{_bounds(self.lo, self.hi)}") from None
        return self.check(name, value)

    def show(self, value: Any) -> str:
        return str(value)


@dataclass(frozen=True)
class Float:
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False

    def check(self, name: str, value: Any) -> float:
        return check_float(name, value, self.lo, self.hi, self.lo_open, self.hi_open)

    def parse(self, name: str, text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise ConfigError(f"{name}={text!r} must be a number"
                              f"{_fbounds(self.lo, self.hi, self.lo_open, self.hi_open)}") from None
        return self.check(name, value)

    def show(self, value: Any) -> str:
        return f"{value:g}"


@dataclass(frozen=True)
class Choice:
    options: tuple

    def check(self, name: str, value: Any) -> Any:
        return check_choice(name, value, self.options)

    def parse(self, name: str, text: str) -> Any:
        for option in self.options:  # the option whose text was typed, in the option's own type
            if str(option) == text:
                return option
        return self.check(name, text)

    def show(self, value: Any) -> str:
        return str(value)


@dataclass(frozen=True)
class Bool:
    def check(self, name: str, value: Any) -> bool:
        if not isinstance(value, bool):
            raise ConfigError(f"{name}={value!r} is not allowed; choose one of: true, false")
        return value

    def parse(self, name: str, text: str) -> bool:
        t = text.lower()
        if t in ("true", "1", "yes"):
            return True
        if t in ("false", "0", "no"):
            return False
        raise ConfigError(f"{name}={text!r} is not allowed; choose one of: true, false")

    def show(self, value: Any) -> str:
        return "true" if value else "false"


@dataclass(frozen=True)
class Text:
    """Any text; `empty_ok` lets a knob's default be "" (meaning: derived, see its help)."""

    empty_ok: bool = False

    def check(self, name: str, value: Any) -> str:
        if not isinstance(value, str):
            raise ConfigError(f"{name}={value!r} must be text")
        if not value and not self.empty_ok:
            raise ConfigError(f"{name}= must not be empty")
        return value

    def parse(self, name: str, text: str) -> str:
        if not text:
            raise ConfigError(f"{name}= must not be empty")
        return self.check(name, text)

    def show(self, value: Any) -> str:
        return str(value)


@dataclass(frozen=True)
class AutoOr:
    """"auto" (the program decides; its help says how) or a value of another kind."""

    item: Any

    def check(self, name: str, value: Any) -> Any:
        return self._or_auto(self.item.check, name, value)

    def parse(self, name: str, text: str) -> Any:
        return self._or_auto(self.item.parse, name, text)

    @staticmethod
    def _or_auto(read, name: str, value: Any) -> Any:
        if value == "auto":
            return value
        try:
            return read(name, value)
        except ConfigError as err:
            raise ConfigError(f"{err}; or auto") from None

    def show(self, value: Any) -> str:
        return value if value == "auto" else self.item.show(value)


@dataclass(frozen=True)
class ListOf:
    """A comma-separated list (`policies=eps,ucb`); its value is always a non-empty tuple."""

    item: Any

    def check(self, name: str, value: Any) -> tuple:
        if isinstance(value, (str, bytes)) or not isinstance(value, Iterable):
            raise ConfigError(f"{name}={value!r} must be a comma-separated list")
        value = tuple(self.item.check(name, v) for v in value)
        if not value:
            raise ConfigError(f"{name}= must be a comma-separated list with at least one item")
        return value

    def parse(self, name: str, text: str) -> tuple:
        items = [t.strip() for t in text.split(",")]
        if not text.strip() or any(not t for t in items):
            raise ConfigError(f"{name}={text!r} must be a comma-separated list with no empty items")
        return tuple(self.item.parse(name, t) for t in items)

    def show(self, value: Any) -> str:
        return ",".join(self.item.show(v) for v in value)


_NO_LEGACY = object()


def knob(default: Any, help: str, kind: Any, *, key: str | None = None, cli: bool = True,
         resume_free: bool = False, shown: str | None = None, group: str | None = None,
         legacy: Any = _NO_LEGACY):
    """A dataclass field that is a knob.

    key: its name on the command line (default: the field's name); cli=False: derived, not a key;
    resume_free: may differ when a sweep is resumed (bookkeeping, not results); shown: how --help
    shows the default when the value itself would mislead (out's "" is a new runs/<date-time>);
    group: the --help section (default: the dataclass's); legacy: the value a sweep made before
    this knob existed ran with, when that is not the default (its manifest lacks the knob, and
    reading it as the default would misdescribe it)."""
    meta = dict(help=help, kind=kind, key=key, cli=cli, resume_free=resume_free, shown=shown, group=group)
    if legacy is not _NO_LEGACY:
        meta["legacy"] = legacy
    if isinstance(default, (list, tuple)):
        default = tuple(default)
    return dataclasses.field(default=default, metadata=meta)


def knobs(cls) -> list[dataclasses.Field]:
    """The knob fields of a config dataclass (class or instance), in declaration order."""
    return [f for f in dataclasses.fields(cls) if "kind" in f.metadata]


def key_name(f: dataclasses.Field) -> str:
    return f.metadata["key"] or f.name


def legacy_settings(cls) -> dict:
    """{field: value} of every knob of `cls` whose behaviour before the paper-faithful defaults
    differs from its default (what a sweep made before them ran with)."""
    return {f.name: f.metadata["legacy"] for f in knobs(cls) if "legacy" in f.metadata}


def check_knobs(obj) -> None:
    """Check (and normalise: lists to tuples, ints to floats where a float is asked) every knob
    of a frozen config dataclass; called by each one's __post_init__."""
    for f in knobs(obj):
        value = f.metadata["kind"].check(key_name(f), getattr(obj, f.name))
        object.__setattr__(obj, f.name, value)


# ------------------------------------------------------------------------------------ knobs

POLICY_IDS = {"eps": 0, "boltzmann": 1, "ucb": 2}
# Each policy's own setting: the sweep multiplies a policy by its own setting's list only.
POLICY_SETTING = {"eps": "eps", "boltzmann": "temperature", "ucb": "ucb_c"}
LATENT_MODES = ("stored", "reencode")
CURIOSITY_SCALES = ("mean", "sum")
Z_MODES = ("sample", "mean")
VAE_LAYERS = ("hs", "authors")
CAMERAS = ("authors", "square")
FRICTIONS = ("geoms", "unit")
WALLS = ("same", "different")
N_AGENTS = (1, 2)
MAX_JITTER = 0.4  # metres: further and objects could start inside a wall or each other
RUNS_LOOPS = ("map", "vmap")


@dataclass(frozen=True)
class LearnerConfig:
    """Sizes and training knobs of the shared world model and the self-models.

    The paper's values (and the authors' code where the paper is silent, docs/paper_setup.md)
    are the defaults. Tests shrink `image` and the network widths; the code is written for any
    `n_agents` (the paper uses 1 or 2)."""

    image: int = knob(64, "frame side in pixels (the arena's image)", Int(8, 256, power_of_two=True), cli=False)
    n_agents: int = knob(2, "agents sharing the world model (the arena's agents)", Int(1, 2), cli=False)
    latent: int = knob(32, "VAE latent size per agent (paper: 32)", Int(1))
    vae_channels: tuple = knob((32, 64, 128, 256), "VAE encoder conv widths, kernel 4 stride 2 (paper)", ListOf(Int(1)))
    # Decoder: one 4x4 stride-2 transposed conv per encoder layer (DCGAN / Ha & Schmidhuber
    # style), computed as a 2x2 conv + depth-to-space (nets.py). Widths are the encoder's
    # reversed and halved: the paper does not give the decoder, and half width keeps a VAE
    # update above 2x PyTorch's speed on the CPU (bench.py).
    dec_channels: tuple = knob((128, 64, 32, 16), "VAE decoder widths, one per encoder layer (vae_layers=hs; "
                               "authors mirrors vae_channels)", ListOf(Int(1)))
    # The layers around those convolutions (nets.VAE). "hs": Ha & Schmidhuber's, whose
    # architecture the paper names: unpadded convolutions and ReLUs. "authors": the authors'
    # code's: convolutions padded by one pixel, batch normalisation and leaky ReLUs, and their
    # wider decoder (256-128-64-32-32, then a 3x3 convolution). Batch normalisation makes the
    # learner keep running averages (LearnerState.vae_stats): the learner's VAE batch and its
    # re-encoded frames are normalised by their own statistics, the acting frames by the running
    # averages, as the authors' code does in train and eval mode.
    vae_layers: str = knob("hs", "VAE layers: hs (Ha & Schmidhuber: ReLU, no padding) or authors (padded, batch "
                           "normalisation, leaky ReLU, their decoder)", Choice(VAE_LAYERS))
    # Reconstruction = per-image SUM of squared pixel errors (pixels in [0, 1]) plus beta * KL
    # (paper eqs. 1 and 5; the authors' code: `F.mse_loss(..., reduction='sum')` + KL, beta 1).
    # kl_tolerance > 0 adds Ha & Schmidhuber's "free bits", a KL floor of kl_tolerance * latent
    # nats per image; neither the paper nor the authors' code has one, hence 0. (Sweeps made
    # before 0 became the default record their 0.5 in the manifest.)
    beta: float = knob(1.0, "weight of the VAE's KL term", Float(0.0))
    kl_tolerance: float = knob(0.0, "VAE free bits: KL floor in nats per latent dimension (0: none, as the paper)",
                               Float(0.0), legacy=0.5)
    rnn_hidden: int = knob(256, "MDN-RNN LSTM units (paper: 256)", Int(1))
    mixtures: int = knob(5, "Gaussians per latent dimension in the MDN head", Int(1))
    self_hidden: int = knob(256, "hidden width of each agent's self-model MLP", Int(1))
    lr: float = knob(1e-3, "Adam learning rate of all three models (paper)", Float(0.0, lo_open=True))
    batch: int = knob(16, "replay sequences per learner update (paper)", Int(1))
    seq_len: int = knob(16, "transitions per replay sequence (truncated BPTT length)", Int(2))
    # "reencode": every replay frame of the sample re-encoded by the current VAE (stop-gradient;
    #   a posterior sample or the mean as `z` says, as the authors' code re-encodes its training
    #   batches), so the MDN-RNN sees today's latent space: an encoder pass over
    #   batch x seq_len x n_agents frames per update (the VAE's own batch supplies the rest).
    # "stored": the MDN-RNN trains on the latents computed when the step was acted (kept in
    #   replay), by an encoder up to a replay's length of updates older. Cheaper, but measured
    #   (docs/latents.md) it leaves curiosity about 1.8 times as high over 10,000 steps: the
    #   memory predicts in an outdated latent space, and curiosity partly measures the drift.
    latents: str = knob("reencode", "MDN-RNN training latents: reencode (current VAE, as the authors) or stored (as acted)",
                        Choice(LATENT_MODES), legacy="stored")
    # Curiosity (eq. 3) is a squared distance between the next latent and the MDN-RNN's expected
    # one. The authors' code averages it over the latent dimensions (`F.mse_loss(pred, actual,
    # reduction='none').mean(dim=1)`), and the paper's curiosity figures (about 0.5-1.0), its
    # Boltzmann T = 1.5 and UCB c = 1 are on that scale; "sum" (`latent` times larger) is what
    # this code did before the knob existed. The self-models learn to predict it, so their
    # targets and outputs follow the same scale.
    curiosity: str = knob("mean", "curiosity scale: mean (authors' code) or sum of the squared errors over latent dims",
                          Choice(CURIOSITY_SCALES), legacy="sum")
    # The latent of a frame wherever the acting loop uses one (the self-models' and the
    # MDN-RNN's input, the curiosity target, the latents kept in replay) and, with
    # latents=reencode, the MDN-RNN's training inputs: "sample" draws z ~ q(z|o) = N(mu, sigma^2)
    # (reparameterised) as the paper writes it (z_t^i ~ q(z_t^i|o_t^i), section 4) and the
    # authors' code does (`vae.reparameterize` everywhere); "mean" uses z = mu, what this code
    # did before the knob existed.
    z: str = knob("sample", "latent of a frame: sample (from the VAE posterior, as the authors) or mean",
                  Choice(Z_MODES), legacy="mean")
    n_actions: int = knob(7, "actions per agent (the arena's)", Int(2), cli=False)

    def __post_init__(self):
        check_knobs(self)
        if len(self.dec_channels) != len(self.vae_channels):
            raise ConfigError(f"dec_channels={','.join(map(str, self.dec_channels))} must have one width per "
                              f"encoder layer (vae_channels={','.join(map(str, self.vae_channels))})")


@dataclass(frozen=True)
class RunConfig:
    """Everything that fixes the shapes and the program of a run. Identical for every run of a
    sweep; what varies between runs (seed, policy and its setting) lives in the run's state."""

    walls: str = knob("same", "wall textures: same (one on all walls) or different (one per wall)", Choice(WALLS))
    n_agents: int = knob(2, "cube agents per arena: 1 or 2", Int(min(N_AGENTS), max(N_AGENTS)), key="agents")
    image: int = knob(64, "camera image side in pixels: a power of two in [8, 256]", Int(8, 256, power_of_two=True))
    jitter: float = knob(0.0, f"objects start up to this many metres from the paper's layout, seeded, in [0, {MAX_JITTER}]",
                         Float(0.0, MAX_JITTER))
    # The authors render 640 x 480 at a vertical field of view of 90 degrees (about 106 degrees
    # horizontally) and resize that to 64 x 64, squeezing the view sideways. "authors": that
    # camera, ray cast directly at the image size through the pixels a nearest-pixel resize
    # keeps (render.py); "square": a square camera of 90 degrees both ways, what this code did
    # before the knob existed.
    camera: str = knob("authors", "agents' camera: authors (640x480 at fovy 90, squeezed into the square image) "
                       "or square (90 degrees both ways)", Choice(CAMERAS), legacy="square")
    # Every contact of the scenes is an explicit <pair>, and a pair does not take its geoms'
    # friction. "geoms": each pair has what MuJoCo gives a contact of its two geoms (their
    # element-wise max: sliding 0.6, scenes/arena_defaults.xml); "unit": MuJoCo's pair default
    # (sliding 1.0), what the scenes gave before this knob existed.
    friction: str = knob("geoms", "contact friction: geoms (MuJoCo's mix of the two geoms', sliding 0.6) "
                         "or unit (sliding 1.0)", Choice(FRICTIONS), legacy="unit")
    buffer: int = knob(10_000, "replay capacity in agent steps (authors' code: 10,000)", Int(3))
    update_every: int = knob(4, "agent steps between learner updates (paper: 4)", Int(1))
    metrics_every: int = knob(20, "agent steps per metrics window (the paper samples every 20)", Int(1))
    runs_loop: str = knob("map", "map: runs one by one in the program; vmap: batched", Choice(RUNS_LOOPS), cli=False)
    learner: LearnerConfig = LearnerConfig()

    def __post_init__(self):
        check_knobs(self)
        if self.metrics_every % self.update_every:
            raise ConfigError(f"metrics_every={self.metrics_every} must be a multiple of update_every="
                              f"{self.update_every}, so every metrics window holds whole learner updates")
        if self.learner.image != self.image or self.learner.n_agents != self.n_agents:
            raise ConfigError(f"learner.image/n_agents ({self.learner.image}, {self.learner.n_agents}) must equal "
                              f"image/agents ({self.image}, {self.n_agents})")
        check_int("buffer", self.buffer, self.learner.seq_len + 2)

    @property
    def arena(self):
        from mjx_curio import arena as arena_lib

        return arena_lib.make(self.walls, self.n_agents, self.image, self.jitter, camera=self.camera,
                              friction=self.friction)


_OUT, _RUN = "output and checkpoints", "execution"


@dataclass(frozen=True)
class SweepConfig:
    """The grid of runs (every policy x every seed x that policy's own setting list) and the
    bookkeeping of a sweep: where it writes, how often it checkpoints, how it runs."""

    preset: str = knob("none", "one of the paper's experiments (listed at the end), or none: its keys become the defaults", Text())
    policies: tuple = knob(("eps", "boltzmann", "ucb"), "exploration policies: eps, boltzmann, ucb",
                           ListOf(Choice(tuple(POLICY_IDS))))
    seeds: int = knob(8, "seeds per setting (first_seed .. first_seed + seeds - 1)", Int(1))
    first_seed: int = knob(0, "first seed", Int(0))
    steps: int = knob(80_000, "agent steps per run (the paper: 80,000)", Int(1), resume_free=True)
    eps: tuple = knob((0.2,), "epsilon-greedy: probability of a random action, in [0, 1] (a list sweeps it)",
                      ListOf(Float(0.0, 1.0)))
    temperature: tuple = knob((1.5,), "Boltzmann temperature > 0 (a list sweeps it, e.g. 0.5,1,1.5,2,2.5)",
                              ListOf(Float(0.0, lo_open=True)))
    ucb_c: tuple = knob((1.0,), "UCB exploration constant c > 0 (a list sweeps it)", ListOf(Float(0.0, lo_open=True)))

    out: str = knob("", "sweep directory", Text(empty_ok=True), resume_free=True, shown="runs/<date-time>", group=_OUT)
    resume: bool = knob(False, "continue the sweep in `out` from its newest complete checkpoint", Bool(),
                        resume_free=True, group=_OUT)
    checkpoint_every: int = knob(5_000, "agent steps between checkpoints (a multiple of chunk)", Int(1),
                                 resume_free=True, group=_OUT)
    keep_last: int = knob(2, "newest checkpoints kept", Int(1), resume_free=True, group=_OUT)
    keep_every: int = knob(20_000, "also keep every checkpoint at a multiple of this step (0: none)", Int(0),
                           resume_free=True, group=_OUT)
    keep_steps: tuple = knob((500, 5_000), "also checkpoint and keep at these steps (early reconstructions)",
                             ListOf(Int(1)), resume_free=True, group=_OUT)
    save_replay: bool = knob(True, "save replay buffers with checkpoints (needed for an exact resume)", Bool(),
                             resume_free=True, group=_OUT)
    # Writing a paper-size checkpoint (24 runs: about 7 GB before compression, most of it replay)
    # held a sweep on one H200 about 10 s each time, 17 times in the main job: in the background
    # the compression and writing run on the host's cores while the accelerator steps on. On a
    # CPU the same cores do both, so the steps gain nothing (measured: docs/cost_model.md), and
    # the state being written cannot be donated to the next chunk, which holds a second copy.
    async_checkpoints: str = knob("auto", "write checkpoints in the background while the sweep steps on: true, "
                                  "false (the sweep waits for each write), auto (true on a GPU or TPU, false on a CPU)",
                                  Choice(("auto", "true", "false")), resume_free=True, group=_OUT)

    chunk: int = knob(100, "agent steps per compiled chunk between host syncs", Int(1), resume_free=True, group=_RUN)
    runs_loop: str = knob("auto", "how runs share the program: map (one by one), vmap (batched), auto (map on CPU)",
                          Choice(("auto",) + RUNS_LOOPS), group=_RUN)
    distributed: str = knob("auto", "jax.distributed.initialize() first: true, false, auto (when a cluster is detected)",
                            Choice(("auto", "true", "false")), resume_free=True, group=_RUN)
    host_devices: Any = knob("auto", "CPU devices the runs are spread over: auto (the most, at most one per physical "
                             "core and one per run, whose padding runs are at most a tenth of the runs; a resumed "
                             "sweep keeps its count) or a number", AutoOr(Int(1)),
                             resume_free=True, group=_RUN)
    compile_cache: str = knob("~/.cache/mjx_curio/xla", "persistent XLA compilation cache directory, or none", Text(),
                              resume_free=True, group=_RUN)
    progress: bool = knob(True, "show a progress line", Bool(), resume_free=True, group=_RUN)

    def __post_init__(self):
        check_knobs(self)
        chunk = self.chunk
        if self.steps % chunk:
            raise ConfigError(f"steps={self.steps} must be a multiple of chunk={chunk} "
                              f"(e.g. steps={math.ceil(self.steps / chunk) * chunk})")
        if self.checkpoint_every % chunk:
            raise ConfigError(f"checkpoint_every={self.checkpoint_every} must be a multiple of chunk={chunk}")
        if self.keep_every and self.keep_every % self.checkpoint_every:
            raise ConfigError(f"keep_every={self.keep_every} must be 0 or a multiple of "
                              f"checkpoint_every={self.checkpoint_every}")
        for s in self.keep_steps:
            if s % chunk:
                raise ConfigError(f"keep_steps={s} must be a multiple of chunk={chunk}")
        if self.resume and not self.out:
            raise ConfigError("resume=true needs out=<the sweep directory to continue>")

    def check_schedule(self, run: RunConfig) -> None:
        """A chunk holds whole learner periods and whole metrics windows."""
        for name in ("update_every", "metrics_every"):
            if self.chunk % getattr(run, name):
                raise ConfigError(f"chunk={self.chunk} must be a multiple of {name}={getattr(run, name)}")


@dataclass(frozen=True)
class PolicyConfig:
    """How a controller turns predicted curiosities q[a] into an action (paper 3.2.1)."""

    policy: str = knob("eps", "exploration policy", Choice(tuple(POLICY_IDS)))
    eps: float = knob(0.2, "epsilon-greedy: probability of a uniformly random action", Float(0.0, 1.0))
    temperature: float = knob(1.5, "Boltzmann: softmax(q / T)", Float(0.0, lo_open=True))
    ucb_c: float = knob(1.0, "UCB: q + c * sqrt(ln t / N(a))", Float(0.0, lo_open=True))

    def __post_init__(self):
        check_knobs(self)

    @property
    def policy_id(self) -> int:
        return POLICY_IDS[self.policy]


# The sweep's knobs, in the order --help lists them, and how the flat key=value dict a command
# line gives becomes the three dataclasses.
SWEEP_CLASSES = (SweepConfig, RunConfig, LearnerConfig)


def sweep_configs(values: dict) -> tuple[SweepConfig, RunConfig]:
    """(SweepConfig, RunConfig with its LearnerConfig) from a flat dict of key values. Missing
    keys take their defaults; `runs_loop=auto` is resolved to `map` here (`execute` resolves it
    by device). Raises ConfigError naming the first bad knob."""
    def pick(cls, **extra):
        kw = {f.name: values[key_name(f)] for f in knobs(cls) if f.metadata["cli"] and key_name(f) in values}
        return cls(**kw, **extra)

    sweep = pick(SweepConfig)
    n_agents = values.get("agents", RunConfig.n_agents)
    image = values.get("image", RunConfig.image)
    check_int("image", image)
    learner = pick(LearnerConfig, image=image, n_agents=n_agents)
    loop = sweep.runs_loop if sweep.runs_loop != "auto" else "map"
    run = pick(RunConfig, learner=learner, runs_loop=loop)
    sweep.check_schedule(run)
    return sweep, run
