"""experiments/analysis.ipynb runs end to end (nbclient) on the session's tiny sweeps.

The notebook is pointed at a directory holding a 2-agent and a 1-agent tiny sweep (its one
parameter, SWEEP). It must run without an error in any cell, and save every figure as a PNG in
<SWEEP>/figures that is not blank, each also shown inline; its `show` helper refuses a figure with
an empty panel (analysis.save_figure), so an empty plot fails a cell. The sweeps themselves must
be left untouched. The notebook is kept in the repository without outputs.
"""

import pathlib

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


def test_notebook_runs(tiny_sweeps_dir):
    from nbclient import NotebookClient

    sweeps = {name: (tiny_sweeps_dir / name).resolve() for name in ("multi", "single")}
    before = {name: _listing(p) for name, p in sweeps.items()}
    nb = _read()
    params = next(c for c in nb.cells if c.cell_type == "code")
    params.source = f"SWEEP = {str(tiny_sweeps_dir)!r}"
    NotebookClient(nb, timeout=600, kernel_name="python3",
                   resources={"metadata": {"path": str(NOTEBOOK.parent)}}).execute()  # raises on a failing cell

    figures = tiny_sweeps_dir / "figures"
    pngs = {p.stem: p for p in figures.glob("*.png")}
    slugs = {"multi": ["eps-eps0.2", "boltzmann-temperature0.5", "boltzmann-temperature1.5", "ucb-ucb_c1"],
             "single": ["eps-eps0.2", "ucb-ucb_c1"]}
    expected = {"fig23-single-vs-multi-curiosity", "fig24-single-vs-multi-vae", "multi-fig19-temperatures",
                "multi-boltzmann-greediness", "multi-observational", "multi-temperature-measures"}
    for s, groups in slugs.items():
        expected |= {f"{s}-fig11-curiosity-policies", f"{s}-fig21-22-cumulative-interactions", f"{s}-fig10-actions",
                     f"{s}-fig07-reconstructions-run0", f"{s}-losses"}
        for g in groups:
            expected |= {f"{s}-fig08-curiosity-{g}", f"{s}-fig09-interactions-{g}", f"{s}-view-fractions-{g}"}
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
