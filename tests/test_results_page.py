"""The results page (docs/results.md, made by experiments/results.py): its tables are what the
claims code computes from the committed metrics, its figures exist, and snapshots copy only
final windows and never replace a sweep with another or with less."""

import csv
import importlib.util
import io
import json
import math
import pathlib
import re
import shutil
import sys
import types

import numpy as np
import pytest

from mjx_curio import analysis as an

ROOT = pathlib.Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def results():
    name = "mjx_curio_results_page"
    spec = importlib.util.spec_from_file_location(name, ROOT / "experiments" / "results.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses look their module up while the file executes
    spec.loader.exec_module(module)
    yield module
    sys.modules.pop(name, None)


@pytest.fixture(scope="module")
def full_length_page(results):
    """experiments/full_length_page.py, the page's full-length block, as results.py imports it."""
    return sys.modules["full_length_page"]


# ---------------------------------------------------------------------- the committed page


def test_the_page_is_what_the_committed_metrics_give(results):
    # Regenerating from experiments/results/ gives the committed tables, number for number.
    assert results.check_page() == [], "run `python experiments/results.py page` and commit"
    presets = results.load_presets()
    page = results.PAGE.read_text()
    blocks = results.blocks(page)
    assert set(blocks) == {"scale", "figures", "claims", "paper_numbers", "history", "authors_memory", "vae_layers",
                           "rerun", "vae_layers_every_seed", "vae_layers_two_agents",
                           "vae_layers_two_agents_every_seed", "power", "curiosity_parts", "temperatures", "walls",
                           "reconstructions", "full_length"}
    assert blocks["figures"] == results.figures_block(presets, out=None)
    if presets:  # the CSV's full-precision numbers may differ in the last bit on another CPU's NumPy
        _assert_same_csv(results.CLAIMS_CSV.read_text(), an.claims_table(presets).to_csv())
        _assert_same_csv(results.WALLS_CSV.read_text(), an.walls_table(presets).to_csv())
    for link in results.re.findall(r"\]\((figures/[^)]+\.png)\)", page):
        assert (results.PAGE.parent / link).is_file(), link


def _assert_same_csv(committed: str, computed: str):
    a, b = list(csv.DictReader(io.StringIO(committed))), list(csv.DictReader(io.StringIO(computed)))
    assert [list(r) for r in a] == [list(r) for r in b] and len(a) == len(b)
    for ra, rb in zip(a, b):
        for k in ra:
            try:
                x, y = float(ra[k]), float(rb[k])
            except ValueError:
                assert ra[k] == rb[k], (k, ra[k], rb[k])
                continue
            assert math.isclose(x, y, rel_tol=1e-9, abs_tol=1e-12) or (math.isnan(x) and math.isnan(y)), (
                ra.get("key", ra.get("group")), k, x, y)


def test_the_pages_links_to_its_own_sections_find_them():
    page = (ROOT / "docs" / "results.md").read_text()
    slugs = {re.sub(r"[^\w\- ]", "", h.lower()).replace(" ", "-") for h in re.findall(r"^#+ (.+)$", page, re.M)}
    links = re.findall(r"\]\(#([^)]+)\)", page)
    assert links and set(links) <= slugs, sorted(set(links) - slugs)


def test_the_headline_count_of_claims_that_hold_is_the_tables(results):
    # The README and the page say in words how many claims hold; the claims table decides it.
    presets = results.load_presets()
    if not presets:
        pytest.skip("no snapshot committed")
    verdicts = [v["verdict"] for v in an.claims_table(presets).values]
    words = "zero one two three four five six seven eight nine ten eleven twelve thirteen fourteen fifteen sixteen " \
            "seventeen eighteen nineteen twenty".split()
    held, total = sum(v.startswith("holds") for v in verdicts), len(verdicts)
    phrase = f"{words[held]} of the {words[total]}"
    readme = " ".join((ROOT / "README.md").read_text().split())
    page = " ".join((ROOT / "docs" / "results.md").read_text().split())
    assert phrase.capitalize() in readme or phrase in readme, phrase
    assert f"{phrase} hold" in page, phrase


def test_the_readme_links_the_page():
    head = (ROOT / "README.md").read_text().split("\n## ")[0]
    assert "docs/results.md" in head


def test_blocks_are_replaced_and_nothing_else(results):
    page = "intro\n<!-- generated: a -->\nold a\n<!-- end: a -->\nmiddle\n<!-- generated: b -->\nold b\n<!-- end: b -->\nend\n"
    assert results.blocks(page) == {"a": "old a\n", "b": "old b\n"}
    new = results.fill(page, {"a": "new a\n"})
    assert new == page.replace("old a", "new a")
    with pytest.raises(KeyError, match="c"):
        results.fill(page, {"c": "x\n"})


def _reconstruction_entry(sweep: str, step: int, p: float) -> dict:
    cell = {"mean": 300.0, "low": 290.0, "high": 310.0, "n": 9}
    test = {"diff": 50.0, "low": 40.0, "high": 60.0, "n": 9, "p": p}
    rows = [{"step": s, "error": cell, "error_vs_newest": test, "edge_error": cell, "edge_error_vs_newest": test}
            for s in (500, step)]
    return {"sweep": sweep, "step": step, "replay_step": step, "frames_per_run": 32, "heldout_frames_per_vae": 512,
            "image": 64, "steps": [500, step], "summary": rows, "runs": []}


def test_reconstructions_block_shows_each_sweeps_newest_entry(results, tmp_path):
    path = tmp_path / "reconstructions.json"
    assert results.reconstructions_block(path).startswith("No sweep's reconstructions")
    entries = [_reconstruction_entry("b", 2_000, 0.01), _reconstruction_entry("a", 40_000, 1e-6),
               _reconstruction_entry("a", 15_000, 0.5)]
    path.write_text(json.dumps(entries))
    block = results.reconstructions_block(path)
    assert block.index("`a`:") < block.index("`b`:")  # sorted by sweep
    assert "at step 40,000" in block and "15,000" not in block  # a sweep's newest entry only
    assert "| 500 | 9 | 300 [290, 310] | +50 (p = 1e-06) |" in block and "| 2,000 | 9 |" in block
    assert "![a_reconstructions](figures/a_reconstructions.png)" in block
    entries = [_reconstruction_entry("a", 1_000, float("nan"))]
    path.write_text(json.dumps(entries))  # json writes NaN for a test with no spread
    block = results.reconstructions_block(path)
    assert "| 500 | 9 | 300 [290, 310] | — |" in block and "Per policy" not in block
    # With several policies: each at the newest checkpoint, the test across them, and who reconstructs whose views.
    cell = {"mean": 150.0, "low": 140.0, "high": 160.0, "n": 3}
    entries[0]["by_policy"] = {
        "train_windows": 50, "anova_p": {"error": 4e-6, "edge_error": 0.5, "train_recon": float("nan")},
        "groups": [{"group": g, "error": cell, "edge_error": cell, "train_recon": cell,
                    "on_views_of": {"P": 100.0, "Q": 200.0 + i}} for i, g in enumerate(("P", "Q"))]}
    path.write_text(json.dumps(entries))
    block = results.reconstructions_block(path)
    assert "| P | 3 | 150 [140, 160] | 150 [140, 160] | 150 [140, 160] |" in block
    assert "| across the policies | | p = 4e-06 | p = 0.5 | — |" in block
    assert "| VAE of | views of P | views of Q |" in block and "| Q | 100 | 201 |" in block


def test_reconstruction_evidence_refuses_a_sweep_without_checkpoints(tiny_sweep, tmp_path, capsys):
    module = _experiment("reconstruction_evidence")
    module.OUT, module.FIGURES = tmp_path / "out" / "reconstructions.json", tmp_path / "out"
    _refuses_bad_sweeps(module, "reconstruction_evidence.py", tiny_sweep, tmp_path, capsys)


def test_spread_evidence_on_the_tiny_sweep(results, tiny_sweep, tmp_path, capsys):
    """Every run's posterior variance per dimension at every checkpoint, on the newest buffer's
    views: its mean is `posterior_spread`'s, the dimensions near the prior are counted from it, and
    the page's block shows one row per group. Bad input writes nothing."""
    module = _experiment("spread_evidence")
    module.OUT = tmp_path / "out" / "posterior_dims.json"
    _refuses_bad_sweeps(module, "spread_evidence.py", tiny_sweep, tmp_path, capsys)
    entry = module.evidence(str(tiny_sweep))
    sweep = an.load(tiny_sweep)
    assert [r["run"] for r in entry["runs"]] == [r.name for r in sweep.runs]
    for i in (0, sweep.n_runs - 1):
        spread = an.posterior_spread(sweep, i, every=module.EVERY)
        got = entry["runs"][i]["by_checkpoint"]
        assert list(got) == [str(k) for k in sweep.checkpoint_steps()]
        for k, v in spread.items():
            assert got[str(k)]["spread"] == pytest.approx(v, rel=1e-9)
            sigma2 = np.array(got[str(k)]["sigma2"])
            assert len(sigma2) == entry["latent"] and got[str(k)]["near_prior"] == int((sigma2 > module.NEAR_PRIOR).sum())
            assert got[str(k)]["median"] == pytest.approx(np.median(sigma2), abs=1e-4)  # sigma2 is kept to 4 decimals
    assert json.loads(module.OUT.read_text()) == [entry]
    block = results.curiosity_parts_block({}, dims=module.OUT)
    rows = [r for r in block.splitlines() if r.startswith("| ") and not r.startswith("| group")]
    assert len(rows) == len(sweep.groups()) and block.startswith("No sweep that records")
    # A later seed part is one table with the first, over the checkpoints both kept.
    steps = list(entry["runs"][0]["by_checkpoint"])
    later = {**entry, "sweep": entry["sweep"] + ".seeds-10-99",
             "runs": [{**r, "run": r["run"] + "+10", "seed": r["seed"] + 10,
                       "by_checkpoint": {k: v for k, v in r["by_checkpoint"].items() if k != steps[0]}}
                      for r in entry["runs"]]}
    module.OUT.write_text(json.dumps([entry, later]))
    block = results.curiosity_parts_block({}, dims=module.OUT)
    assert block.count("each checkpoint's VAE") == 1 and f"step {int(steps[0]):,} |" not in block
    rows = [r for r in block.splitlines() if r.startswith("| ") and not r.startswith("| group")]
    assert [int(r.split(" | ")[1]) for r in rows] == [2 * sum(x.group_label == g for x in sweep.runs)
                                                      for g in dict.fromkeys(x.group_label for x in sweep.runs)]


def test_seed_parts_of_an_experiment_pool(tmp_path):
    """Entries of one experiment's seed parts at the same values of `same` become one, runs in seed
    order, named by the seeds held; another experiment, or another step, stays apart; parts that
    hold one run twice are refused, naming the file, and a part saved among them then leaves the
    file as it was."""
    module = _experiment("evidence_cli")

    def part(sweep, seeds, step=100):
        return {"sweep": sweep, "step": step, "runs": [{"run": f"eps_s{k}", "seed": k} for k in seeds]}

    first, later = part("x", [2, 0, 1]), part("x.seeds-3-5", [5, 3, 4])
    saved = [first, later, part("y", [0, 1, 2]), part("x.seeds-6-7", [6, 7], step=200)]
    pooled = module.pool_seed_parts(saved, later, same=("step",), source=pathlib.Path("f.json"))
    assert pooled["sweep"] == "x.seeds-0-5" and pooled["step"] == 100
    assert [r["seed"] for r in pooled["runs"]] == [0, 1, 2, 3, 4, 5]
    assert module.pool_seed_parts([first], first, same=("step",), source=pathlib.Path("f.json")) is first
    assert [e["sweep"] for e in module.pooled_entries(saved, ("step",), source=pathlib.Path("f.json"))] == [
        "x.seeds-0-5", "y", "x.seeds-6-7"]
    with pytest.raises(an.SweepError, match=r"f\.json.*repeat a run"):
        module.pool_seed_parts([first, part("x.seeds-2-4", [2, 3, 4])], first, same=("step",),
                               source=pathlib.Path("f.json"))
    path = tmp_path / "entries.json"
    assert module.save_part(path, first, keys=("sweep", "step"), same=("step",)) == first
    assert module.save_part(path, later, keys=("sweep", "step"), same=("step",))["sweep"] == "x.seeds-0-5"
    assert module.save_part(path, later, keys=("sweep", "step"), same=("step",))["sweep"] == "x.seeds-0-5"  # again
    before = path.read_text()
    with pytest.raises(an.SweepError, match="repeat a run"):
        module.save_part(path, part("x.seeds-2-4", [2, 3, 4]), keys=("sweep", "step"), same=("step",))
    assert path.read_text() == before and [e["sweep"] for e in json.loads(before)] == ["x", "x.seeds-3-5"]


def test_evidence_entries_are_replaced_by_key_and_kept_sorted(tmp_path):
    module = _experiment("evidence_cli")
    path = tmp_path / "deep" / "entries.json"
    for sweep, step, value in (("b", 2, 1), ("a", 5, 2), ("b", 1, 3), ("b", 2, 4)):
        module.save_entry(path, {"sweep": sweep, "step": step, "value": value}, keys=("sweep", "step"))
    assert json.loads(path.read_text()) == [{"sweep": "a", "step": 5, "value": 2}, {"sweep": "b", "step": 1, "value": 3},
                                            {"sweep": "b", "step": 2, "value": 4}]
    module.save_entry(path, {"sweep": "b", "step": 9, "value": 5})  # by sweep alone: every "b" entry replaced
    assert [e["value"] for e in json.loads(path.read_text())] == [2, 5]


def test_history_evidence_on_the_tiny_sweep(results, tiny_sweep, tmp_path, capsys):
    """Every run's curiosity on its replay buffer from the live carry and from a zero carry is
    `curiosity_noise`'s each way, the sweep's own curiosity is taken over the buffer's steps, and
    the page's block shows one row per group. Bad input writes nothing."""
    module, entry, sweep = _evidence_on_tiny_sweep("history", tiny_sweep, tmp_path, capsys)
    assert [r["run"] for r in entry["runs"]] == [r.name for r in sweep.runs] and entry["replay_step"] == 200
    for i in (0, sweep.n_runs - 1):
        live, zero = an.curiosity_noise(sweep, i), an.curiosity_noise(sweep, i, zero_state=True)
        got = entry["runs"][i]
        assert got["live"] == pytest.approx(live.expected.mean(), rel=1e-9)
        assert got["zero"] == pytest.approx(zero.expected.mean(), rel=1e-9)
        assert got["spread"] == pytest.approx(live.spread.mean(), rel=1e-9) and got["steps"] == 199
        # The buffer holds the run's 200 steps: every window of the metrics.
        assert got["logged"] == pytest.approx(np.nanmean(sweep.metrics["curiosity"][i]), rel=1e-6)
    assert json.loads(module.OUT.read_text()) == [entry]
    block = results.history_block(module.OUT)
    rows = [r for r in block.splitlines() if r.startswith("| ") and not r.startswith("| group")]
    assert len(rows) == len(sweep.groups())
    assert results.history_block(tmp_path / "none.json").startswith("No sweep's replay buffers")


def test_authors_memory_evidence_on_the_tiny_sweeps(results, tiny_sweep, tiny_single_sweep, tmp_path, capsys):
    """Every run's logged number each way is `logged_curiosity`'s late mean with the run's seed, one
    agent's two pairings are one, and the page's block shows one row per group. Bad input writes
    nothing."""
    from mjx_curio.analysis import authors_memory as am

    module, entry, sweep = _evidence_on_tiny_sweep("authors_memory", tiny_sweep, tmp_path, capsys)
    assert [r["run"] for r in entry["runs"]] == [r.name for r in sweep.runs] and entry["agents"] == 2
    got = entry["runs"][0]
    assert got["steps"] == 200 and got["updates"] == 50  # the buffer holds the run's 200 steps
    for name in am.PAIRINGS:
        out = am.logged_curiosity(sweep, 0, pairing_name=name, updates=50, seed=got["seed"])
        assert got[name] == pytest.approx(out["logged"][-12:].mean(), rel=1e-12)
        assert got["floor"] == pytest.approx(out["floor"], rel=1e-12)
    assert got["logged"] == pytest.approx(np.nanmean(sweep.metrics["curiosity"][0]), rel=1e-6)
    single = module.evidence(str(tiny_single_sweep))
    assert all(r["authors"] == r["matched"] for r in single["runs"]) and single["agents"] == 1
    saved = json.loads(module.OUT.read_text())
    assert [e["sweep"] for e in saved] == sorted([entry["sweep"], single["sweep"]])
    block = results.authors_memory_block(module.OUT)
    rows = [r for r in block.splitlines() if r.startswith("| ") and not r.startswith("| group")]
    assert len(rows) == len(sweep.groups()) + len(an.load(tiny_single_sweep).groups())
    assert "the same (one agent)" in block
    assert results.authors_memory_block(tmp_path / "none.json").startswith("No sweep's replay buffers")


def test_self_model_evidence_on_the_tiny_sweep(tiny_sweep, tmp_path, capsys):
    """Every run's figures are `curiosity_noise`'s and `step_tracking`'s, the printed table pools the
    saved seed parts of the sweep's experiment (and only those), and bad input writes nothing."""
    module, entry, sweep = _evidence_on_tiny_sweep("self_model", tiny_sweep, tmp_path, capsys)
    assert [r["run"] for r in entry["runs"]] == [r.name for r in sweep.runs] and entry["window"] == 20
    tracked = an.step_tracking(sweep)
    for i in (0, sweep.n_runs - 1):
        cn, got = an.curiosity_noise(sweep, i), entry["runs"][i]
        np.testing.assert_allclose(got["curiosity_mean"], cn.expected.mean(axis=0), rtol=1e-12)
        np.testing.assert_allclose(got["spread_share"], cn.spread.mean(axis=0) / cn.expected.mean(axis=0), rtol=1e-12)
        assert got["r_self_obtained_late"] == pytest.approx(np.tanh(tracked["self_late"][i]), rel=1e-12)
    assert json.loads(module.OUT.read_text()) == [entry]
    assert f"| eps | {sum(r.policy == 'eps' for r in sweep.runs)} |" in capsys.readouterr().out
    # The printed table pooled the saved seed parts (`test_seed_parts_of_an_experiment_pool`); a
    # part that repeats a run is refused before the file is touched.
    module.OUT.write_text(json.dumps([{**entry, "sweep": sweep.name + ".seeds-0-99"}]))
    before = module.OUT.read_text()
    with pytest.raises(an.SweepError, match="repeat a run"):
        module.evidence(str(tiny_sweep))
    assert module.OUT.read_text() == before


def test_temperature_evidence_on_the_tiny_sweep(tiny_sweep, tiny_single_sweep, tmp_path, capsys):
    """Every Boltzmann run's figures are NumPy's softmax of its self-models' predictions, one table
    row per temperature, the figure written where FIGURES points; a sweep without Boltzmann runs,
    like any bad input, writes nothing."""
    module = _experiment("temperature_evidence")
    module.OUT, module.FIGURES = tmp_path / "out" / "temperature.json", tmp_path / "figures"
    module.FIGURES.mkdir()
    assert module.main([str(tiny_single_sweep)]) == 2 and "temperature_evidence.py:" in capsys.readouterr().err
    _refuses_bad_sweeps(module, "temperature_evidence.py", tiny_sweep, tmp_path, capsys)
    entry, sweep = module.evidence(str(tiny_sweep)), an.load(tiny_sweep)
    boltzmann = sweep.select(policy="boltzmann")
    assert [r["run"] for r in entry["runs"]] == [sweep.runs[i].name for i in boltzmann]
    for k in (0, len(boltzmann) - 1):
        q, got = an.action_values(sweep, int(boltzmann[k])).q.astype(np.float64), entry["runs"][k]
        x = q / got["temperature"]
        p = np.exp(x - x.max(-1, keepdims=True))
        p /= p.sum(-1, keepdims=True)
        assert got["max_prob"] == pytest.approx(p.max(-1).mean(), rel=1e-6)
        assert got["entropy_rel"] == pytest.approx((-(p * np.log(p)).sum(-1) / np.log(7)).mean(), rel=1e-6)
        assert got["spread_median"] == pytest.approx(np.median(q.max(-1) - q.min(-1)), rel=1e-6)
    temperatures = sorted({r["temperature"] for r in entry["runs"]})
    out = capsys.readouterr().out
    assert all(f"| {t:g} | {sum(r['temperature'] == t for r in entry['runs'])} |" in out for t in temperatures)
    assert (module.FIGURES / f"{sweep.name}_greediness.png").stat().st_size > 0
    assert json.loads(module.OUT.read_text()) == [entry]


def test_latents_evidence_refuses_bad_input(tmp_path, capsys):
    """No command, an unknown one, the wrong number of sweeps or no such sweep: a message and
    status 2, with nothing written."""
    module = _experiment("latents_evidence")
    module.DOCS = tmp_path / "docs"
    for argv in ([], ["bogus", "x"], ["curves", "one"], ["staleness", "a", "b"]):
        assert module.main(argv) == 2 and "latents_evidence.py curves STORED REENCODE" in capsys.readouterr().err
    assert module.main(["staleness", str(tmp_path / "nowhere")]) == 2
    assert "does not exist" in capsys.readouterr().err and not module.DOCS.exists()


def test_reconstruction_evidence_policies_and_paired_test_on_planted_numbers(tiny_sweep):
    """Planted errors: run i's VAE on run j's views costs 100 * (i's group) + (j's group); the
    per-policy table must average exactly the pairs of other runs, and the paired test must be
    Student's t on the differences."""
    module = _experiment("reconstruction_evidence")  # a fresh module: no OUT set by another test
    sweep = an.load(tiny_sweep)
    groups = sweep.groups()
    gid = np.empty(sweep.n_runs, int)
    for k, g in enumerate(groups):
        gid[g.indices] = k
    by_source = (100.0 * gid[:, None] + gid[None, :])[..., None].repeat(2, axis=2)
    idx = np.arange(sweep.n_runs)
    by_source[idx, idx] = np.nan
    error = np.nanmean(by_source, axis=1) + 0.5 * (idx % 2)[:, None]  # a little spread within each group
    q = an.ReconstructionQuality([100, 200], 200, 4, error, error / 100, by_source)
    out = module.by_policy(sweep, q)
    for k, g in enumerate(out["groups"]):
        assert g["group"] == groups[k].label
        assert g["on_views_of"] == {h.label: pytest.approx(100.0 * k + m) for m, h in enumerate(groups)}
        assert g["error"]["mean"] == pytest.approx(error[groups[k].indices, -1].mean())
    assert out["anova_p"]["error"] < 1e-6  # the groups differ by 100 with a spread below 4
    d = np.array([3.0, 5.0, 4.0, 8.0])
    t = module.paired(d + 10.0, np.full(4, 10.0))
    want_t = d.mean() / (d.std(ddof=1) / 2.0)
    assert t["diff"] == pytest.approx(d.mean()) and t["n"] == 4
    assert t["p"] == pytest.approx(an.t_pvalue(want_t, 3))
    assert math.isnan(module.paired(np.ones(3), np.ones(3))["p"])  # no spread, no test


# ------------------------------------------------------------- the paper's experiments at their full length


def _full_length_module():
    return _experiment("full_length_evidence")


def _experiment(name: str):
    """experiments/<name>.py loaded as a module of its own."""
    spec = importlib.util.spec_from_file_location(f"mjx_curio_{name}", ROOT / "experiments" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _refuses_bad_sweeps(module, script: str, tiny_sweep, tmp_path, capsys) -> None:
    """An evidence script's command line: no such sweep, a sweep without checkpoints (what a
    snapshot keeps) and no argument are each one line on stderr and status 2, and nothing is
    written under tmp_path/out."""
    assert module.main([str(tmp_path / "nowhere")]) == 2 and "does not exist" in capsys.readouterr().err
    metrics_only = _copy_sweep(tiny_sweep, tmp_path / "metrics_only")
    assert module.main([str(metrics_only)]) == 2 and f"{script}:" in capsys.readouterr().err
    assert module.main([]) == 2 and f"{script} runs/paper" in capsys.readouterr().err
    assert module.main(["a", "b"]) == 2 and "want one sweep directory, got 2 arguments" in capsys.readouterr().err
    assert module.main(["--help"]) == 0 and f"{script} runs/paper" in capsys.readouterr().out
    assert not (tmp_path / "out").exists()


def _evidence_on_tiny_sweep(name: str, tiny_sweep, tmp_path, capsys):
    """(module, entry, sweep): experiments/<name>_evidence.py, writing docs/results/<name>.json
    under tmp_path/out instead, checked to refuse bad sweeps, then run on the tiny sweep."""
    module = _experiment(f"{name}_evidence")
    module.OUT = tmp_path / "out" / f"{name}.json"
    _refuses_bad_sweeps(module, f"{name}_evidence.py", tiny_sweep, tmp_path, capsys)
    return module, module.evidence(str(tiny_sweep)), an.load(tiny_sweep)


def test_the_committed_full_length_numbers_are_what_their_runs_give(full_length_page):
    # The tests' p-values against SciPy's, from the per-run numbers the file keeps; Holm's
    # correction recomputed; the verdicts' sweep is the main job's shape.
    stats = pytest.importorskip("scipy.stats")
    if not full_length_page.FULL_LENGTH.exists():
        pytest.skip("no full-length sweep measured")
    doc = json.loads(full_length_page.FULL_LENGTH.read_text())
    for e in doc["sweeps"]:
        _check_full_length_sweep(e, stats)
    assert len({(e["preset"], e["platform"]) for e in doc["sweeps"]}) == len(doc["sweeps"])  # one entry each
    for a in doc.get("one_against_two", []):
        _check_one_against_two(doc, a, stats)
    by = {x["sweep"]: x for x in doc["sweeps"]}
    for t in doc.get("across_platforms", []):  # each side's per-run numbers its own entry's last steps
        assert (by[t["cpu"]]["platform"], by[t["gpu"]]["platform"]) == ("cpu", "gpu")
        assert by[t["cpu"]]["preset"] == by[t["gpu"]]["preset"] == t["preset"]
        late = {w: {(h["group"], h["measure"]): h["second"] for h in by[t[w]]["halves"]} for w in ("cpu", "gpu")}
        _check_two_against_one(t["rows"], late, stats, ("cpu", "gpu"))


def _check_one_against_two(doc: dict, a: dict, stats):
    """A one-agent sweep against a two-agent one: each side's per-run numbers are its own entry's
    last steps, Welch's test and Holm's correction SciPy's, claim 3's row the UCB rule."""
    by = {x["sweep"]: x for x in doc["sweeps"]}
    assert by[a["one"]]["agents"] == 1 and by[a["two"]]["agents"] == 2
    assert a["on"] == [by[a["one"]]["platform"], by[a["two"]]["platform"]]
    late = {w: {(h["group"], h["measure"]): h["second"] for h in by[a[w]]["halves"]} for w in ("one", "two")}
    _check_two_against_one(a["rows"], late, stats)
    if "committed" in a:  # the same on the committed runs: each side's `platforms` numbers of them
        c = a["committed"]
        assert (c["one"], c["two"]) == (by[a["one"]]["committed"]["sweep"], by[a["two"]]["committed"]["sweep"])
        assert c["steps"] == by[a["one"]]["committed"]["steps"] == by[a["two"]]["committed"]["steps"]
        short = {w: {(r["group"], r["measure"]): r["short"] for r in by[a[w]]["platforms"]} for w in ("one", "two")}
        _check_two_against_one(c["rows"], short, stats)
        assert [(r["group"], r["measure"]) for r in c["rows"]] == [(r["group"], r["measure"]) for r in a["rows"]]
    if "changes" in a:  # each run's change over the second half: its entry's late steps minus its earlier ones
        ch = a["changes"]
        assert ch["steps"] == [by[a["one"]]["committed"]["steps"] - a["late_steps"], by[a["one"]]["committed"]["steps"]]
        change = {w: {(h["group"], h["measure"]): [y - x for x, y in zip(h["first"], h["second"])]
                      for h in by[a[w]]["halves"]} for w in ("one", "two")}
        for r in ch["rows"]:
            for w in ("one", "two"):
                assert r[w] == pytest.approx(change[w][(r["group"], r["measure"])], rel=1e-12)
                change[w][(r["group"], r["measure"])] = r[w]  # the rounding of the JSON's floats aside
        _check_two_against_one(ch["rows"], change, stats)
        assert [(r["group"], r["measure"]) for r in ch["rows"]] == [(r["group"], r["measure"]) for r in a["rows"]]
    ucb = [r for r in a["rows"] if r["group"].startswith("UCB") and r["measure"] in ("curiosity", "vae_loss")]
    [row] = [r for r in doc["claims"] if r["claim"] == "3" and r["on"] == a["on"][::-1]] if ucb else [None]
    if ucb:
        holds = all(r["p"] < 0.05 and r["diff"] > 0 for r in ucb)
        assert row["verdict"].startswith("holds" if holds else "does not hold")


def _check_two_against_one(rows: list, runs: dict, stats, names=("one", "two")):
    """Each row's per-run numbers are `runs`' ({"one", "two": {(group, measure): list}}, or the
    sides `names`), its Welch test SciPy's (the second side against the first), and Holm's
    correction over the rows recomputed."""
    ps = []
    a, b = names
    for r in rows:
        assert r[a] == runs[a][(r["group"], r["measure"])] and r[b] == runs[b][(r["group"], r["measure"])]
        want = stats.ttest_ind(np.array(r[b]), np.array(r[a]), equal_var=False)
        assert r["p"] == pytest.approx(want.pvalue, rel=1e-6) and r["t"] == pytest.approx(want.statistic, rel=1e-6)
        ps.append(r["p"])
    order = np.argsort(ps)
    want_holm = np.maximum.accumulate(np.minimum(1.0, (len(ps) - np.arange(len(ps))) * np.array(ps)[order]))
    assert [rows[i]["p_holm"] for i in order] == pytest.approx(list(want_holm))


def _check_full_length_sweep(e: dict, stats):
    assert e["steps"] > e["committed"]["steps"] and e["runs"] <= e["committed"]["runs"]
    for rows, test, a, b in (("platforms", stats.ttest_ind, "long", "short"), ("halves", stats.ttest_rel, "second", "first")):
        ps = []
        for r in e[rows]:
            x, y = np.array(r[a], float), np.array(r[b], float)
            want = test(x, y, equal_var=False) if test is stats.ttest_ind else test(x, y)
            assert r["p"] == pytest.approx(want.pvalue, rel=1e-6, abs=1e-12), (rows, r["group"], r["measure"])
            assert r["diff"] == pytest.approx(np.mean(x) - np.mean(y), rel=1e-6, abs=1e-9)
            ps.append(r["p"])
        order = np.argsort(ps)
        m = len(ps)
        want_holm = np.maximum.accumulate(np.minimum(1.0, (m - np.arange(m)) * np.array(ps)[order]))
        assert [e[rows][i]["p_holm"] for i in order] == pytest.approx(list(want_holm))


def test_holm_on_planted_p_values():
    module = _full_length_module()
    # sorted 0.01, 0.02, 0.03, 0.5 of four tests: 0.04, 0.06, 0.06 (kept monotone), 0.5; None is no test
    assert module.holm([0.03, 0.5, None, 0.01, 0.02]) == pytest.approx([0.06, 0.5, None, 0.04, 0.06])
    assert module.holm([]) == []


def test_full_length_evidence_on_the_tiny_sweep(full_length_page, tiny_sweep, tiny_single_sweep, tmp_path, monkeypatch):
    """The tiny sweep's 200 steps as the long sweep, its first 100 as the committed one: the same
    runs over the same steps differ by nothing, and the halves' paired test is Student's t on
    each run's own numbers."""
    module = _full_length_module()
    monkeypatch.setattr(module, "LATE_STEPS", 40)
    monkeypatch.setattr(module, "BIN_STEPS", 40)
    long = an.load(tiny_sweep)
    short = an.load(_copy_sweep(tiny_sweep, tmp_path / "first_half", windows_done=long.metrics["curiosity"].shape[1] // 2))
    assert short.steps_done == long.steps_done // 2
    with pytest.raises(ValueError, match="no committed runs of multi_agent"):
        module.evidence({("multi_agent", "cpu"): long}, {})
    whole = module.evidence({("multi_agent", "cpu"): long}, {"multi_agent": short})
    assert [(x["preset"], x["platform"]) for x in whole["sweeps"]] == [("multi_agent", "cpu")]
    assert {(tuple(r["presets"]), tuple(r["on"])) for r in whole["claims"]} <= {(("multi_agent",), ("cpu",))}
    e = whole["sweeps"][0]
    assert e["agents"] == 2 and e["steps"] == long.steps_done and e["committed"]["steps"] == short.steps_done
    measures = 4
    assert len(e["platforms"]) == len(e["halves"]) == measures * len(long.groups())
    for r in e["platforms"]:
        assert r["long"] == r["short"]
        assert r["diff"] == 0.0 and r["p"] in (None, 1.0)
    steps = long.steps
    late = (steps > long.steps_done - 40) & (steps <= long.steps_done)
    g = long.groups()[0]
    want = np.nanmean(long.metrics["curiosity"][g.indices][:, late].mean(axis=2), axis=1)
    assert e["halves"][0]["measure"] == "curiosity" and e["halves"][0]["second"] == pytest.approx(list(want), rel=1e-5)
    assert e["curves"]["long"]["steps"] == list(range(40, long.steps_done + 1, 40))
    for key, counts in (("object_contacts", an.object_contacts(long)), ("agent_contacts", an.agent_contacts(long))):
        assert [r[-1] for r in e["curves"]["long"][key]] == counts.sum(axis=1).tolist(), key  # summed from the start
    path = tmp_path / "full_length.json"
    path.write_text(json.dumps(whole))
    block = full_length_page.full_length_block(path)
    assert block.count("| curiosity |") == 2 * len(long.groups())
    assert "Holm's correction over the table's" in block and "full_length_multi_agent_cpu_curiosity.png" in block
    full_length_page.full_length_figure(path, tmp_path / "figures", dpi=40)  # save_figure refuses a panel with nothing drawn
    for name in ("full_length_multi_agent_cpu_curiosity", "full_length_multi_agent_cpu_interactions"):
        assert (tmp_path / "figures" / f"{name}.png").is_file(), name
    with pytest.raises(ValueError, match="other settings"):
        module.sweep_evidence("multi_agent", long, an.load(tiny_single_sweep))
    with pytest.raises(ValueError, match="no more than"):
        module.sweep_evidence("multi_agent", short, long)
    assert full_length_page.full_length_block(tmp_path / "missing.json").startswith("No sweep of the paper's full length")


def test_claim_14_of_one_and_two_agents_reduced_together_on_one_platform(tiny_sweep, tiny_single_sweep, tmp_path,
                                                                         monkeypatch):
    """Claim 14 needs each run's VAE loss over the second half, which the file does not keep: the
    reduction tests it on a one-agent and a two-agent sweep given together, of one length, on one
    platform, as the claims table tests the same pair."""
    from mjx_curio.analysis.claims import curiosity

    module = _full_length_module()
    one, two = an.load(tiny_single_sweep), an.load(tiny_sweep)
    both = {("single_agent", "cpu"): one, ("multi_agent", "cpu"): two}
    assert module.vae_unsettled(both) == []  # 200 steps and 1-2 seeds: not testable at this scale
    monkeypatch.setattr(curiosity, "_scale_gaps", lambda items: None)
    [row] = module.vae_unsettled(both)
    [want] = [r for r in an.claims_table({"single_agent": one, "multi_agent": two}).rows if r[0] == "14"]
    assert (row["claim"], row["text"], row["statistic"], row["verdict"]) == (want[0], want[1], want[3], want[4])
    assert (row["presets"], row["on"]) == (["multi_agent", "single_agent"], ["cpu", "cpu"])
    assert module.vae_unsettled({("single_agent", "cpu"): one, ("multi_agent", "gpu"): two}) == []
    half = an.load(_copy_sweep(tiny_sweep, tmp_path / "half", windows_done=two.metrics["curiosity"].shape[1] // 2))
    assert module.vae_unsettled({("single_agent", "cpu"): one, ("multi_agent", "cpu"): half}) == []
    assert module.vae_unsettled({("multi_agent", "cpu"): two}) == []


def test_full_length_evidence_sets_fewer_runs_beside_all_the_committed_ones(full_length_page, tiny_sweep, tmp_path, monkeypatch):
    """A full-length sweep of some of the committed policies and seeds (on a CPU, fig. 8's
    ε-greedy runs alone) is compared with every committed run of its settings; one with a run the
    committed ones lack is refused."""
    module = _full_length_module()
    monkeypatch.setattr(module, "LATE_STEPS", 40)
    monkeypatch.setattr(module, "BIN_STEPS", 40)
    whole = an.load(tiny_sweep)
    eps, ucb = whole.select(policy="eps"), whole.select(policy="ucb")
    long = an.load(_subset_sweep(tiny_sweep, tmp_path / "some", [*eps, ucb[0]]))
    short = an.load(_copy_sweep(tiny_sweep, tmp_path / "first_half", windows_done=whole.n_windows // 2))
    e = module.evidence({("multi_agent", "cpu"): long}, {"multi_agent": short})["sweeps"][0]
    assert e["runs"] == len(eps) + 1 and e["committed"]["runs"] == whole.n_runs
    by_group = {r["group"]: r for r in e["platforms"] if r["measure"] == "curiosity"}
    assert sorted(by_group) == sorted(g.label for g in long.groups())
    ucb_label = long.groups("ucb")[0].label
    assert len(by_group[ucb_label]["long"]) == 1 and len(by_group[ucb_label]["short"]) == len(ucb)
    eps_label = long.groups("eps")[0].label
    assert by_group[eps_label]["long"] == by_group[eps_label]["short"]  # the same runs over the same steps
    assert full_length_page._same_runs(e) == f"The same settings ({eps_label}: {len(eps)} against {len(eps)} seeds; " \
                                    f"{ucb_label}: 1 against {len(ucb)} seeds)"
    all_but_one = [i for i in range(whole.n_runs) if i != ucb[1]]
    with pytest.raises(ValueError, match=r"has runs the committed runs .* lack \(ucb seed 1\)"):
        module.sweep_evidence("multi_agent", an.load(_copy_sweep(tiny_sweep, tmp_path / "all")),
                              an.load(_subset_sweep(tiny_sweep, tmp_path / "fewer", all_but_one, windows_done=1)))


def test_full_length_evidence_keeps_what_the_file_holds_of_other_presets():
    module = _full_length_module()
    # An entry written before entries recorded their platform has its machine's.
    sweep = lambda preset, platform="cpu": {"preset": preset, "sweep": preset, "device": {"platform": platform}}  # noqa: E731
    row = lambda claim, *presets, on="cpu": {"claim": claim, "verdict": claim + "".join(presets), **(  # noqa: E731
        {"presets": list(presets), "on": [on] * len(presets)} if presets else {})}
    assert module.merged(None, {"claims": [], "sweeps": []}) == {"claims": [], "sweeps": []}
    # A file written before its rows named their presets and platforms: they came from its one sweep.
    old = {"claims": [row("1"), row("15"), row("6a")], "sweeps": [sweep("multi_agent", "gpu")]}
    new = {"claims": [row("1", "single_agent"), row("13", "single_agent")], "sweeps": [sweep("single_agent")]}
    both = module.merged(old, new)
    assert [(r["claim"], r["presets"], r["on"]) for r in both["claims"]] == [
        ("1", ["multi_agent"], ["gpu"]), ("1", ["single_agent"], ["cpu"]), ("6a", ["multi_agent"], ["gpu"]),
        ("13", ["single_agent"], ["cpu"]), ("15", ["multi_agent"], ["gpu"])]
    assert [x["preset"] for x in both["sweeps"]] == ["multi_agent", "single_agent"]
    # The same preset on another platform stands beside it: nothing of the GPU entry is dropped.
    cpu = module.merged(both, {"claims": [row("1", "multi_agent")], "sweeps": [sweep("multi_agent")]})
    assert [(r["claim"], r["on"]) for r in cpu["claims"] if r["presets"] == ["multi_agent"]] == [
        ("1", ["cpu"]), ("1", ["gpu"]), ("6a", ["gpu"]), ("15", ["gpu"])]
    assert [module.entry_key(x) for x in cpu["sweeps"]] == [
        ("multi_agent", "cpu"), ("multi_agent", "gpu"), ("single_agent", "cpu")]
    # Measured anew, an entry's sweep and every row computed from it are replaced.
    again = module.merged(both, {"claims": [row("2", "multi_agent", on="gpu")],
                                 "sweeps": [{**sweep("multi_agent", "gpu"), "new": 1}]})
    assert [(r["claim"], r["presets"]) for r in again["claims"]] == [
        ("1", ["single_agent"]), ("2", ["multi_agent"]), ("13", ["single_agent"])]
    assert [x.get("new") for x in again["sweeps"]] == [1, None]
    assert module.merged({"claims": [row("3", "multi_agent", "single_agent")], "sweeps": []}, new)["claims"] == new["claims"]
    assert module.platform_of([{"platform": "gpu"}, {"platform": "gpu"}]) == "gpu"
    assert module.platform_of([{"platform": "gpu"}, {"platform": "cpu"}]) == "cpu+gpu"


def test_full_length_evidence_refuses_to_drop_runs_the_file_holds(tiny_sweep, tmp_path, capsys, monkeypatch):
    """Measuring a preset anew replaces its entry whole: sweeps with fewer runs of a policy than
    the file holds of that preset are refused before anything is reduced, the file left as it is."""
    module = _full_length_module()
    sweep = an.load(tiny_sweep)
    key = next(iter(module.stands_for(an.assign_presets([sweep]))))
    preset, platform = key
    assert platform == "cpu"
    counts = {g.label: len(g.indices) for g in sweep.groups()}
    first = next(iter(counts))
    entry = lambda extra: {"preset": preset, "platform": platform, "sweep": "held", "curves": {"groups": {  # noqa: E731
        label: list(range(n + (extra if label == first else 0))) for label, n in counts.items()}}}
    # As many runs of every policy as the file holds, or more: nothing is lost.
    for extra in (0, -1):
        assert module.lost_runs({"claims": [], "sweeps": [entry(extra)]}, {key: sweep}) == []
    assert module.lost_runs(None, {key: sweep}) == []
    assert module.lost_runs({"claims": [], "sweeps": [{**entry(1), "preset": "another"}]}, {key: sweep}) == []
    # The preset on another platform is another entry, which the file keeps beside the new one.
    assert module.lost_runs({"claims": [], "sweeps": [{**entry(1), "platform": "gpu"}]}, {key: sweep}) == []
    # One run more of the first policy in the file, and a policy the sweep lacks.
    held = {**entry(1), "curves": {"groups": {**entry(1)["curves"]["groups"], "UCB (c=9)": [0, 1]}}}
    assert module.lost_runs({"claims": [], "sweeps": [held]}, {key: sweep}) == [
        f"{preset} on CPU (`held`; {first}: {counts[first] + 1} runs against {counts[first]}, "
        "UCB (c=9): 2 runs against 0)"]
    out = tmp_path / "full_length.json"
    out.write_text(json.dumps({"claims": [], "sweeps": [held]}))
    before = out.read_text()
    monkeypatch.setattr(module, "OUT", out)
    assert module.main([str(tiny_sweep)]) == 2
    err = capsys.readouterr().err
    assert "holds runs the sweeps given lack" in err and f"{first}: {counts[first] + 1} runs against" in err
    assert "move the file aside" in err and out.read_text() == before


def test_contact_timing_of_a_full_length_sweep_from_planted_cumulative_curves(full_length_page):
    # 80 bins of 1,000 steps. "steady": 2 contact steps a bin before step 25,000 and 4 + the run's
    # index after; "stops": 6 a bin up to step 30,000, none after, in two runs of three.
    steps = list(range(1000, 80_001, 1000))
    per_bin = []
    for k in range(3):
        per_bin.append([2 if s <= 25_000 else 4 + k for s in steps])
    for k in range(3):
        per_bin.append([6 if s <= 30_000 or k == 2 else 0 for s in steps])
    cum = np.cumsum(per_bin, axis=1).tolist()
    e = {"curves": {"bin_steps": 1000, "groups": {"steady": [0, 1, 2], "stops": [3, 4, 5]},
                    "long": {"steps": steps, "object_contacts": cum}}}
    lines = full_length_page._contact_timing(e)
    rows = {r.split(" | ")[0].strip("| "): r.split(" | ") for r in lines if r.startswith(("| steady", "| stops"))}
    assert rows["steady"][1:3] == ["2.0", "5.0"]  # before, after: 4, 5, 6 a bin
    assert rows["steady"][3] == "3.0 [0.5, 5.5]"  # 2, 3, 4: mean 3, t(0.975, 2) x 1 / sqrt(3)
    assert rows["steady"][4] == f"{an.t_pvalue(3 * math.sqrt(3), 2):.2g}"
    share = np.mean([100 * (25 * 2 + 15 * (4 + k)) / (25 * 2 + 55 * (4 + k)) for k in range(3)])  # by step 40,000
    assert rows["steady"][5].startswith(f"{share:.0f} % [")
    assert rows["steady"][6] == "3 of 3 |" and rows["stops"][6] == "1 of 3 |"
    # Too short a run for the marks: no table.
    short = {"curves": {"bin_steps": 1000, "groups": {"steady": [0]},
                        "long": {"steps": steps[:30], "object_contacts": [c[:30] for c in cum[:1]]}}}
    assert full_length_page._contact_timing(short) == []


def test_the_paper_readings_figure_has_a_panel_for_each_loaded_preset(results, tmp_path):
    from test_claims import POLICIES, fake_sweep

    single = fake_sweep("single_agent", 1, POLICIES, 100, seeds=3)
    single.metrics["curiosity"][:] = 0.4
    results.paper_readings_figure({"single_agent": single}, path=tmp_path / "none.json", out=tmp_path)
    assert (tmp_path / f"{results.PAPER_READINGS}.png").is_file()  # save_figure refuses an empty panel
    results.paper_readings_figure({}, path=tmp_path / "none.json", out=tmp_path / "nothing")
    assert not (tmp_path / "nothing").exists()


def test_claim_15_row_of_a_full_length_sweep_from_planted_cumulative_curves(full_length_page):
    # A full_length.json written before claim 15 existed: its row comes from the curves' last
    # points, each run's agent-agent contact steps, and says what the claim itself would.
    steps = list(range(1000, 80_001, 1000))
    totals = [3, 4, 5, 40, 60, 50, 100, 100, 100]
    curves = [np.linspace(0, t, len(steps)).round().tolist() for t in totals]
    labels = {"ε-greedy (ε=0.2)": [0, 1, 2], "Boltzmann (T=1.5)": [3, 4, 5], "UCB (c=1)": [6, 7, 8]}
    e = {"agents": 2, "sweep": "main", "curves": {"groups": labels, "long": {"steps": steps, "agent_contacts": curves}}}
    [row] = full_length_page._agent_contact_order_row(e)
    assert row.startswith("| 15 | Boltzmann agents touch each other more often than ε-greedy agents")
    assert "ε-greedy 4 [" in row and "Boltzmann 50 [" in row and "(50 % of UCB's)" in row
    assert row.endswith("| holds (Welch p < 0.05, Boltzmann > ε-greedy) |")
    assert full_length_page._agent_contact_order_row({**e, "agents": 1}) == []
    ucb_only = {**e, "curves": {**e["curves"], "groups": {"UCB (c=1)": [6, 7, 8]}}}  # a sweep of one policy
    assert full_length_page._agent_contact_order_row(ucb_only) == []
    short = {**e, "curves": {"groups": labels, "long": {"steps": steps[:40], "agent_contacts": [c[:40] for c in curves]}}}
    assert full_length_page._agent_contact_order_row(short) == []


def test_full_length_evidence_refuses_bad_command_lines(tiny_sweep, tmp_path, capsys, monkeypatch):
    module = _full_length_module()
    monkeypatch.setattr(module, "OUT", tmp_path / "out" / "full_length.json")
    assert module.main([]) == 2 and "full_length_evidence.py runs/h200/main" in capsys.readouterr().err
    assert module.main([str(tmp_path / "nowhere")]) == 2
    assert "full_length_evidence.py:" in capsys.readouterr().err
    # two sweeps of one preset's settings: the second stands for nothing
    twin = _copy_sweep(tiny_sweep, tmp_path / "twin")
    assert module.main([str(tiny_sweep), str(twin)]) == 2
    assert "twin: fits no preset, or one another sweep given already stands for" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
    # A damaged full_length.json is named and left as it is.
    bad = tmp_path / "out" / "full_length.json"
    bad.parent.mkdir()
    for text, says in (("{not json", "is not JSON"), ("[]", "has no claims and sweeps")):
        bad.write_text(text)
        assert module.main([str(tiny_sweep)]) == 2
        err = capsys.readouterr().err
        assert f"{bad}" in err and says in err and "move it aside" in err
        assert bad.read_text() == text


def test_a_side_experiment_stands_for_its_preset_at_the_full_length():
    module = _full_length_module()
    on = lambda name, platform: types.SimpleNamespace(name=name, manifest={"device": {"platform": platform}})  # noqa: E731
    s, t, g = on("a", "cpu"), on("b", "cpu"), on("main", "gpu")
    assert module.stands_for({"multi_agent.full_length": s, "single_agent": t}) == {
        ("multi_agent", "cpu"): s, ("single_agent", "cpu"): t}
    # The main job on a GPU and some of its runs again on a CPU: two entries, not one merged sweep.
    assert module.stands_for({"multi_agent": g, "multi_agent.full_length_ucb": s}) == {
        ("multi_agent", "gpu"): g, ("multi_agent", "cpu"): s}


def test_sweeps_of_one_presets_different_policies_stand_for_it_together(tiny_sweep, tmp_path, monkeypatch):
    """`single_agent.full_length` (ε-greedy, its seeds in two parts, the second
    `single_agent.full_length.seeds-3-5`) and `single_agent.full_length_ucb` (UCB), as the tiny
    sweep's runs of each policy: one sweep of all, whose entry names them, keeps each part's
    command and their one machine once; a run in two is refused, naming it."""
    module = _full_length_module()
    whole = an.load(tiny_sweep)
    eps, ucb = whole.select(policy="eps"), whole.select(policy="ucb")
    assert [whole.runs[i].seed for i in eps] == [0, 1]
    parts = {}
    for name, runs, policy in (("multi_agent.full_length", eps[:1], "eps"), ("multi_agent.full_length.seeds-1", eps[1:], "eps"),
                               ("multi_agent.full_length_ucb", ucb, "ucb")):
        path = _subset_sweep(tiny_sweep, tmp_path / name, list(runs))
        manifest = json.loads((path / "manifest.json").read_text())
        manifest["config"]["policies"] = [policy]
        manifest["command"] += f" out={name}"  # each part its own command
        (path / "manifest.json").write_text(json.dumps(manifest))
        parts[name] = an.load(path)
    [(key, both)] = module.stands_for(an.assign_presets(parts)).items()
    assert key == ("multi_agent", "cpu") and both.name == "multi_agent.full_length.seeds-0-1 + multi_agent.full_length_ucb"
    assert [p.name for p in both.parts] == list(parts)  # the sweeps read from disk, seed parts and all
    assert [p["path"] for p in both.manifest["parts"]] == [str(tmp_path / name) for name in parts]
    assert [g.policy for g in both.groups()] == ["eps", "ucb"] and both.n_runs == len(eps) + len(ucb)
    assert np.array_equal(both.metrics["curiosity"], whole.metrics["curiosity"][[*eps, *ucb]])
    monkeypatch.setattr(module, "LATE_STEPS", 40)
    monkeypatch.setattr(module, "BIN_STEPS", 40)
    short = an.load(_copy_sweep(tiny_sweep, tmp_path / "first_half", windows_done=whole.n_windows // 2))
    e = module.sweep_evidence("multi_agent", both, short)
    assert e["sweep"] == both.name and e["runs"] == both.n_runs
    assert e["command"] == " && ".join(p.manifest["command"] for p in parts.values())
    assert e["device"] == whole.manifest["device"]  # one machine: its record once, not a list
    again = an.load(_subset_sweep(tiny_sweep, tmp_path / "again", [eps[0]]))
    with pytest.raises(an.SweepError, match="seed"):
        module.stands_for({**parts, "multi_agent.again": again})


def _late_entry(preset: str, agents: int, late: dict, steps: int = 80_000, platform: str = "cpu") -> dict:
    """A full-length entry of `preset` on `platform` whose runs' last-steps measures are `late`
    ({group: {measure: per-run list}})."""
    halves = [{"group": g, "measure": m, "what": m, "second": v} for g, ms in late.items() for m, v in ms.items()]
    first = np.cumsum([0] + [len(ms["curiosity"]) for ms in late.values()])
    groups = {g: list(range(a, b)) for g, a, b in zip(late, first[:-1], first[1:])}
    bins = list(range(1000, steps + 1, 1000))
    runs = [[c] * len(bins) for ms in late.values() for c in ms["curiosity"]]  # flat at the late level
    device = {"platform": "cpu", "cpu": "X"} if platform == "cpu" else {"platform": platform, "kind": "NVIDIA Z"}
    return {"preset": preset, "platform": platform, "sweep": f"{preset}.long_{platform}", "agents": agents,
            "steps": steps, "late_steps": 10_000, "halves": halves, "device": device,
            "curves": {"bin_steps": 1000, "groups": groups, "long": {"steps": bins, "runs": runs}}}


def test_one_agent_against_two_at_the_full_length_on_planted_entries(full_length_page, tmp_path):
    # Two agents planted higher by 0.1 in curiosity and by 10 in the VAE loss, with a spread of
    # 0.01 and 1: claim 3 holds; the same runs the other way round: it does not.
    module = _full_length_module()
    spread = lambda m, n, d: [m + d * k for k in np.linspace(-1, 1, n)]  # noqa: E731
    ucb, eps = "UCB (c=1)", "ε-greedy (ε=0.2)"
    low = {"curiosity": spread(0.4, 3, 0.01), "vae_loss": spread(100, 3, 1), "recon": spread(70, 3, 1)}
    high = {"curiosity": spread(0.5, 8, 0.01), "vae_loss": spread(110, 8, 1), "recon": spread(80, 8, 1)}
    one = _late_entry("single_agent", 1, {eps: low, ucb: low})
    two = _late_entry("multi_agent", 2, {eps: high, ucb: high, "Boltzmann (T=1.5)": high})
    [a] = module.one_against_two([two, one])
    assert a["on"] == ["cpu", "cpu"]
    assert [(r["group"], r["measure"]) for r in a["rows"]] == [(g, m) for g in (eps, ucb) for m in module.AGENT_MEASURES]
    r = a["rows"][0]
    assert r["one"] == low["curiosity"] and r["two"] == high["curiosity"] and r["diff"] == pytest.approx(0.1)
    assert a["claim"]["claim"] == "3" and a["claim"]["verdict"] == "holds (both Welch tests p < 0.05, multi > single)"
    assert "mean over steps 70,000-80,000" in a["claim"]["statistic"] and a["claim"]["presets"] == ["multi_agent",
                                                                                                   "single_agent"]
    [swapped] = module.one_against_two([_late_entry("single_agent", 1, {ucb: high}), _late_entry("multi_agent", 2, {ucb: low})])
    assert swapped["claim"]["verdict"].startswith("does not hold: curiosity not significantly higher with two agents")
    assert module.one_against_two([one, {**two, "steps": 40_000}]) == []
    assert module.one_against_two([one]) == []
    assert module.one_against_two([_late_entry("single_agent", 1, {eps: low}), two])[0]["claim"] is None  # no UCB: no row
    # In the file: claim 3's row replaces one computed before from the same two presets, and the
    # page sets the table out.
    old = {"claim": "3", "verdict": "stale", "presets": ["multi_agent", "single_agent"]}
    doc = module.with_one_against_two({"claims": [{"claim": "13", "presets": ["single_agent"]}, old],
                                       "sweeps": [two, one]})
    assert [r["claim"] for r in doc["claims"]] == ["3", "13"] and doc["claims"][0]["verdict"].startswith("holds")
    [table] = doc["one_against_two"]
    assert set(table) == {"one", "two", "on", "steps", "late_steps", "rows"}
    lines = full_length_page._one_against_two(table, {x["sweep"]: x for x in doc["sweeps"]})
    assert "Holm's correction over the table's 6 tests" in lines[0] and "different machines" not in lines[0]
    assert f"| {ucb} | curiosity | 0.4 (3) | 0.5 (8) | +0.1 | {full_length_page._p(a['rows'][3]['p'])} " \
           f"| {full_length_page._p(a['rows'][3]['p_holm'])} |" in lines
    full_length_page._one_against_two_figure(doc, tmp_path, dpi=40)  # save_figure refuses a panel with nothing drawn
    assert (tmp_path / f"{full_length_page.ONE_AGAINST_TWO}.png").is_file()
    assert "one_against_two" not in module.with_one_against_two({"claims": [], "sweeps": [one]})
    # Two agents on a GPU (all the policies) and on a CPU (UCB, fewer seeds): two pairs, the one on
    # one platform first, each with its claim 3 row; the figure draws every sweep where it ran.
    gpu = _late_entry("multi_agent", 2, {eps: high, ucb: high}, platform="gpu")
    few = _late_entry("multi_agent", 2, {ucb: {k: v[:3] for k, v in low.items()}})
    doc = module.with_one_against_two({"claims": [old], "sweeps": [gpu, one, few]})
    assert [(t["two"], t["on"]) for t in doc["one_against_two"]] == [
        (few["sweep"], ["cpu", "cpu"]), (gpu["sweep"], ["cpu", "gpu"])]
    assert [(r["claim"], r["on"]) for r in doc["claims"]] == [("3", ["cpu", "cpu"]), ("3", ["gpu", "cpu"])]
    assert "(CPU) vs multi_agent.long_gpu (GPU)" in doc["claims"][1]["statistic"]
    assert doc["claims"][0]["verdict"].startswith("does not hold") and doc["claims"][1]["verdict"].startswith("holds")
    lines = full_length_page._one_against_two(doc["one_against_two"][1], {x["sweep"]: x for x in doc["sweeps"]})
    assert "on one NVIDIA Z" in lines[0] and "different machines" in lines[0]
    full_length_page._one_against_two_figure(doc, tmp_path / "three", dpi=40)
    assert (tmp_path / "three" / f"{full_length_page.ONE_AGAINST_TWO}.png").is_file()
    # The two-agent preset on both platforms: its GPU runs against its CPU ones over the same last
    # steps, per policy both ran (UCB) and measure both entries keep.
    [t] = doc["across_platforms"]
    assert (t["preset"], t["cpu"], t["gpu"]) == ("multi_agent", few["sweep"], gpu["sweep"])
    assert [(r["group"], r["measure"]) for r in t["rows"]] == [(ucb, m) for m in module.AGENT_MEASURES]
    assert t["rows"][0]["cpu"] == low["curiosity"][:3] and t["rows"][0]["gpu"] == high["curiosity"]
    assert t["rows"][0]["diff"] == pytest.approx(np.mean(high["curiosity"]) - np.mean(low["curiosity"][:3]))
    lines = full_length_page._across_platforms(t, {x["sweep"]: x for x in doc["sweeps"]})
    assert "`multi_agent.long_gpu` on one NVIDIA Z against `multi_agent.long_cpu` on a CPU (X)" in lines[0]
    assert "the table's 3 tests" in lines[0] and lines[4].startswith(f"| {ucb} | curiosity | ")
    assert "across_platforms" not in module.with_one_against_two({"claims": [], "sweeps": [one, few]})
    # Where both entries keep their committed runs' measures at one length, the same comparison
    # on those runs (planted the other way round: one agent the higher) follows the table.
    def committed(e, late, steps=40_000):
        return {**e, "committed": {"sweep": e["preset"], "steps": steps, "devices": [{"platform": "cpu", "cpu": "Y"}]},
                "platforms": [{"group": g, "measure": m, "what": m, "short": v} for g, ms in late.items() for m, v in ms.items()]}
    c = module.one_against_two([committed(one, {eps: high, ucb: high}), committed(two, {eps: low, ucb: low})])[0]["committed"]
    assert (c["one"], c["two"], c["steps"]) == ("single_agent", "multi_agent", 40_000)
    assert [(r["group"], r["measure"]) for r in c["rows"]] == [(r["group"], r["measure"]) for r in a["rows"]]
    assert c["rows"][0]["one"] == high["curiosity"] and c["rows"][0]["diff"] == pytest.approx(-0.1)
    assert "committed" not in module.one_against_two([committed(one, {ucb: high}), committed(two, {ucb: low}, 20_000)])[0]
    # The page sets out the committed runs' table once for pairs that share it, and again for a
    # pair whose two-agent sweep ran fewer policies (its table has other rows).
    ucb_only = module.one_against_two([committed(one, {eps: high, ucb: high}), committed(two, {ucb: low})])
    both = module.one_against_two([committed(one, {eps: high, ucb: high}), committed(two, {eps: low, ucb: low})])
    assert [r["group"] for r in ucb_only[0]["committed"]["rows"]] == [ucb] * len(module.AGENT_MEASURES)
    assert full_length_page._committed_shown(ucb_only + both) == [True, True]
    assert full_length_page._committed_shown(both + both) == [True, False]
    doc = module.with_one_against_two({"claims": [], "sweeps": [committed(two, {eps: low, ucb: low}),
                                                                committed(one, {eps: high, ucb: high})]})
    lines = full_length_page._one_against_two(doc["one_against_two"][0], {x["sweep"]: x for x in doc["sweeps"]})
    at = lines.index("The same over the committed runs' last 10,000 steps (steps 30,000-40,000): `single_agent` on a "
                     "CPU (Y) against `multi_agent` on a CPU (Y), all their seeds, Holm's correction over the table's "
                     "6 tests:")
    assert lines[at + 4].startswith(f"| {eps} | curiosity | 0.5 (8) | 0.4 (3) | -0.1 |")  # high has 8 runs, low 3
    assert not any(line.startswith("The same over the committed runs") for line in full_length_page._one_against_two(
        doc["one_against_two"][0], {x["sweep"]: x for x in doc["sweeps"]}, committed=False))
    assert not any(line.startswith("What the second half changes") for line in lines)  # no earlier steps kept
    # Where both entries keep each run's measures over the committed runs' last steps too, each
    # run's change over the second half, two agents against one: planted, run i of one agent's
    # VAE loss falls by 10 + 0.2 i and of two agents' by 4 + 0.2 i, every other measure by 0.2 i.
    stats = pytest.importorskip("scipy.stats")

    def halved(e, fall):
        return {**committed(e, {}), "halves": [{**h, "first": [v + fall.get(h["measure"], 0) + 0.2 * i
                                                               for i, v in enumerate(h["second"])]} for h in e["halves"]]}
    doc = module.with_one_against_two({"claims": [], "sweeps": [halved(two, {"vae_loss": 4}), halved(one, {"vae_loss": 10})]})
    ch = doc["one_against_two"][0]["changes"]
    assert ch["steps"] == [30_000, 40_000]
    falls = lambda n, by: {(g, m): [-(by.get(m, 0) + 0.2 * i) for i in range(n)]  # noqa: E731
                           for g in (eps, ucb) for m in module.AGENT_MEASURES}
    want = {"one": falls(3, {"vae_loss": 10}), "two": falls(8, {"vae_loss": 4})}
    for r in ch["rows"]:
        for w in ("one", "two"):
            assert r[w] == pytest.approx(want[w][(r["group"], r["measure"])])
            want[w][(r["group"], r["measure"])] = r[w]  # to the last bit, for the tests' check
    _check_two_against_one(ch["rows"], want, stats)
    [loss] = [r for r in ch["rows"] if r["group"] == ucb and r["measure"] == "vae_loss"]
    assert loss["diff"] == pytest.approx(-4.7 + 10.2) and loss["p"] < 1e-6
    lines = full_length_page._one_against_two(doc["one_against_two"][0], {x["sweep"]: x for x in doc["sweeps"]})
    at = next(i for i, line in enumerate(lines) if line.startswith("What the second half changes"))
    assert "from steps 30,000-40,000 to 70,000-80,000" in lines[at] and "the table's 6 tests" in lines[at]
    assert f"| {ucb} | vae_loss | -10.2 (3) | -4.7 (8) | +5.5 | {full_length_page._p(loss['p'])} " \
           f"| {full_length_page._p(loss['p_holm'])} |" in lines[at + 2:at + 10]
    other = {**halved(two, {}), "committed": {"sweep": "multi_agent", "steps": 20_000, "devices": []}}
    assert "changes" not in module.one_against_two([halved(one, {}), other])[0]  # earlier steps that differ


# ---------------------------------------------------------------------- snapshots of tiny sweeps


def _copy_sweep(src: pathlib.Path, dst: pathlib.Path, windows_done: int | None = None) -> pathlib.Path:
    """What the analysis reads of a sweep, optionally as if it had only `windows_done` windows."""
    (dst / "metrics").mkdir(parents=True)
    for f in ("manifest.json", "progress.json"):
        shutil.copy2(src / f, dst / f)
    for f in (src / "metrics").glob("*.npy"):
        shutil.copy2(f, dst / "metrics" / f.name)
    if windows_done is not None:
        p = json.loads((dst / "progress.json").read_text())
        p["windows_done"] = windows_done
        (dst / "progress.json").write_text(json.dumps(p))
    return dst


def _subset_sweep(src: pathlib.Path, dst: pathlib.Path, keep: list[int], windows_done: int | None = None) -> pathlib.Path:
    """`_copy_sweep` of the runs `keep` (indices of `src`'s runs axis) alone, as if a sweep had
    run only those."""
    _copy_sweep(src, dst, windows_done)
    manifest = json.loads((dst / "manifest.json").read_text())
    manifest["runs"] = [{**manifest["runs"][i], "index": k} for k, i in enumerate(keep)]
    (dst / "manifest.json").write_text(json.dumps(manifest))
    for f in (dst / "metrics").glob("*.npy"):
        if f.name != "steps.npy":
            np.save(f, np.load(f)[keep])
    return dst


def test_snapshot_copies_final_windows_and_refuses_to_lose_any(results, tiny_sweep, tmp_path):
    src = tmp_path / "runs"
    full = an.load(tiny_sweep)
    half = full.n_windows // 2
    partial = _copy_sweep(tiny_sweep, src / "multi_agent", windows_done=half)
    dst = tmp_path / "snap"
    (written,) = results.snapshot(src, dst)
    assert written == dst / "multi_agent"
    assert sorted(p.name for p in written.iterdir()) == ["manifest.json", "metrics", "progress.json"]
    snap = an.load(written)
    assert snap.n_windows == half
    for name, arr in snap.metrics.items():
        np.testing.assert_array_equal(arr, full.metrics[name][:, :half], err_msg=name)
    raw = np.load(written / "metrics" / "curiosity.npy")
    assert np.isnan(raw[:, half:]).all()  # not final in the source: blanked as a fresh sweep has them
    assert (np.load(written / "metrics" / "action_counts.npy")[:, half:] == 0).all()

    # The whole sweep replaces the partial snapshot; the partial one may not replace it back.
    shutil.rmtree(partial)
    _copy_sweep(tiny_sweep, src / "multi_agent")
    results.snapshot(src, dst)
    assert an.load(dst / "multi_agent").n_windows == full.n_windows
    shutil.rmtree(src / "multi_agent")
    _copy_sweep(tiny_sweep, src / "multi_agent", windows_done=half)
    with pytest.raises(ValueError, match="steps done"):
        results.snapshot(src, dst)
    assert an.load(dst / "multi_agent").n_windows == full.n_windows

    # Another sweep under the same preset's name is refused too.
    other = json.loads((tiny_sweep / "manifest.json").read_text())
    other["command"] = other["command"].replace("seeds=", "seeds=9 was_seeds=")
    (dst / "multi_agent" / "manifest.json").write_text(json.dumps(other))
    with pytest.raises(ValueError, match="holds another sweep.*name its directory multi_agent.<label>"):
        results.snapshot(src, dst)
    # Named as a side experiment, it goes beside the preset's snapshot, which stays as it was.
    (src / "multi_agent").rename(src / "multi_agent.order")
    assert results.snapshot(src, dst) == [dst / "multi_agent.order"]
    assert json.loads((dst / "multi_agent" / "manifest.json").read_text()) == other
    assert list(results.load_presets(dst)) == ["multi_agent", "multi_agent.order"]


def test_a_presets_seeds_run_in_two_sweeps_snapshot_as_two_parts_and_load_as_one(results, tiny_sweep, tmp_path):
    src, dst = tmp_path / "runs", tmp_path / "snap"
    first = _copy_sweep(tiny_sweep, src / "multi_agent")
    more = _copy_sweep(tiny_sweep, src / "multi_agent_more")
    for part, shift in ((first, 0), (more, 2)):  # the second part ran seeds 2 and 3 (`first_seed=2`)
        m = json.loads((part / "manifest.json").read_text())
        m["config"].update(preset="multi_agent", first_seed=shift)
        m["command"] += f" first_seed={shift}"
        for r in m["runs"]:
            r["seed"] += shift
        (part / "manifest.json").write_text(json.dumps(m))
    written = results.snapshot(src, dst)
    assert [p.name for p in written] == ["multi_agent", "multi_agent.seeds-2-3"]
    merged = results.load_presets(dst)["multi_agent"]
    one = an.load(tiny_sweep)
    assert merged.n_runs == 2 * one.n_runs and [p.name for p in merged.parts] == ["multi_agent", "multi_agent.seeds-2-3"]
    assert {g.n for g in merged.groups()} == {4}  # 2 seeds a group in each part
    np.testing.assert_array_equal(merged.metrics["curiosity"], np.concatenate([one.metrics["curiosity"]] * 2))
    assert "`experiments/results/multi_agent`, `experiments/results/multi_agent.seeds-2-3`" in results.scale_block(
        results.load_presets(dst))
    # Snapshotting again replaces each part with itself.
    assert [p.name for p in results.snapshot(src, dst)] == ["multi_agent", "multi_agent.seeds-2-3"]
    # The next seeds alone (the first ones' run directory gone, their snapshot committed) go beside
    # that snapshot, not over it, and load with it as one.
    shutil.rmtree(first)
    assert [p.name for p in results.snapshot(src, dst)] == ["multi_agent.seeds-2-3"]
    assert results.load_presets(dst)["multi_agent"].n_runs == 2 * one.n_runs
    # A part behind the others (still running) is refused: it would cut the preset back to its steps.
    shutil.rmtree(dst / "multi_agent.seeds-2-3")
    p = json.loads((more / "progress.json").read_text())
    p["windows_done"] = one.n_windows // 2
    (more / "progress.json").write_text(json.dumps(p))
    with pytest.raises(ValueError, match=r"fewer than .*multi_agent \(200\), another part of multi_agent"):
        results.snapshot(src, dst)
    assert sorted(q.name for q in dst.iterdir()) == ["multi_agent"]


def test_page_blocks_on_the_tiny_sweeps(results, tiny_sweeps_dir, tmp_path):
    dst = tmp_path / "snap"
    results.snapshot(tiny_sweeps_dir, dst)
    presets = results.load_presets(dst)
    assert set(presets) == {"single_agent", "multi_agent"}
    # The snapshot gives the claims of the sweeps it copied.
    original = an.claims_table(tiny_sweeps_dir).values
    copied = an.claims_table(presets).values
    # Every number but claim 7's (the tiny two-agent sweep also stood for the temperatures preset, and
    # a sweep is copied once, as the first preset it stands for); the keys name the sweeps.
    numbers = lambda vs: [[x for x in v.values() if isinstance(x, float)] for v in vs if v["key"] != "7"]  # noqa: E731
    assert numbers(copied) == numbers(original)
    scale = results.scale_block(presets)
    assert "| `multi_agent` | 2 | same |" in scale and "200 / 200" in scale and "`boltzmann_temperatures`" in scale
    figures = results.figures_block(presets, out=tmp_path / "fig")
    drawn = sorted(p.stem for p in (tmp_path / "fig").glob("*.png"))
    assert drawn == sorted(f.name for f in results._figures() if set(f.needs) <= set(presets))
    assert len(drawn) == 10 and figures.count("![") == 10
    # The temperature and wall figures too, the tiny sweeps of matching agent count standing in.
    assert results.temperatures_block(presets).startswith("No Boltzmann temperature sweep")
    assert results.walls_block(presets).startswith("No walls-different sweep")
    presets["boltzmann_temperatures"] = presets["multi_agent_walls_different"] = presets["multi_agent"]
    presets["boltzmann_low_temperatures"] = presets["multi_agent.order"] = presets["multi_agent"]
    presets["multi_agent.per_step"] = presets["multi_agent"]
    presets["single_agent_walls_different"] = presets["single_agent.spread"] = presets["single_agent"]
    presets["single_agent.z_mean"] = presets["single_agent.spread_ucb"] = presets["single_agent"]
    presets["multi_agent.spread"] = presets["multi_agent.spread_ucb"] = presets["multi_agent"]
    presets["multi_agent.z_mean"] = presets["multi_agent"]
    results.figures_block(presets, out=tmp_path / "all")
    # All but the one-agent Boltzmann parts: the tiny one-agent sweep has no Boltzmann runs to stand in.
    drawn_all = {p.stem for p in (tmp_path / "all").glob("*.png")}
    assert {f.name for f in results._figures()} - drawn_all == {"single_agent_boltzmann_curiosity_parts"}
    assert len(results._figures()) == 26
    # The tiny sweeps record the spread: claim 1's three parts per group of each preset they stand
    # for; 200 steps fill the early block (steps 0-2k) alone.
    block = results.curiosity_parts_block(presets, dims=tmp_path / "no_posterior_dims.json")
    first, agents = block.split("\n\n| sweeps (one agent / two) |")  # claim 1's table, then claim 3's
    parts = [r.split(" | ") for r in first.splitlines()[2:] if r.startswith("| ")]
    assert len(parts) == 3 * sum(len(s.groups()) for s in presets.values())
    # Claim 3's: every one-agent name of the tiny one-agent sweep against every two-agent name of the
    # two-agent sweep, the groups they share (eps and UCB), three parts each.
    n_one, n_two = (sum(s is presets[k] for s in presets.values()) for k in ("single_agent", "multi_agent"))
    shared = {g.label for g in presets["single_agent"].groups()} & {g.label for g in presets["multi_agent"].groups()}
    agents, policies = agents.split("\n\n| agents | policy (sweep) |")  # then claims 10 and 11's
    assert sum(r.startswith("| `") for r in agents.splitlines()) == n_one * n_two * len(shared) * 3 > 0
    # Claims 10 and 11's: the tiny two-agent sweep's three policy pairs, the one-agent's UCB against ε.
    assert sum(r.startswith(("| 1 |", "| 2 |")) for r in policies.splitlines()) == (3 + 1) * 3
    assert [r[3] for r in parts[:3]] == list(an.PARTS.values())
    assert all(float(r[4]) > 0 and r[5:9] == ["n/a"] * 4 for r in parts if r[3] != "error against the posterior mean")
    temperatures = results.temperatures_block(presets)
    assert temperatures.count("| across T, blocked by seed |") == 2 and "`boltzmann_low_temperatures`:" in temperatures
    # With both, the test across all their temperatures (here one sweep standing for both: its own T).
    n_t = len(presets["multi_agent"].groups("boltzmann"))
    assert temperatures.count(f"| across all {n_t} T, blocked by seed |") == 1
    assert "the two-agent sweep (`multi_agent`)" in temperatures and "| ε-greedy (ε=0.2) | 2 |" in temperatures
    # Walls: each sweep standing for its own walls-different preset is its own comparison, every
    # group against itself: equal means, no difference to test.
    walls = results.walls_block(presets).splitlines()
    assert [r.split(" | ")[:2] for r in walls[2:] if r.startswith("| ")] == (
        [["| 1", g.label] for g in presets["single_agent"].groups()]
        + [["| 2", g.label] for g in presets["multi_agent"].groups()])
    assert "steps 0-200 |" in walls[0]
    for row in (r for r in walls[2:] if r.startswith("| ")):
        for cell in row.strip("| ").split(" | ")[3:]:
            a, b = cell.split(" (")[0].split(" vs ")
            assert a == b, row
    # Power from the tests with two seeds' values: the two-agent sweep's groups.
    power = results.power_block(presets)
    rows = [r.split(" | ") for r in power.splitlines()[2:] if r.startswith("| ")]
    assert rows and all(r[7] == "2" for r in rows), rows
    # Below it, their effects on one axis, drawn where the block links it.
    assert "![claim_effects](figures/results/claim_effects.png)" in power
    results.claim_effects_figure(presets, out=tmp_path / "effects")
    assert (tmp_path / "effects" / "claim_effects.png").is_file()


def test_bad_command_lines_are_messages_not_tracebacks(results, tmp_path, capsys):
    assert results.main(["snapshot", str(tmp_path / "nowhere")]) == 2
    assert "results.py snapshot:" in capsys.readouterr().err
    assert results.main(["snapshot", str(tmp_path)]) == 2  # a directory with no sweep in it
    assert "no manifest.json" in capsys.readouterr().err
    assert results.main(["draw"]) == 2
    err = capsys.readouterr().err
    assert "unknown command 'draw'" in err and "results.py page" in err
    assert results.main(["page", "extra"]) == 2 and "page takes no arguments" in capsys.readouterr().err
    assert results.main(["--help"]) == 0 and "results.py check" in capsys.readouterr().out
    assert not any(tmp_path.iterdir())  # nothing written


@pytest.mark.parametrize("setting, message", [
    ("STEPS=150", "STEPS=150: want a positive whole number, a multiple of 100"),
    ("TEMPERATURE_STEPS=abc", "TEMPERATURE_STEPS=abc: want a positive whole number"),
    ("MULTI_STEPS=7", "MULTI_STEPS=7: want a positive whole number, a multiple of 100"),
    ("SEEDS=0", "SEEDS=0: want a positive whole number"),
    ("MULTI_SEEDS=2.5", "MULTI_SEEDS=2.5: want a positive whole number"),
    ("SINGLE_SEEDS=-1", "SINGLE_SEEDS=-1: want a positive whole number"),
    ("SINGLE_WALL_SEEDS=x", "SINGLE_WALL_SEEDS=x: want a positive whole number"),
    ("MULTI_WALL_SEEDS=0", "MULTI_WALL_SEEDS=0: want a positive whole number"),
    ("TEMPERATURE_SEEDS=3x", "TEMPERATURE_SEEDS=3x: want a positive whole number"),
])
def test_reproduce_refuses_bad_settings_before_any_sweep(setting, message):
    import os
    import subprocess

    key, value = setting.split("=")
    # PYTHON=false: had a sweep been started, it would fail with another message and exit 1
    env = {**os.environ, key: value, "PYTHON": "false"}
    done = subprocess.run(["bash", str(ROOT / "experiments" / "reproduce.sh")], env=env, capture_output=True,
                          text=True, timeout=60)
    assert done.returncode == 2 and message in done.stderr


@pytest.mark.parametrize("settings, want", [
    ({}, {"multi_agent": 40000, "single_agent": 40000, "boltzmann_temperatures": 40000,
          "boltzmann_low_temperatures": 40000, "single_agent_walls_different": 15000, "multi_agent_walls_different": 15000}),
    ({"STEPS": "80000", "SINGLE_STEPS": "30000"},
     {"multi_agent": 80000, "single_agent": 30000, "boltzmann_temperatures": 80000,
      "boltzmann_low_temperatures": 80000, "single_agent_walls_different": 80000, "multi_agent_walls_different": 80000}),
])
def test_reproduce_run_lengths_per_sweep_and_steps_for_all(settings, want):
    import os
    import re
    import subprocess

    # PYTHON=echo prints each command instead of running it: nothing is swept or written.
    env = {k: v for k, v in os.environ.items()
           if k not in ("SEEDS", "MULTI_SEEDS", "SINGLE_SEEDS", "SINGLE_WALL_SEEDS", "MULTI_WALL_SEEDS", "TEMPERATURE_SEEDS",
                        "STEPS", "MULTI_STEPS", "SINGLE_STEPS", "TEMPERATURE_STEPS", "WALL_STEPS")}
    env.update(settings, PYTHON="echo")
    done = subprocess.run(["bash", str(ROOT / "experiments" / "reproduce.sh")], env=env, capture_output=True,
                          text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    got = {m[1]: int(m[2]) for m in re.finditer(r"preset=(\S+) seeds=3 first_seed=0 steps=(\d+)", done.stdout)}
    assert got == want
    # The one-agent, two-agent, temperature and both wall experiments' later seeds as they ran for the page:
    # sweeps of their own beside the first, the one-agent experiment's seeds 8-10 apart from 6-7 (added later).
    parts = re.findall(r"preset=(\w+) seeds=(\d) first_seed=([1-9]) steps=(\d+) .* out=(\S+)", done.stdout)
    assert parts == [("multi_agent", "3", "3", str(want["multi_agent"]), "runs/paper/multi_agent.seeds-3-5"),
                     ("multi_agent", "2", "6", str(want["multi_agent"]), "runs/paper/multi_agent.seeds-6-7"),
                     ("single_agent", "3", "3", str(want["single_agent"]), "runs/paper/single_agent.seeds-3-5"),
                     ("single_agent", "2", "6", str(want["single_agent"]), "runs/paper/single_agent.seeds-6-7"),
                     ("single_agent", "3", "8", str(want["single_agent"]), "runs/paper/single_agent.seeds-8-10"),
                     ("boltzmann_temperatures", "3", "3", str(want["boltzmann_temperatures"]),
                      "runs/paper/boltzmann_temperatures.seeds-3-5"),
                     ("single_agent_walls_different", "3", "3", str(want["single_agent_walls_different"]),
                      "runs/paper/single_agent_walls_different.seeds-3-5"),
                     ("single_agent_walls_different", "2", "6", str(want["single_agent_walls_different"]),
                      "runs/paper/single_agent_walls_different.seeds-6-7"),
                     ("multi_agent_walls_different", "3", "3", str(want["multi_agent_walls_different"]),
                      "runs/paper/multi_agent_walls_different.seeds-3-5"),
                     ("multi_agent_walls_different", "2", "6", str(want["multi_agent_walls_different"]),
                      "runs/paper/multi_agent_walls_different.seeds-6-7")]
    # Then the evidence from their checkpoints (the self-model's from each two-agent part), then the page.
    evidence = re.findall(r"experiments/(\w+)_evidence\.py runs/paper/(\S+)", done.stdout)
    assert evidence == [("temperature", "boltzmann_temperatures"), ("temperature", "boltzmann_temperatures.seeds-3-5"),
                        ("temperature", "boltzmann_low_temperatures"),
                        ("reconstruction", "single_agent"), ("reconstruction", "single_agent.seeds-3-5"),
                        ("reconstruction", "single_agent.seeds-6-7"), ("reconstruction", "single_agent.seeds-8-10"),
                        ("reconstruction", "single_agent_walls_different"),
                        ("reconstruction", "single_agent_walls_different.seeds-3-5"),
                        ("reconstruction", "single_agent_walls_different.seeds-6-7"),
                        ("reconstruction", "multi_agent"), ("reconstruction", "multi_agent.seeds-3-5"),
                        ("reconstruction", "multi_agent.seeds-6-7"),
                        ("reconstruction", "multi_agent_walls_different"),
                        ("reconstruction", "multi_agent_walls_different.seeds-3-5"),
                        ("reconstruction", "multi_agent_walls_different.seeds-6-7"),
                        ("self_model", "multi_agent"), ("self_model", "multi_agent.seeds-3-5"),
                        ("self_model", "multi_agent.seeds-6-7")]
    assert done.stdout.rstrip().endswith("experiments/results.py check")


def test_reproduce_at_the_papers_seeds_runs_each_experiment_as_one_sweep():
    import os
    import re
    import subprocess

    env = {k: v for k, v in os.environ.items()
           if k not in ("MULTI_SEEDS", "SINGLE_SEEDS", "SINGLE_WALL_SEEDS", "MULTI_WALL_SEEDS", "TEMPERATURE_SEEDS", "STEPS",
                        "MULTI_STEPS")}
    env.update(SEEDS="8", PYTHON="echo")
    done = subprocess.run(["bash", str(ROOT / "experiments" / "reproduce.sh")], env=env, capture_output=True,
                          text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert re.findall(r"preset=multi_agent seeds=(\d) first_seed=(\d)", done.stdout) == [("8", "0")]
    assert re.findall(r"preset=single_agent seeds=(\d) first_seed=(\d)", done.stdout) == [("8", "0")]
    assert re.findall(r"preset=boltzmann_temperatures seeds=(\d) first_seed=(\d)", done.stdout) == [("8", "0")]
    assert ".seeds-" not in done.stdout


def test_reproduce_seeds_sets_every_experiment_and_each_experiments_own_knob_wins():
    import os
    import re
    import subprocess

    env = {k: v for k, v in os.environ.items()
           if k not in ("MULTI_SEEDS", "SINGLE_SEEDS", "SINGLE_WALL_SEEDS", "MULTI_WALL_SEEDS", "TEMPERATURE_SEEDS", "STEPS")}
    env.update(SEEDS="3", SINGLE_SEEDS="10", PYTHON="echo")
    done = subprocess.run(["bash", str(ROOT / "experiments" / "reproduce.sh")], env=env, capture_output=True,
                          text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert re.findall(r"preset=multi_agent seeds=(\d) first_seed=(\d)", done.stdout) == [("3", "0")]
    # 10 one-agent seeds: parts of at most 3, a new one where the page's experiment grew (seed 8)
    assert re.findall(r"preset=single_agent seeds=(\d) first_seed=(\d) .* out=(\S+)", done.stdout) == [
        ("3", "0", "runs/paper/single_agent"), ("3", "3", "runs/paper/single_agent.seeds-3-5"),
        ("2", "6", "runs/paper/single_agent.seeds-6-7"), ("2", "8", "runs/paper/single_agent.seeds-8-9")]
    assert ".seeds-" not in done.stdout.replace("single_agent.seeds-", "")


@pytest.mark.parametrize("block", ["vae_layers", "rerun", "vae_layers_every_seed", "vae_layers_two_agents",
                                   "vae_layers_two_agents_every_seed"])
def test_a_side_by_side_block_sets_its_two_sweeps_beside_each_other_or_says_what_is_missing(results, block):
    from test_claims import fake_sweep

    pair = results.SIDE_BY_SIDE[block]
    names, labels, figure = pair.names, pair.labels, pair.figure
    agents = 1 if figure == "fig. 8" else 2
    a, b = (fake_sweep(name, agents, [("eps", 0.2)], 300, seeds=2) for name in names)
    assert f"{names[1]} has not been snapshotted yet" in results.side_by_side_block({names[0]: a}, block)
    text = results.side_by_side_block(dict(zip(names, (a, b))), block)
    assert text.startswith(f"| window | what | the paper (one run) | {labels[0]} | {labels[1]} |")
    assert "steps 0-1,000" in text and "steps 4,000-6,000 (the last both ran)" in text
