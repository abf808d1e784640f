"""The paper's claims tested on your own sweeps, from the command line:

    python -m mjx_curio.verdicts sweeps=runs/paper
    python -m mjx_curio.verdicts sweeps=runs/paper table=power format=csv
    python -m mjx_curio.verdicts sweeps=runs/paper out=runs/paper/verdicts

prints the claims table (each claim's statistic across seeds and its verdict) and the power table
(per test: the largest effect the runs do not rule out, the p-value with Holm's adjustment, the
seeds it would need), the tables docs/results.md shows for the committed runs and the notebook
for any. `sweeps` is a sweep directory or a directory of them; the sweeps are read as the
presets they ran, seed parts of one experiment joined (`analysis.join_seed_parts`). `out` also
writes each table as Markdown and CSV into a directory, and refuses to replace a file there.
NumPy only: nothing is compiled.
"""

from __future__ import annotations

import pathlib
import sys

from mjx_curio import cli
from mjx_curio.cli import Key, as_choice, as_str

PROG = "mjx_curio.verdicts"
SUMMARY = ("The paper's claims tested across the seeds of your sweeps: the claims table and the power table, as "
           "Markdown or CSV, printed and optionally written to a directory.")
TABLES = ("claims", "power")

KEYS = (
    Key("sweeps", "", "a sweep directory, or a directory of sweep directories (e.g. runs/paper)", as_str,
        shown="required"),
    Key("table", "both", "which table: claims | power | both", as_choice(TABLES + ("both",))),
    Key("format", "markdown", "how to print them: markdown | csv", as_choice(("markdown", "csv"))),
    Key("out", "", "also write <table>.md and <table>.csv into this directory (never replacing a file)", as_str,
        shown="none"),
)


def tables(sweeps_dir: str | pathlib.Path, which: str = "both") -> dict:
    """{name: analysis.Table} of the claims and/or power table of the sweeps in `sweeps_dir`."""
    from mjx_curio import analysis as an

    sweeps = an.join_seed_parts(an.load_sweeps(sweeps_dir))
    names = TABLES if which == "both" else (which,)
    make = {"claims": an.claims_table, "power": an.power_table}
    return {name: make[name](sweeps) for name in names}


def main(argv=None) -> int:
    v = cli.main_guard(argv, PROG, SUMMARY, KEYS)
    if v is None:
        return 0
    if not v["sweeps"]:
        print("error: sweeps=<directory> is required (a sweep directory or a directory of them)", file=sys.stderr)
        return 2
    names = TABLES if v["table"] == "both" else (v["table"],)
    out = pathlib.Path(v["out"]).expanduser() if v["out"] else None
    if out is not None and out.exists() and not out.is_dir():
        print(f"error: out={v['out']}: {out} is a file, not a directory", file=sys.stderr)
        return 2
    if out is not None:
        taken = [out / f"{n}.{ext}" for n in names for ext in ("md", "csv") if (out / f"{n}.{ext}").exists()]
        if taken:
            print(f"error: out={v['out']}: {', '.join(map(str, taken))} already exist(s); choose another directory "
                  "(nothing is replaced)", file=sys.stderr)
            return 2
    from mjx_curio import analysis as an

    try:
        made = tables(v["sweeps"], v["table"])
    except an.SweepError as err:
        print(f"error: sweeps={v['sweeps']}: {err}", file=sys.stderr)
        return 2
    for name, table in made.items():
        print(table.to_markdown() if v["format"] == "markdown" else table.to_csv())
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        for name, table in made.items():
            for ext, text in (("md", table.to_markdown()), ("csv", table.to_csv())):
                path = out / f"{name}.{ext}"
                with open(path, "x") as f:  # "x": a file that appeared meanwhile is not replaced either
                    f.write(text)
                print(f"wrote {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
