"""`python -m mjx_curio.verdicts`: the claims and power tables of any sweeps from the command line,
checked on the committed snapshots against the results page's own CSV, and its refusals."""

import csv
import io
import math
import pathlib

import pytest

from mjx_curio import verdicts
from mjx_curio.analysis.claims import CLAIMS

ROOT = pathlib.Path(__file__).resolve().parents[1]
SNAPSHOTS = ROOT / "experiments" / "results"
PAGE_CLAIMS = ROOT / "docs" / "results" / "claims.csv"


def test_the_claims_of_the_committed_sweeps_are_the_pages(capsys):
    # The page loads the snapshots as presets (experiments/results.py); the command reads the same
    # directory as any user's runs/paper. Both must give the page's table, verdict for verdict.
    assert verdicts.main([f"sweeps={SNAPSHOTS}", "table=claims", "format=csv"]) == 0
    got = list(csv.DictReader(io.StringIO(capsys.readouterr().out)))
    want = list(csv.DictReader(io.StringIO(PAGE_CLAIMS.read_text())))
    assert [r["key"] for r in got] == [r["key"] for r in want] and len(got) == len(CLAIMS)
    for a, b in zip(got, want):
        assert a.keys() == b.keys()
        for k in a:
            try:
                x, y = float(a[k]), float(b[k])
            except ValueError:
                assert a[k] == b[k], (a["key"], k)
                continue
            assert math.isclose(x, y, rel_tol=1e-9, abs_tol=1e-12) or (math.isnan(x) and math.isnan(y)), (a["key"], k)


def test_both_tables_printed_and_written_never_replacing_a_file(tmp_path, capsys):
    out = tmp_path / "verdicts"
    assert verdicts.main([f"sweeps={SNAPSHOTS}", f"out={out}"]) == 0
    printed = capsys.readouterr().out
    assert "| # | claim | paper's evidence | our statistic | verdict |" in printed
    assert "largest not ruled out (95 %) | p (Holm)" in printed
    written = sorted(p.name for p in out.iterdir())
    assert written == ["claims.csv", "claims.md", "power.csv", "power.md"]
    assert (out / "claims.md").read_text() in printed
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    (out / "power.md").write_text("mine")
    assert verdicts.main([f"sweeps={SNAPSHOTS}", f"out={out}"]) == 2
    err = capsys.readouterr().err
    assert f"out={out}" in err and "already exist" in err
    assert (out / "power.md").read_text() == "mine"
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.name != "power.md"} == {
        k: v for k, v in before.items() if k != "power.md"}


@pytest.mark.parametrize("argv, message", [
    ([], "sweeps=<directory> is required"),
    (["sweeps=/nonexistent/runs"], "sweeps=/nonexistent/runs: /nonexistent/runs does not exist"),
    ([f"sweeps={SNAPSHOTS}", "table=all"], "table='all' is not allowed; choose one of: 'claims', 'power', 'both'"),
    ([f"sweeps={SNAPSHOTS}", "format=json"], "format='json' is not allowed"),
    ([f"sweeps={SNAPSHOTS}", "seeds=3"], "unknown key 'seeds'"),
])
def test_bad_input_is_a_message_naming_the_key(argv, message, capsys):
    assert _exit_code(argv) == 2
    assert message in capsys.readouterr().err


def test_a_directory_without_sweeps_is_refused(tmp_path, capsys):
    assert verdicts.main([f"sweeps={tmp_path}"]) == 2
    assert "no manifest.json" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())  # nothing written


def test_an_out_that_is_a_file_is_refused_before_any_work(tmp_path, capsys):
    f = tmp_path / "taken"
    f.write_text("mine")
    assert verdicts.main([f"sweeps={SNAPSHOTS}", f"out={f}"]) == 2
    captured = capsys.readouterr()
    assert f"out={f}" in captured.err and "is a file" in captured.err and captured.out == ""
    assert f.read_text() == "mine"


def _exit_code(argv) -> int:
    """The command's exit status, whether it returns it or exits with it (bad keys exit at parsing)."""
    try:
        return verdicts.main(argv)
    except SystemExit as exc:
        return exc.code
