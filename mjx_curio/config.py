"""Frozen configuration dataclasses and the checks every knob goes through.

Every check raises `ConfigError` naming the knob and what is allowed, so a bad
value stops a program before any work starts or any file is written.
"""

from __future__ import annotations

import math
from typing import Any, Iterable


class ConfigError(ValueError):
    """A configuration value is not allowed. The message names the knob."""


def check_choice(name: str, value: Any, allowed: Iterable[Any]) -> Any:
    allowed = tuple(allowed)
    if value not in allowed:
        raise ConfigError(
            f"{name}={value!r} is not allowed; choose one of: {', '.join(map(repr, allowed))}"
        )
    return value


def check_int(name: str, value: Any, lo: int | None = None, hi: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, (int,)) and not (
        hasattr(value, "__index__")
    ):
        raise ConfigError(f"{name}={value!r} must be an integer{_bounds(lo, hi)}")
    value = int(value)
    if (lo is not None and value < lo) or (hi is not None and value > hi):
        raise ConfigError(f"{name}={value!r} is out of range; allowed: an integer{_bounds(lo, hi)}")
    return value


def check_float(
    name: str,
    value: Any,
    lo: float | None = None,
    hi: float | None = None,
    lo_open: bool = False,
    hi_open: bool = False,
) -> float:
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
        raise ConfigError(
            f"{name}={value!r} is out of range; allowed: a number{_fbounds(lo, hi, lo_open, hi_open)}"
        )
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


# --------------------------------------------------------------------------
# The learning agent: world model (VAE + MDN-RNN), self-models, policies.
# --------------------------------------------------------------------------

from dataclasses import dataclass  # noqa: E402  (appended section)

LATENT_MODES = ("stored", "reencode")
POLICY_IDS = {"eps": 0, "boltzmann": 1, "ucb": 2}


@dataclass(frozen=True)
class LearnerConfig:
    """Sizes and training knobs of the shared world model and the self-models.

    Paper / FACTS.md values are the defaults. Tests shrink `image` and the
    network widths; the code is written for any `n_agents` (the paper uses 1 or 2).
    """

    image: int = 64  # square frames, a power of two in [8, 256]
    n_agents: int = 2
    latent: int = 32  # z size per agent
    vae_channels: tuple = (32, 64, 128, 256)  # encoder convs, kernel 4, stride 2 (paper)
    # Decoder: one 4x4 stride-2 transposed conv per encoder layer (DCGAN / H&S style),
    # computed as a 2x2 conv + depth-to-space (see nets.py). Widths are the encoder's
    # reversed and halved: the decoder is not specified by the paper and half width
    # keeps a VAE update above 2x PyTorch's speed on the CPU (bench.py).
    dec_channels: tuple = (128, 64, 32, 16)
    # Ha & Schmidhuber's VAE: reconstruction = per-image SUM of squared pixel errors
    # (pixels in [0, 1]), KL weight 1 (beta = 1) with "free bits": the KL term is
    # max(KL, kl_tolerance * latent), kl_tolerance = 0.5, so the encoder is not pushed
    # below half a nat per latent dimension (prevents posterior collapse).
    beta: float = 1.0
    kl_tolerance: float = 0.5
    rnn_hidden: int = 256  # LSTM units (paper)
    mixtures: int = 5  # Gaussians per latent dimension in the MDN head (H&S)
    self_hidden: int = 256  # hidden width of each agent's self-model MLP
    lr: float = 1e-3  # Adam, all three models (paper)
    batch: int = 16  # sequences per update (paper)
    seq_len: int = 16  # transitions per sequence (truncated BPTT length)
    # "stored": the MDN-RNN trains on the latents the acting loop computed when the step
    #   was taken (kept in replay). Cheap: the only encoder work per update is the VAE's
    #   own batch (batch x n_agents frames).
    # "reencode": re-encode every replay frame of the sample with the current VAE (mean,
    #   stop-gradient) so the MDN-RNN always sees today's latent space. Costs an encoder
    #   forward over batch x (seq_len + 1) x n_agents frames per update (544 images at
    #   the defaults, 17x the VAE batch): measured 342 ms against 76 ms per update at
    #   64 px on the 2-core CPU (bench.py).
    latents: str = "stored"
    n_actions: int = 7

    def __post_init__(self):
        check_int("image", self.image, 8, 256)
        if self.image & (self.image - 1):
            raise ConfigError(f"image={self.image!r} is not allowed; allowed: a power of two in [8, 256]")
        check_int("n_agents", self.n_agents, 1, 2)
        check_int("latent", self.latent, 1)
        for name in ("vae_channels", "dec_channels"):
            chans = getattr(self, name)
            if not isinstance(chans, (tuple, list)) or not chans:
                raise ConfigError(f"{name}={chans!r} must be a non-empty tuple of positive integers")
            for c in chans:
                check_int(name, c, 1)
            object.__setattr__(self, name, tuple(int(c) for c in chans))
        if len(self.dec_channels) != len(self.vae_channels):
            raise ConfigError(
                f"dec_channels={self.dec_channels!r} must have one width per encoder layer "
                f"(vae_channels={self.vae_channels!r})"
            )
        check_float("beta", self.beta, 0.0)
        check_float("kl_tolerance", self.kl_tolerance, 0.0)
        check_int("rnn_hidden", self.rnn_hidden, 1)
        check_int("mixtures", self.mixtures, 1)
        check_int("self_hidden", self.self_hidden, 1)
        check_float("lr", self.lr, 0.0, lo_open=True)
        check_int("batch", self.batch, 1)
        check_int("seq_len", self.seq_len, 2)
        check_choice("latents", self.latents, LATENT_MODES)
        check_int("n_actions", self.n_actions, 2)


@dataclass(frozen=True)
class PolicyConfig:
    """How a controller turns predicted curiosities q[a] into an action (paper 3.2.1)."""

    policy: str = "eps"  # "eps" | "boltzmann" | "ucb"
    eps: float = 0.2  # epsilon-greedy: probability of a uniformly random action
    temperature: float = 1.5  # Boltzmann: softmax(q / T)
    ucb_c: float = 1.0  # UCB: q + c * sqrt(ln t / N(a))

    def __post_init__(self):
        check_choice("policy", self.policy, POLICY_IDS)
        check_float("eps", self.eps, 0.0, 1.0)
        check_float("temperature", self.temperature, 0.0, lo_open=True)
        check_float("ucb_c", self.ucb_c, 0.0, lo_open=True)

    @property
    def policy_id(self) -> int:
        return POLICY_IDS[self.policy]
