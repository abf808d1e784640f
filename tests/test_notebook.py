"""experiments/analysis.ipynb runs end to end (nbclient) on the session's tiny sweeps.

The notebook is pointed at a directory holding a 2-agent and a 1-agent tiny sweep and the 2-agent
one's next seeds as a sweep of their own (its one parameter, SWEEP). It must run without an error in any cell, and save every figure as a PNG in
<SWEEP>/figures that is not blank, each also shown inline; its `show` helper refuses a figure with
an empty panel (analysis.save_figure), so an empty plot fails a cell. The sweeps themselves must
be left untouched. The notebook is kept in the repository without outputs.
"""

import json
import pathlib
import shutil

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

import nbformat  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from PIL import Image  # noqa: E402

NOTEBOOK = pathlib.Path(__file__).resolve().parents[1] / "experiments" / "analysis.ipynb"


def _read():
    return nbformat.read(NOTEBOOK, as_version=4)


def test_saved_without_outputs():
    nb = _read()
    nbformat.validate(nb)
    code = [c for c in nb.cells if c.cell_type == "code"]
    for c in code:
        assert c.outputs == [] and c.execution_count is None, c.source[:60]
    first = code[0]
    assert "parameters" in first.metadata.get("tags", []) and first.source.startswith("SWEEP = ")


def _colours(rgb: np.ndarray) -> int:
    """Distinct colours of a uint8 RGB image, each packed into one integer: np.unique over rows
    (axis=0) sorts them lexicographically and took about a second a figure."""
    rgb = rgb.astype(np.uint32)
    return len(np.unique((rgb[..., 0] << 16) | (rgb[..., 1] << 8) | rgb[..., 2]))


def _listing(root: pathlib.Path) -> dict:
    return {str(p.relative_to(root)): (p.stat().st_size, p.stat().st_mtime_ns) for p in root.rglob("*") if p.is_file()}


def _more_seeds(sweep: pathlib.Path, out: pathlib.Path, offset: int) -> pathlib.Path:
    """A copy of `sweep` standing for its experiment's next seeds, run as a sweep of their own
    (`first_seed=<offset>`): the same files with the runs' seeds moved up by `offset`."""
    shutil.copytree(sweep, out, symlinks=True)
    manifest = json.loads((out / "manifest.json").read_text())
    for r in manifest["runs"]:
        r["name"] = r["name"].replace(f"s{r['seed']}", f"s{r['seed'] + offset}")
        r["seed"] += offset
    manifest["config"]["first_seed"] = offset
    (out / "manifest.json").write_text(json.dumps(manifest))
    return out


