"""The paper's experiments as named presets: `python -m mjx_curio.sweep preset=<name>`.

The presets live in `presets.toml`, shipped inside the package; each is a table of sweep keys
(and an `about` line for --help). A preset's keys are defaults: keys given on the command line
win, and a preset's sweep lands in `runs/paper/<name>` unless `out` is given.
"""

from __future__ import annotations

import importlib.resources
import tomllib

from mjx_curio.config import ConfigError


def load_presets() -> dict:
    return tomllib.loads((importlib.resources.files("mjx_curio") / "presets.toml").read_text())


def apply_preset(argv: list) -> list:
    """argv with the preset's keys put in front of it (the command line's own keys win)."""
    given = {a.partition("=")[0]: a.partition("=")[2] for a in argv if "=" in a}
    name = given.get("preset", "none")
    if name == "none":
        return argv
    presets = load_presets()
    if name not in presets:
        raise ConfigError(f"preset={name!r} is not allowed; choose one of: none, {', '.join(presets)}")
    items = [f"{k}={v}" for k, v in presets[name].items() if k != "about" and k not in given]
    if "out" not in given:
        items.append(f"out=runs/paper/{name}")
    return items + list(argv)


def describe() -> str:
    lines = ["presets (python -m mjx_curio.sweep preset=<name>):"]
    lines += [f"  {name:<30} {preset.get('about', '')}" for name, preset in load_presets().items()]
    return "\n".join(lines)
