"""key=value command lines, shared by `python -m mjx_curio.sweep` and `python -m mjx_curio.bench`.

Each program declares its keys as `Key`s: a name, a default, a one-line help and a parser that
turns the text after `=` into a value or raises `ConfigError` naming the key and what is allowed.
A key declared with `many=True` takes a comma-separated list (`policies=eps,ucb`); its value is
then always a tuple. Nothing is read from the environment: the command line is the whole input.
"""

from __future__ import annotations

import dataclasses
import sys
from typing import Any, Callable, Iterable, Sequence

from mjx_curio.config import ConfigError, check_choice, check_float, check_int


@dataclasses.dataclass(frozen=True)
class Key:
    name: str
    default: Any
    help: str
    parse: Callable[[str, str], Any]  # (key name, one text item) -> value
    many: bool = False  # comma-separated list -> tuple


def parse(argv: Sequence[str], keys: Iterable[Key]) -> dict:
    """Values of every key: the defaults, overridden by `key=value` items of argv.

    Raises ConfigError for an item that is not key=value, an unknown key, a key given twice,
    or a value its parser refuses.
    """
    keys = {k.name: k for k in keys}
    values = {name: k.default for name, k in keys.items()}
    seen = set()
    for item in argv:
        name, sep, text = item.partition("=")
        if not sep or not name:
            raise ConfigError(f"argument {item!r} is not key=value; allowed keys: {', '.join(keys)}")
        if name not in keys:
            raise ConfigError(f"unknown key {name!r}; allowed keys: {', '.join(keys)}")
        if name in seen:
            raise ConfigError(f"key {name!r} is given twice")
        seen.add(name)
        key = keys[name]
        if key.many:
            items = [t.strip() for t in text.split(",")]
            if not text.strip() or any(not t for t in items):
                raise ConfigError(f"{name}={text!r} must be a comma-separated list with no empty items")
            values[name] = tuple(key.parse(name, t) for t in items)
        else:
            values[name] = key.parse(name, text.strip())
    return values


def usage(prog: str, summary: str, keys: Iterable[Key]) -> str:
    lines = [f"usage: python -m {prog} [key=value ...]", "", summary, "", "keys (default in brackets):"]
    for k in keys:
        default = ",".join(map(str, k.default)) if isinstance(k.default, tuple) else k.default
        lines.append(f"  {k.name:<18} {k.help} [{default}]")
    return "\n".join(lines)


def main_guard(argv: Sequence[str] | None, prog: str, summary: str, keys: Sequence[Key]) -> dict | None:
    """Parse argv; print usage and return None on --help/-h; exit 2 with a one-line message on
    bad input (before any work is done)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if any(a in ("-h", "--help", "help") for a in argv):
        print(usage(prog, summary, keys))
        return None
    try:
        return parse(argv, keys)
    except ConfigError as err:
        print(f"error: {err}", file=sys.stderr)
        raise SystemExit(2) from None


# ---------------------------------------------------------------------------- value parsers


def as_int(lo: int | None = None, hi: int | None = None) -> Callable[[str, str], int]:
    def p(name: str, text: str) -> int:
        try:
            value = int(text.replace("_", ""))
        except ValueError:
            raise ConfigError(f"{name}={text!r} must be an integer{_range(lo, hi)}") from None
        return check_int(name, value, lo, hi)

    return p


def as_float(lo: float | None = None, hi: float | None = None, lo_open: bool = False) -> Callable[[str, str], float]:
    def p(name: str, text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise ConfigError(f"{name}={text!r} must be a number") from None
        return check_float(name, value, lo, hi, lo_open=lo_open)

    return p


def as_choice(allowed: Sequence[str]) -> Callable[[str, str], str]:
    def p(name: str, text: str) -> str:
        return check_choice(name, text, allowed)

    return p


def as_bool(name: str, text: str) -> bool:
    t = text.lower()
    if t in ("true", "1", "yes"):
        return True
    if t in ("false", "0", "no"):
        return False
    raise ConfigError(f"{name}={text!r} is not allowed; choose one of: true, false")


def as_str(name: str, text: str) -> str:
    if not text:
        raise ConfigError(f"{name}= must not be empty")
    return text


def _range(lo, hi) -> str:
    if lo is not None and hi is not None:
        return f" in [{lo}, {hi}]"
    if lo is not None:
        return f" >= {lo}"
    return ""
