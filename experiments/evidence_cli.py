"""The command line the one-sweep evidence scripts share: `python experiments/<script>.py <sweep>`.

Bad input (not one argument, no such sweep, no checkpoints or replay buffers) is a one-line
message and exit status 2, before anything is written.
"""

from __future__ import annotations

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
