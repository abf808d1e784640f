"""What the evidence scripts share: their command line, `python experiments/<script>.py <sweep>`
(`one_sweep_main`), the JSON list of entries each keeps under docs/results/ (`save_entry`), and
the seed parts of one experiment read as one entry (`pool_seed_parts`, `save_part`,
`pooled_entries`).

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
    from mjx_curio.cli import wants_help

    usage = doc.split("\n\n")[1]
    if wants_help(argv):
        print(usage)
        return 0
    if len(argv) != 1:
        print(f"{script}: want one sweep directory, got {len(argv)} argument{'s' if len(argv) != 1 else ''}"
              f"{': ' + ' '.join(argv) if argv else ''}\n{usage}", file=sys.stderr)
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


def pool_seed_parts(saved: list[dict], entry: dict, same: tuple[str, ...], source: pathlib.Path) -> dict:
    """`entry` with the runs of every saved entry of the same experiment (its seed parts: the
    name less a `.seeds-...` suffix the same) and the same values of `same` (the step it was
    measured at, say), seeds in order, named by the experiment and the seeds it holds
    (`multi_agent.per_step.seeds-0-5`); `entry` itself where it is the only one. `saved` holds
    `entry` too. SweepError where two parts hold one run (its name: policy, setting and seed),
    naming `source`, the file they were saved in."""
    from mjx_curio import analysis as an
    from mjx_curio.analysis import SweepError

    name = an.experiment_name(entry["sweep"])
    parts = [e for e in saved if an.experiment_name(e["sweep"]) == name and all(e[k] == entry[k] for k in same)]
    if len(parts) <= 1:
        return entry
    runs = sorted((r for e in parts for r in e["runs"]), key=lambda r: r["seed"])
    ran = [r["run"] for r in runs]  # policy, setting and seed
    if len(set(ran)) < len(ran):
        where = ", ".join(f"{k} {entry[k]:,}" if isinstance(entry[k], int) else f"{k} {entry[k]}" for k in same)
        raise SweepError(f"the saved parts of {name} ({where}) in {source} repeat a run (policy, setting, seed): "
                         "a rerun, not more seeds; remove its stale entry there")
    return {**entry, "sweep": an.seeds_name(name, [r["seed"] for r in runs]), "runs": runs}


def save_part(path: pathlib.Path, entry: dict, keys: tuple[str, ...], same: tuple[str, ...], indent: int = 1) -> dict:
    """`save_entry`, and `entry` pooled with the seed parts of its experiment saved at `path`
    (`pool_seed_parts`), which it returns. Pooled first: parts that repeat a run are a SweepError
    that leaves the file as it was."""
    saved = json.loads(path.read_text()) if path.exists() else []
    key = tuple(entry[k] for k in keys)
    pooled = pool_seed_parts([e for e in saved if tuple(e[k] for k in keys) != key] + [entry], entry, same, path)
    save_entry(path, entry, keys=keys, indent=indent)
    return pooled


def pooled_entries(saved: list[dict], same: tuple[str, ...], source: pathlib.Path) -> list[dict]:
    """The saved entries with each experiment's seed parts at the same values of `same` pooled
    into one (`pool_seed_parts`), in the order of their first part."""
    from mjx_curio import analysis as an

    seen, pooled = set(), []
    for e in saved:
        key = (an.experiment_name(e["sweep"]),) + tuple(e[k] for k in same)
        if key not in seen:
            seen.add(key)
            pooled.append(pool_seed_parts(saved, e, same, source))
    return pooled