def test_notebook_runs(tiny_sweeps_dir, tmp_path):
    from nbclient import NotebookClient

    # The two tiny sweeps, and the two-agent one's experiment continued by two more seeds in a
    # sweep of its own: the notebook reads the two parts as one experiment of 4 seeds.
    parent = tmp_path / "sweeps"
    parent.mkdir()
    for name in ("multi", "single"):
        (parent / name).symlink_to((tiny_sweeps_dir / name).resolve(), target_is_directory=True)
    more = _more_seeds((tiny_sweeps_dir / "multi").resolve(), parent / "multi.seeds-2-3", offset=2)
    # Without its checkpoints, as a snapshot of the metrics (experiments/results/) has none: the
    # figures from checkpoints skip it, saying so, and the rest read its metrics.
    shutil.rmtree(more / "checkpoints")
    tiny_sweeps_dir = parent
    sweeps = {name: (tiny_sweeps_dir / name).resolve() for name in ("multi", "single", "multi.seeds-2-3")}
    before = {name: _listing(p) for name, p in sweeps.items()}
    nb = _read()
    params = next(c for c in nb.cells if c.cell_type == "code")
    params.source = f"SWEEP = {str(tiny_sweeps_dir)!r}"
    NotebookClient(nb, timeout=600, kernel_name="python3",
                   resources={"metadata": {"path": str(NOTEBOOK.parent)}}).execute()  # raises on a failing cell

    loading = [c for c in nb.cells if c.cell_type == "code"][1]
    printed = "".join(o.get("text", "") for o in loading.outputs if o.output_type == "stream")
    assert "multi.seeds-0-3, merged from 2 sweeps: 16 runs, 2 agents" in printed, printed
    assert "ε-greedy (ε=0.2) x 4" in printed and "part " in printed

    figures = tiny_sweeps_dir / "figures"
    pngs = {p.stem: p for p in figures.glob("*.png")}
    slugs = {"multi.seeds-0-3": ["eps-eps0.2", "boltzmann-temperature0.5", "boltzmann-temperature1.5", "ucb-ucb_c1"],
             "single": ["eps-eps0.2", "ucb-ucb_c1"]}
    expected = {"fig23-single-vs-multi-curiosity", "fig24-single-vs-multi-vae", "multi.seeds-0-3-fig19-temperatures",
                "multi.seeds-0-3-observational", "multi.seeds-0-3-temperature-measures", "claim-effects",
                "paper_readings"}
    # Figures from checkpoints come from each part of the merged sweep, which keeps its own; the
    # part without checkpoints is skipped by name.
    expected |= {"multi-boltzmann-greediness", "multi-fig07-reconstructions-run0", "single-fig07-reconstructions-run0"}
    said = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code" for o in c.outputs
                   if o.output_type == "stream")
    assert said.count("multi.seeds-2-3: no checkpoint") == 2, said
    shown = "".join(o.get("data", {}).get("text/markdown", "") for c in nb.cells if c.cell_type == "code"
                    for o in c.outputs if o.output_type == "display_data")
    assert "fall [95 % CI]" in shown  # claim 1 taken apart
    assert "Claims 9 and 12 part by part" in shown  # watching and touching taken apart too
    for s, groups in slugs.items():
        expected |= {f"{s}-fig11-curiosity-policies", f"{s}-fig21-22-cumulative-interactions", f"{s}-fig10-actions",
                     f"{s}-losses", f"{s}-turn-reversals", f"{s}-self-model-tracking"}
        for g in groups:
            expected |= {f"{s}-fig08-curiosity-{g}", f"{s}-fig09-interactions-{g}", f"{s}-view-fractions-{g}",
                         f"{s}-curiosity-parts-{g}"}
    assert expected == set(pngs), (sorted(expected - set(pngs)), sorted(set(pngs) - expected))
    for name, path in pngs.items():
        img = np.asarray(Image.open(path).convert("RGB"))
        assert img.shape[0] > 100 and img.shape[1] > 100, name
        assert img.astype(float).std() > 5, f"{name} is blank"
        assert _colours(img) > 20, f"{name} has almost no colours"
    shown = sum(1 for c in nb.cells if c.cell_type == "code" for o in c.outputs
                if o.output_type == "display_data" and "image/png" in o.get("data", {}))
    assert shown == len(pngs)
    for s in slugs:
        assert (figures / f"{s}-headline.md").read_text().count("|") > 20
        assert (figures / f"{s}-headline.csv").is_file()
    # The claims table has a row a claim, the power table its columns; both are saved as CSV too.
    claims = (figures / "claims.md").read_text()
    assert all(f"\n| {k} | " in claims for k in ("1", "2", "3", "4", "5", "6a", "6b", "7", "8", "9")), claims
    assert "largest not ruled out (95 %) | p (Holm)" in (figures / "power.md").read_text()
    assert (figures / "claims.csv").is_file() and (figures / "power.csv").is_file()
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs if o.output_type == "error"]
    assert not errors
    for name, p in sweeps.items():
        assert _listing(p) == before[name], f"the notebook changed the {name} sweep's files"


def test_notebook_says_what_is_missing(tmp_path):
    """Pointed at a directory that does not exist, the loading cell fails saying so."""
    from nbclient import NotebookClient
    from nbclient.exceptions import CellExecutionError

    nb = _read()
    code = [c for c in nb.cells if c.cell_type == "code"]
    code[0].source = f"SWEEP = {str(tmp_path / 'nowhere')!r}"
    nb.cells = [c for c in nb.cells if c in code[:2]]
    with pytest.raises(CellExecutionError, match="does not exist or is not a directory"):
        NotebookClient(nb, timeout=120, kernel_name="python3",
                       resources={"metadata": {"path": str(NOTEBOOK.parent)}}).execute()
