"""What the evidence scripts share: their command line, `python experiments/<script>.py <sweep>`
(`one_sweep_main`), and the JSON list of entries each keeps under docs/results/ (`save_entry`).

Bad input (not one argument, no such sweep, no checkpoints or replay buffers) is a one-line
message and exit status 2, before anything is written.
"""

from __future__ import annotations

import json
import pathlib
import sys
from typing import Callable


def one_sweep_main(script: str, doc: str, evidence: Callable[[str], object], argv: list[str]) -> int:
    """Run `evidence(sweep path)` for `script`, whose module docstring `doc` has its usage as the
    second paragraph; SweepError becomes `script: message` on stderr and status 2."""
    from mjx_curio.analysis import SweepError

    if len(argv) != 1:
        print(doc.split("\n\n")[1], file=sys.stderr)
        return 2
    try:
        evidence(argv[0])
    except SweepError as err:
        print(f"{script}: {err}", file=sys.stderr)
        return 2
    return 0


def save_entry(path: pathlib.Path, entry: dict, keys: tuple[str, ...] = ("sweep",), indent: int = 1) -> None:
    """Add `entry` to the JSON list at `path` (made where missing), replacing an earlier entry with
    the same values of `keys`, the list sorted by them: a script run again on a sweep updates that
    sweep's entry and keeps the others."""
    def key(e: dict) -> tuple:
        return tuple(e[k] for k in keys)

    saved = json.loads(path.read_text()) if path.exists() else []
    saved = [e for e in saved if key(e) != key(entry)] + [entry]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(sorted(saved, key=key), indent=indent) + "\n")
