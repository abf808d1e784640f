"""key=value command lines, shared by `python -m mjx_curio.sweep`, `.bench`, `.video` and `.verdicts`.

A program's keys are `Key`s: a name, a default, a one-line help and a *kind* from config.py
that reads the text after `=` and checks the value (`ConfigError` naming the key and what is
allowed). The sweep's keys are generated from its config dataclasses (`keys_of`), so a knob
added there is a key, in --help and in the manifest at once. A list kind (`ListOf`) takes a
comma-separated list (`policies=eps,ucb`), always given back as a tuple. Nothing is read from
the environment: the command line is the whole input.
"""

from __future__ import annotations

import dataclasses
import sys
from typing import Any, Iterable, Sequence

from mjx_curio import config as config_lib
from mjx_curio.config import Bool, Choice, ConfigError, Float, Int, ListOf, Text


@dataclasses.dataclass(frozen=True)
class Key:
    name: str
    default: Any
    help: str
    kind: Any  # config.Int, Float, Choice, Bool, Text or ListOf
    many: bool = False  # wrap `kind` in ListOf: a comma-separated list -> tuple
    group: str = ""  # --help section
    resume_free: bool = False
    shown: str | None = None  # the default as --help shows it, where the value would mislead

    def __post_init__(self):
        if self.many and not isinstance(self.kind, ListOf):
            object.__setattr__(self, "kind", ListOf(self.kind))
        if isinstance(self.kind, ListOf):
            object.__setattr__(self, "many", True)
            object.__setattr__(self, "default", tuple(self.default))

    def parse(self, text: str) -> Any:
        return self.kind.parse(self.name, text)

    def show_default(self) -> str:
        return self.shown if self.shown is not None else self.kind.show(self.default)


def keys_of(*classes) -> tuple[Key, ...]:
    """The command-line keys of config dataclasses: one per knob with cli=True, in declaration
    order, grouped by the knob's group (or its class's first docstring line)."""
    keys, seen, sections = [], {}, []
    for cls in classes:
        section = {config_lib.SweepConfig: "sweep", config_lib.RunConfig: "arena and run",
                   config_lib.LearnerConfig: "learner"}.get(cls, cls.__name__)
        sections.append(section)
        for f in config_lib.knobs(cls):
            m = f.metadata
            if not m["cli"]:
                continue
            name = config_lib.key_name(f)
            if name in seen:
                raise TypeError(f"key {name!r} is declared by {seen[name]} and {cls.__name__}")
            seen[name] = cls.__name__
            keys.append(Key(name, f.default, m["help"], m["kind"], group=m["group"] or section,
                            resume_free=m["resume_free"], shown=m["shown"]))
    # Each class's own section in class order first, then the sections knobs name themselves.
    return tuple(sorted(keys, key=lambda k: k.group not in sections))


def parse(argv: Sequence[str], keys: Iterable[Key]) -> dict:
    """Values of every key: the defaults, overridden by `key=value` items of argv.

    Raises ConfigError for an item that is not key=value, an unknown key, a key given twice,
    or a value its kind refuses."""
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
        values[name] = keys[name].parse(text.strip())
    return values


def usage(prog: str, summary: str, keys: Iterable[Key]) -> str:
    lines = [f"usage: python -m {prog} [key=value ...]", "", summary, "", "keys (default in brackets):"]
    group = None
    for k in keys:
        if k.group and k.group != group:
            group = k.group
            lines.append(f" {group}:")
        lines.append(f"  {k.name:<18} {k.help} [{k.show_default()}]")
    return "\n".join(lines)


def main_guard(argv: Sequence[str] | None, prog: str, summary: str, keys: Sequence[Key]) -> dict | None:
    """Parse argv; print usage and return None on --help/-h; exit 2 with a one-line message on
    bad input (before any work is done)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if wants_help(argv):
        print(usage(prog, summary, keys))
        return None
    try:
        return parse(argv, keys)
    except ConfigError as err:
        print(f"error: {err}", file=sys.stderr)
        raise SystemExit(2) from None


def wants_help(argv: Sequence[str]) -> bool:
    return any(a in ("-h", "--help", "help") for a in argv)


# Kind constructors under the names the programs' key tables read well with.
as_int = Int
as_float = Float
as_bool = Bool()
as_str = Text()


def as_choice(allowed: Sequence[str]) -> Choice:
    return Choice(tuple(allowed))
