"""The results page, docs/results.md: the paper's figures and claims from the preset sweeps.

    python experiments/results.py snapshot [runs/paper]    # copy the sweeps' metrics into the repository
    python experiments/results.py page                     # figures + tables of docs/results.md from them
    python experiments/results.py check                    # does the page match the committed metrics?

`snapshot` copies, for every sweep under the given directory that stands for one of the paper's
presets (`analysis.assign_presets`), what the analysis reads of it (manifest.json, progress.json
and metrics/, about 2 MB for 9 runs of 15,000 steps; not the checkpoints) into
experiments/results/<preset>/, so the page can be rebuilt, and checked, from the repository
alone. It never replaces a snapshot with a different sweep or with one that has fewer steps done.
A sweep in a directory named `<preset>.<label>` is a side experiment of that preset (its own seeds
and length; `analysis.assign_presets`) and goes to experiments/results/<preset>.<label>/: the
page's `multi_agent.order` records the order of actions, which claim 6b needs and the
`multi_agent` sweeps, made before it was recorded, lack.

`page` loads those snapshots, draws the figures with the notebook's own functions
(`mjx_curio.analysis.plot_*`) into docs/figures/results/, and rewrites the generated blocks of
docs/results.md (between `<!-- generated: NAME -->` and `<!-- end: NAME -->`): the scale of the
sweeps, the figures with their captions, the claims table (`analysis.claims_table`), the
numbers the paper reads off its figures beside ours (`analysis.paper_numbers_table`, with a
column for the full-length sweeps) and the curiosity from a zero memory carry (from
docs/results/history.json, which `history_evidence.py` writes) and from the authors' memory
(docs/results/authors_memory.json, which `authors_memory_evidence.py` writes), fig. 8's and fig.
17's settings with the authors' VAE layers beside Ha and Schmidhuber's (the side experiments' own
runs of the default layers, and every seed of the figure's experiment), and fig. 8's run again
beside its first run (`analysis.readings_side_by_side`), the seeds each claim's tests need (`analysis.power_table`), claim 1's fall and rise taken apart
into the world model's error and the posterior's spread (`analysis.curiosity_parts_table`), the
Boltzmann temperatures measure by measure (`analysis.temperature_table`), different walls against identical ones
(`analysis.walls_table`) and the reconstructions' quality over training (from
docs/results/reconstructions.json, which `reconstruction_evidence.py` writes) and the sweeps
of the paper's full length (from docs/results/full_length.json, which `full_length_evidence.py`
writes, with their figures; `full_length_page.py` makes that block); the rest
of the page (what the verdicts mean, why a claim may fail here) is prose and stays as written.
The claims' numbers also go to docs/results/claims.csv, the walls table's to docs/results/walls.csv.

`check` recomputes the scale, claims, paper's numbers, history, authors' memory, VAE layers, rerun, power, curiosity parts, temperatures,
walls, reconstructions and full-length blocks from the committed results and exits 1 if they differ from the page (the
test suite does the same).
"""

from __future__ import annotations

import dataclasses
import json
import pathlib
import re
import shutil
import sys
from typing import Callable

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))  # its sibling modules, however it is loaded
from full_length_page import FULL_LENGTH, full_length_block, full_length_curves, full_length_figure  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]
SNAPSHOTS = ROOT / "experiments" / "results"
PAGE = ROOT / "docs" / "results.md"
FIGURES = ROOT / "docs" / "figures" / "results"
CLAIMS_CSV = ROOT / "docs" / "results" / "claims.csv"
WALLS_CSV = ROOT / "docs" / "results" / "walls.csv"
RECONSTRUCTIONS = ROOT / "docs" / "results" / "reconstructions.json"  # reconstruction_evidence.py writes it
POSTERIOR_DIMS = ROOT / "docs" / "results" / "posterior_dims.json"  # spread_evidence.py writes it
# Seed parts of one experiment read as one where their views and counting are the same.
POSTERIOR_DIMS_POOLED_BY = ("replay_step", "every", "near_prior", "latent")
HISTORY = ROOT / "docs" / "results" / "history.json"  # history_evidence.py writes it
AUTHORS_MEMORY = ROOT / "docs" / "results" / "authors_memory.json"  # authors_memory_evidence.py writes it
SNAPSHOT_FILES = ("manifest.json", "progress.json")  # plus metrics/*.npy
DPI = 80


# ------------------------------------------------------------------------------------ snapshots


def snapshot(src: str | pathlib.Path, dst: pathlib.Path = SNAPSHOTS) -> list[pathlib.Path]:
    """Copy manifest, progress and metrics of every preset sweep in `src` to `dst/<preset>/`; a
    preset whose seeds ran as several sweeps (`analysis.merge_sweeps`) has the part that starts
    at seed 0 there and each other part in `dst/<preset>.seeds-<first>-<last>/`. A part's name
    depends on its own seeds only, so the next seeds of a preset can be snapshotted from a
    directory that no longer holds the first ones, beside their committed snapshot. Refuses
    (ValueError, before copying anything) a snapshot that would replace one of another sweep
    (different command) or one with more steps done."""
    from mjx_curio import analysis as an

    presets = an.assign_presets(an.load_sweeps(src))
    if not presets:
        raise ValueError(f"no sweep in {src} stands for a preset of mjx_curio/presets.toml")
    plan = []
    for preset, merged in presets.items():
        for s in merged.parts or (merged,):
            if any(t is s for _, _, t in plan):  # a sweep standing for several presets is copied as the first
                continue
            seeds = sorted({r.seed for r in s.runs})
            plan.append((preset, preset if seeds[0] == 0 else f"{preset}.seeds-{seeds[0]}-{seeds[-1]}", s))
    for preset, name, s in plan:
        target = dst / name
        if (target / "manifest.json").is_file():
            old = an.load(target)
            if _command(old.manifest) != _command(s.manifest):
                raise ValueError(f"{target} holds another sweep ({_command(old.manifest)!r}); "
                                 f"{s.path} ran {_command(s.manifest)!r}. Move it away first, or, for another "
                                 f"experiment with the preset's settings, name its directory {preset}.<label> "
                                 "(a side experiment, snapshotted beside the preset's).")
            if old.steps_done > s.steps_done:
                raise ValueError(f"{target} has {old.steps_done:,} steps done, {s.path} only {s.steps_done:,}")
        # A preset's parts are read over the steps all of them ran: a part still running would cut
        # the page's every number of that preset back to its own steps.
        for other in [dst / preset, *dst.glob(f"{preset}.seeds-*")]:
            if other != target and (other / "manifest.json").is_file() and an.load(other).steps_done > s.steps_done:
                raise ValueError(f"{s.path} has {s.steps_done:,} steps done, fewer than {other} "
                                 f"({an.load(other).steps_done:,}), another part of {preset}: the page would read "
                                 f"all of {preset} to {s.steps_done:,} steps only. Snapshot it when it has caught up "
                                 "(other sweeps can be snapshotted one by one: results.py snapshot runs/paper/<sweep>).")
    written = []
    for _, name, s in plan:
        target = dst / name
        tmp = dst / f".{name}.partial"
        shutil.rmtree(tmp, ignore_errors=True)
        (tmp / "metrics").mkdir(parents=True)
        for f in SNAPSHOT_FILES:  # progress first: the metrics copied after it are final up to it
            shutil.copy2(s.path / f, tmp / f)
        done = _windows_done(tmp)
        for f in sorted((s.path / "metrics").glob("*.npy")):
            _copy_final_windows(f, tmp / "metrics" / f.name, done, f.name != "steps.npy")
        shutil.rmtree(target, ignore_errors=True)
        tmp.rename(target)
        written.append(target)
        print(f"{s.path} -> {target}: {s.n_runs} runs, {s.steps_done:,} of {int(s.manifest['config']['steps']):,} steps")
    return written


def _windows_done(sweep_dir: pathlib.Path) -> int:
    progress = json.loads((sweep_dir / "progress.json").read_text())
    return int(progress["windows_done"])


def _copy_final_windows(src: pathlib.Path, dst: pathlib.Path, windows_done: int, blank: bool) -> None:
    """Copy a metrics file with the windows after `windows_done` (not final while a sweep runs)
    set to what a fresh sweep preallocates there (NaN, or 0 for counts), so a snapshot holds
    only final values."""
    arr = np.load(src)
    if blank:
        arr[:, windows_done:] = np.nan if np.issubdtype(arr.dtype, np.floating) else 0
    np.save(dst, arr)


def _command(manifest: dict) -> str:
    """The sweep's command without the keys that may change between sessions of one sweep."""
    return re.sub(r" (steps|resume|progress|compile_cache|host_devices|async_checkpoints|out)=\S+", "", manifest.get("command", ""))


def load_presets(src: pathlib.Path = SNAPSHOTS) -> dict:
    """{preset: Sweep} of the snapshots in `src`."""
    from mjx_curio import analysis as an

    return an.assign_presets(an.load_sweeps(src)) if any(src.glob("*/manifest.json")) else {}


# ------------------------------------------------------------------------------- generated blocks


def scale_block(presets: dict) -> str:
    """The sweeps behind the page: what ran, how many seeds, how far."""
    rows = ["| preset | agents | walls | policies (seeds each) | image | steps done / planned | snapshot |",
            "|---|---|---|---|---|---|---|"]
    for name, s in presets.items():
        cfg = s.manifest["config"]
        groups = ", ".join(f"{g.label} ({g.n})" for g in s.groups())
        halted = s.progress.get("halted", {})
        note = f"; halted runs: {len(halted)}" if halted else ""
        rows.append(f"| `{name}` | {s.n_agents} | {cfg.get('walls')} | {groups} | {s.image} × {s.image} | "
                    f"{s.steps_done:,} / {int(cfg['steps']):,}{note} | "
                    + ", ".join(f"`experiments/results/{part.name}`" for part in s.parts or (s,)) + " |")
    if len(rows) == 2:
        return "No preset sweep has been snapshotted yet.\n"
    missing = [p for p in _preset_names() if p not in presets]
    tail = f"\nNo snapshot yet of: {', '.join(f'`{p}`' for p in missing)}.\n" if missing else "\n"
    return "\n".join(rows) + "\n" + tail


# The Boltzmann sweeps whose temperatures the page compares measure by measure.
TEMPERATURE_PRESETS = ("boltzmann_temperatures", "boltzmann_low_temperatures")


def temperatures_block(presets: dict) -> str:
    """Per Boltzmann temperature sweep snapshotted, `analysis.temperature_table`; with both, the
    test across all their temperatures too (the sweeps read as one, `_all_temperatures`); and the
    same measures for the policies of `multi_agent` (`analysis.policy_measures_table`)."""
    from mjx_curio import analysis as an

    parts = [f"`{name}`:\n\n{an.temperature_table(presets[name]).to_markdown()}"
             for name in TEMPERATURE_PRESETS if name in presets]
    if not parts:
        return "No Boltzmann temperature sweep has been snapshotted yet.\n"
    if all(name in presets for name in TEMPERATURE_PRESETS):
        both = _all_temperatures(presets)
        table = an.temperature_table(both)
        n_t = len(table.rows) - 1  # the last row is the test across T
        across = an.Table(table.columns, [[f"across all {n_t} T, blocked by seed", *table.rows[-1][1:]]],
                          [table.values[-1]])
        parts.append(f"Both read as one sweep, {n_t} temperatures over the {both.steps_done:,} steps both "
                     f"ran:\n\n{across.to_markdown()}")
    if "multi_agent" in presets:
        parts.append("The same measures for the three policies of the two-agent sweep (`multi_agent`), to set the "
                     f"temperatures beside them:\n\n{an.policy_measures_table(presets['multi_agent']).to_markdown()}")
    return "\n".join(parts)


def curiosity_parts_block(presets: dict, dims: pathlib.Path = POSTERIOR_DIMS) -> str:
    """Claim 1's fall and rise split into error and spread (`analysis.curiosity_parts_table`),
    from the sweeps that record the spread, claim 3 split the same way wherever one agent and two
    ran the same policy (`analysis.agents_parts_table`), and claims 10 and 11 wherever two policies
    ran with the same agents (`analysis.policies_parts_table`), and claims 9 and 12, watching and
    touching (`analysis.situation_parts_table`); then, from posterior_dims.json, each
    experiment's spread and latent dimensions near the prior checkpoint by checkpoint
    (`posterior_dims_table`), its seed parts measured on buffers of the same step as one."""
    from mjx_curio import analysis as an

    table = an.curiosity_parts_table(presets)
    parts = [table.to_markdown() if table.rows else "No sweep that records the posterior spread has been snapshotted yet.\n"]
    for table in (an.agents_parts_table(presets), an.policies_parts_table(presets),
                  an.situation_parts_table(presets)):
        if table.rows:
            parts.append(table.to_markdown())
    if dims.exists():
        sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
        from evidence_cli import pooled_entries

        saved = json.loads(dims.read_text())
        parts += [posterior_dims_table(e) for e in pooled_entries(saved, POSTERIOR_DIMS_POOLED_BY, source=dims)]
    return "\n".join(parts)


def posterior_dims_table(entry: dict) -> str:
    """Markdown: per group and checkpoint, the mean over its runs (range over runs) of the spread,
    the median dimension's variance and the dimensions near the prior, at the checkpoints every
    run kept (seed parts that ran apart may have kept others too)."""
    checkpoints = [k for k in entry["runs"][0]["by_checkpoint"] if all(k in r["by_checkpoint"] for r in entry["runs"])]
    lines = [f"`{entry['sweep']}`: each checkpoint's VAE on every {entry['every']}th view of the replay buffer kept "
             f"at step {entry['replay_step']:,}; per checkpoint, the posterior spread (mean over views and the "
             f"{entry['latent']} dimensions of σ²), the median dimension's σ² (mean over views), and the dimensions "
             f"whose σ² exceeds {entry['near_prior']:g} (mostly noise, nearer the prior's 1 than a precise code); "
             "mean over runs (range over runs).", "",
             "| group | runs | " + " | ".join(f"step {int(k):,}" for k in checkpoints) + " |",
             "|---|---|" + "---|" * len(checkpoints)]
    for group in dict.fromkeys(r["group"] for r in entry["runs"]):
        rows = [r for r in entry["runs"] if r["group"] == group]
        cells = []
        for k in checkpoints:
            spread, median, near = ([r["by_checkpoint"][k][x] for r in rows] for x in ("spread", "median", "near_prior"))
            cells.append(f"spread {np.mean(spread):.3f} ({min(spread):.3f}–{max(spread):.3f}); median "
                         f"{np.mean(median):.3f} ({min(median):.3f}–{max(median):.3f}); "
                         f"{np.mean(near):.1f} ({min(near)}–{max(near)}) dims")
        lines.append(f"| {group} | {len(rows)} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def walls_block(presets: dict) -> str:
    """Different walls against identical ones, per policy (`analysis.walls_table`)."""
    from mjx_curio import analysis as an

    table = an.walls_table(presets)
    if not table.rows:
        return "No walls-different sweep and its identical-walls sweep have both been snapshotted yet.\n"
    return table.to_markdown()


def reconstructions_table(entry: dict) -> str:
    """Markdown of one entry of reconstructions.json: per checkpoint, the mean over runs [95 % CI]
    of the squared error and the edge error on held-out views, and the paired test against the
    newest checkpoint; with several policies, a table of them at the newest checkpoint."""
    def cell(c):
        return f"{c['mean']:.3g} [{c['low']:.3g}, {c['high']:.3g}]"

    def test(c):
        return f"{c['diff']:+.3g} (p = {c['p']:.2g})" if c["p"] is not None and np.isfinite(c["p"]) else "—"

    lines = [f"`{entry['sweep']}`: each run's VAE on {entry['heldout_frames_per_vae']} views from the other runs' "
             f"replay buffers at step {entry['replay_step']:,} ({entry['image']} × {entry['image']}); mean over "
             "runs [95 % CI]; against the newest checkpoint, the mean paired difference and the two-sided paired "
             "t-test's p.",
             "",
             "| checkpoint (step) | runs | squared error per image | minus the newest | edge error | minus the newest |",
             "|---|---|---|---|---|---|"]
    for row in entry["summary"]:
        lines.append(f"| {row['step']:,} | {row['error']['n']} | {cell(row['error'])} | {test(row['error_vs_newest'])} "
                     f"| {cell(row['edge_error'])} | {test(row['edge_error_vs_newest'])} |")
    policies = entry.get("by_policy")
    if policies and len(policies["groups"]) > 1:
        def p(key):
            v = policies["anova_p"][key]
            return f"p = {v:.2g}" if v is not None and np.isfinite(v) else "—"

        lines += ["", f"Per policy at step {entry['step']:,}, beside each run's error on its own training views "
                  f"(the `recon` metric per image over its last {policies['train_windows']} windows; there the latent "
                  "is sampled, not its mean); the last row tests across the policies (one-way ANOVA).",
                  "",
                  "| policy | runs | held-out squared error per image | held-out edge error | own training views' squared error |",
                  "|---|---|---|---|---|"]
        lines += [f"| {g['group']} | {g['error']['n']} | {cell(g['error'])} | {cell(g['edge_error'])} "
                  f"| {cell(g['train_recon'])} |" for g in policies["groups"]]
        lines.append(f"| across the policies | | {p('error')} | {p('edge_error')} | {p('train_recon')} |")
        labels = [g["group"] for g in policies["groups"]]
        lines += ["", "The held-out squared error per image by whose views were reconstructed (columns) with whose "
                  "VAE (rows), mean over the pairs of runs (a run's own views left out):", "",
                  "| VAE of | " + " | ".join(f"views of {h}" for h in labels) + " |", "|---|" + "---|" * len(labels)]
        lines += [f"| {g['group']} | " + " | ".join(f"{g['on_views_of'][h]:.3g}" for h in labels) + " |"
                  for g in policies["groups"]]
    return "\n".join(lines) + "\n"


def reconstructions_block(path: pathlib.Path = RECONSTRUCTIONS) -> str:
    """The newest entry per sweep of reconstructions.json (`reconstructions_table`) and its figure."""
    entries = json.loads(path.read_text()) if path.exists() else []
    newest = {}
    for e in sorted(entries, key=lambda e: e["step"]):
        newest[e["sweep"]] = e
    if not newest:
        return "No sweep's reconstructions have been measured yet (`experiments/reconstruction_evidence.py`).\n"
    return "\n".join(f"{reconstructions_table(e)}\n![{name}_reconstructions](figures/{name}_reconstructions.png)\n"
                     for name, e in sorted(newest.items()))


def history_table(entry: dict) -> str:
    """Markdown of one entry of history.json: per group, means over its runs of the sweep's own
    curiosity over the buffer's steps, the curiosity's expectation on those steps from the live
    carry and from a zero carry, their difference (mean over runs [95 % CI]) and the spread."""
    lines = [f"`{entry['sweep']}`, the networks of step {entry['replay_step']:,} on the replay buffer kept there "
             f"({entry['runs'][0]['steps']:,} steps a run); means over runs:", "",
             "| group | runs | curiosity (the sweep's metrics) | E[curiosity], the live carry | E[curiosity], a zero "
             "carry | zero - live | posterior spread |", "|---|---|---|---|---|---|---|"]
    for group, n, col in _by_group(entry, ("logged", "live", "zero", "spread")):
        lines.append(f"| {group} | {n} | {col['logged'].mean():.3f} | {col['live'].mean():.3f} | "
                     f"{col['zero'].mean():.3f} | {_difference(col['zero'] - col['live'])} | {col['spread'].mean():.3f} |")
    return "\n".join(lines) + "\n"


def _by_group(entry: dict, keys: tuple[str, ...]):
    """(group, runs, {key: float array over the group's runs}) for each group of an evidence
    entry's runs, in their order."""
    for group in dict.fromkeys(r["group"] for r in entry["runs"]):
        rs = [r for r in entry["runs"] if r["group"] == group]
        yield group, len(rs), {k: np.array([r[k] for r in rs], float) for k in keys}


def _difference(d: np.ndarray) -> str:
    """'+0.094 [+0.064, +0.125]': the mean over runs of a difference with its 95 % CI."""
    from mjx_curio import analysis as an

    m, lo, hi = an.mean_ci(d)[:3]
    return f"{m:+.3f} [{lo:+.3f}, {hi:+.3f}]"


def _entries_block(path: pathlib.Path, table, missing: str) -> str:
    """`table(entry)` for every entry of the JSON list at `path`, one a sweep, or `missing`."""
    entries = json.loads(path.read_text()) if path.exists() else []
    if not entries:
        return missing
    return "\n".join(table(e) for e in sorted(entries, key=lambda e: e["sweep"]))


def history_block(path: pathlib.Path = HISTORY) -> str:
    """Every entry of history.json (`history_table`), one table a sweep."""
    return _entries_block(path, history_table, "No sweep's replay buffers have been evaluated from a zero carry "
                                               "yet (`experiments/history_evidence.py`).\n")


def authors_memory_table(entry: dict) -> str:
    """Markdown of one entry of authors_memory.json: per group, means over its runs of the sweep's
    own curiosity over the buffer's steps, the number the authors' memory logs late in its training
    with every view beside its own transition and with the authors' pairing, their difference
    (mean over runs [95 % CI]) and the posterior's floor."""
    r0 = entry["runs"][0]
    two = entry["agents"] > 1
    lines = [f"`{entry['sweep']}` ({'two agents' if two else 'one agent'}), the VAE of step {entry['replay_step']:,} "
             f"on the replay buffer kept there ({r0['steps']:,} steps, {r0['updates']:,} updates of a fresh memory "
             "a run; the logged number's mean over the last quarter of them); means over runs:", "",
             "| group | runs | curiosity (the sweep's metrics) | logged, each view with its own transition | "
             "logged, the authors' pairing | authors' - own | posterior floor |", "|---|---|---|---|---|---|---|"]
    for group, n, col in _by_group(entry, ("logged", "matched", "authors", "floor")):
        authors, diff = ((f"{col['authors'].mean():.3f}", _difference(col["authors"] - col["matched"])) if two
                         else ("the same (one agent)", "—"))
        lines.append(f"| {group} | {n} | {col['logged'].mean():.3f} | {col['matched'].mean():.3f} | {authors} | "
                     f"{diff} | {col['floor'].mean():.3f} |")
    return "\n".join(lines) + "\n"


def authors_memory_block(path: pathlib.Path = AUTHORS_MEMORY) -> str:
    """Every entry of authors_memory.json (`authors_memory_table`), one table a sweep."""
    return _entries_block(path, authors_memory_table, "No sweep's replay buffers have been given to the authors' "
                                                      "memory yet (`experiments/authors_memory_evidence.py`).\n")


@dataclasses.dataclass(frozen=True)
class SideBySide:
    """Two sweeps of a figure's setting, one thing apart, as a page block: the sweeps, their labels,
    what the second one is, the figure whose setting both run, and whether to show only the
    measures both record (`analysis.readings_side_by_side`)."""

    names: tuple[str, str]
    labels: tuple[str, str]
    what: str
    figure: str
    shared_only: bool = False


# A figure's setting twice, one thing apart: page block -> `SideBySide`. The side experiments run
# on the seeds of a default-layers sweep that records the posterior spread; the one-agent rerun of
# fig. 8 (a later build, so a chaotically different but equally likely trajectory per seed)
# records the training batches' curiosity, which the first predates, so it is the default layers'
# side against the authors'. The `_every_seed` blocks set the authors' layers against every seed of
# the figure's own experiment, the default layers' largest sample, which records the curiosity alone.
SIDE_BY_SIDE = {
    "vae_layers": SideBySide(("single_agent.batch_curiosity", "single_agent.authors_vae"),
                             ("Ha & Schmidhuber's layers", "the authors' layers"),
                             "the side experiment with the authors' VAE layers", "fig. 8"),
    "rerun": SideBySide(("single_agent.spread", "single_agent.batch_curiosity"),
                        ("the first run", "the rerun"),
                        "fig. 8's setting run again", "fig. 8"),
    "vae_layers_every_seed": SideBySide(("single_agent", "single_agent.authors_vae"),
                                        ("Ha & Schmidhuber's layers (all seeds)", "the authors' layers"),
                                        "the authors' VAE layers against every seed of fig. 8's experiment",
                                        "fig. 8", shared_only=True),
    "vae_layers_two_agents": SideBySide(("multi_agent.spread", "multi_agent.authors_vae"),
                                        ("Ha & Schmidhuber's layers", "the authors' layers"),
                                        "the two-agent side experiment with the authors' VAE layers", "fig. 17"),
    "vae_layers_two_agents_every_seed": SideBySide(("multi_agent", "multi_agent.authors_vae"),
                                                   ("Ha & Schmidhuber's layers (all seeds)", "the authors' layers"),
                                                   "the authors' VAE layers against every seed of fig. 17's experiment",
                                                   "fig. 17", shared_only=True),
}


def side_by_side_block(presets: dict, block: str) -> str:
    """One of `SIDE_BY_SIDE`'s pairs in its figure's windows (`analysis.readings_side_by_side`),
    or which sweep is still missing."""
    from mjx_curio import analysis as an

    pair = SIDE_BY_SIDE[block]
    missing = [name for name in pair.names if name not in presets]
    if missing:
        return (f"{pair.what[0].upper()}{pair.what[1:]} ({pair.names[1]}, beside {pair.names[0]}): "
                f"{', '.join(missing)} has not been snapshotted yet.\n")
    return an.readings_side_by_side(*(presets[name] for name in pair.names), pair.labels, pair.figure,
                                    shared_only=pair.shared_only).to_markdown()



PAPER_READINGS = "paper_readings"


def paper_numbers_block(presets: dict, path: pathlib.Path = FULL_LENGTH) -> str:
    """The paper's numbers beside ours (`analysis.paper_numbers_table`): on the committed runs, and
    on the full-length runs of full_length.json where it exists; then the figure of the curiosity
    readings (`paper_readings_figure`)."""
    from mjx_curio import analysis as an

    if not presets:
        return "No snapshot has been committed yet.\n"
    long, label = full_length_curves(path)
    md = an.paper_numbers_table(presets, long, label or "80,000 steps", label="the committed runs").to_markdown()
    return md + (f"\n![{PAPER_READINGS}](figures/results/{PAPER_READINGS}.png)\n\n*The curiosity of the paper's "
                 "figs. 8, 17, 18 and 20 beside what the paper says of them: the mean over runs of each run's curiosity "
                 f"(the mean of its agents) in bins of 1,000 steps, with its 95 % CI, for the committed runs"
                 + (f" and the full-length runs ({label})" if label else "")
                 + "; grey boxes: the paper's words (\"about 0.55\" around step 5,000), over the steps it puts "
                 "them at.*\n")


def paper_readings_figure(presets: dict, path: pathlib.Path = FULL_LENGTH, out: pathlib.Path = FIGURES) -> None:
    """docs/figures/results/paper_readings.png: a panel for each curiosity figure with readings
    (`analysis.plot_paper_readings_panels`), the committed runs and the full-length ones where they ran."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mjx_curio import analysis as an

    long, _ = full_length_curves(path)
    figure = plt.figure()
    if an.plot_paper_readings_panels(figure, presets, long):
        figure.tight_layout()
        an.save_figure(figure, out, PAPER_READINGS, dpi=DPI)
    plt.close(figure)


def claims_block(presets: dict) -> str:
    from mjx_curio import analysis as an

    return an.claims_table(presets).to_markdown()


def power_block(presets: dict) -> str:
    """The power table, and below it the figure of every test's effect where one has two runs."""
    from mjx_curio import analysis as an

    table = an.power_table(presets)
    md = table.to_markdown()
    if _has_effects(table):
        md += f"\n![{CLAIM_EFFECTS}](figures/results/{CLAIM_EFFECTS}.png)\n\n*{CLAIM_EFFECTS_CAPTION}*\n"
    return md


CLAIM_EFFECTS = "claim_effects"
CLAIM_EFFECTS_CAPTION = (
    "The table's tests on one axis, in the claims' order. x: each test's effect divided by the standard deviation "
    "across runs (two samples: the root of the mean of the two variances), the paper's direction to the right; line: "
    "its 95 % interval, from the test's own standard error (Student's t of one sample, Welch's of two). Blue: the "
    "interval lies on the paper's side of 0; red: on the other side; grey: it spans 0. Filled: significant after "
    "Holm's adjustment over all the tests; hollow: not. Claim 7, a claim of no difference, is left out: its bound is "
    "in the table.")


def _has_effects(table) -> bool:
    return any(v.get("d") is not None and v.get("d_low") is not None for v in table.values)


def claim_effects_figure(presets: dict, out: pathlib.Path = FIGURES) -> None:
    """Draw the power block's figure of every test's effect into `out`, where there is one."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mjx_curio import analysis as an

    table = an.power_table(presets)
    if not _has_effects(table):
        return
    n = sum(v.get("d") is not None for v in table.values)
    fig, ax = plt.subplots(figsize=(8.0, 1.4 + 0.24 * n))
    an.plot_claim_effects(table, ax)
    fig.tight_layout()
    an.save_figure(fig, out, CLAIM_EFFECTS, dpi=DPI)
    plt.close(fig)


@dataclasses.dataclass(frozen=True)
class Figure:
    name: str
    needs: tuple[str, ...]  # presets
    caption: str  # {placeholders} filled from the sweeps (`_facts`)
    draw: Callable  # (presets) -> matplotlib Figure


def _policy_panels(preset: str, plot: Callable, height: float = 3.0, width: float = 8.0):
    def draw(presets):
        import matplotlib.pyplot as plt

        s = presets[preset]
        gs = s.groups()
        fig, axes = plt.subplots(len(gs), 1, figsize=(width, height * len(gs)), squeeze=False)
        for ax, g in zip(axes[:, 0], gs):
            plot(s, ax, g)
            ax.yaxis.label.set_fontsize(8)  # stacked panels: the long labels must not run into each other
        fig.tight_layout()
        return fig
    return draw


def _one(plot: Callable, size=(8.0, 3.6), panels: int = 1):
    """A figure of one row of `panels` axes (one Axes, or a list of them, passed to `plot`)."""
    def draw(presets):
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(1, panels, figsize=size)
        plot(presets, axes)
        fig.tight_layout()
        return fig
    return draw


def _interactions(presets):
    import matplotlib.pyplot as plt

    from mjx_curio import analysis as an

    fig, axes = plt.subplots(1, 2, figsize=(11, 3.8))
    an.plot_cumulative_interactions(presets["multi_agent"], axes[0], "object")
    an.plot_cumulative_interactions(presets["multi_agent"], axes[1], "agent")
    fig.tight_layout()
    return fig


def _walls_single(presets):
    """Figs. 15, 14 and 12 of the walls-different experiment, one agent, ε-greedy, stacked."""
    import matplotlib.pyplot as plt

    from mjx_curio import analysis as an

    s = presets["single_agent_walls_different"]
    g = s.group("eps")
    fig, axes = plt.subplots(3, 1, figsize=(8, 8.4))
    an.plot_curiosity(s, axes[0], g)
    an.plot_interaction_frequency(s, axes[1], g, every=500)
    an.plot_action_histogram(s, axes[2], g)
    for ax in axes:
        ax.yaxis.label.set_fontsize(8)  # stacked panels: the long labels must not run into each other
    fig.tight_layout()
    return fig


def _single_vs_multi(presets):
    import matplotlib.pyplot as plt

    from mjx_curio import analysis as an

    fig, axes = plt.subplots(2, 1, figsize=(8, 7.6))
    an.plot_single_vs_multi(presets["single_agent"], presets["multi_agent"], axes[0])
    an.plot_vae_single_vs_multi(presets["single_agent"], presets["multi_agent"], axes[1])
    for ax in axes:
        ax.yaxis.label.set_fontsize(8)  # stacked panels: the long labels must not run into each other
    fig.tight_layout()
    return fig


def _curiosity_parts_figure(name: str, preset: str, group: str, agents: int, policy: str, paper: str) -> Figure:
    """Claim 1's curve taken apart (curiosity = spread + error) for one group of a spread side experiment."""
    from mjx_curio import analysis as an

    who, mean = ("one agent", "") if agents == 1 else ("two agents", " Mean of both agents.")
    return Figure(
        name, (preset,),
        f"Claim 1's curve taken apart, {who}, {policy}, from the side experiment that records the posterior spread "
        f"(`{preset}`: the paper's settings, its own seeds and length). Black: the curiosity obtained; dashed "
        "purple: the spread of the VAE's posterior over the next view's latent, the part of the curiosity's "
        "expectation no prediction removes; red: the rest, the MDN-RNN's error against the posterior mean "
        f"(curiosity minus spread).{mean} y: squared latent distance, unitless, moving average over 1,000 "
        "steps; x: agent steps. Means over {seeds} seeds with 95 % confidence bands. "
        f"Paper: {paper} (the curiosity alone, one run).",
        _one(lambda p, ax: an.plot_curiosity_parts(p[preset], ax, group), size=(10, 3.8)))


def _error_without_spread_figure(name: str, preset: str, agents: int, setting: str) -> Figure:
    """Claim 1's curve without the posterior's spread, ε-greedy: the world model's error from the
    spread side experiment of `preset` beside the curiosity of its z=mean one."""
    from mjx_curio import analysis as an

    sampled, mean_latent = f"{preset}.spread", f"{preset}.z_mean"
    who = "one agent" if agents == 1 else "two agents, the mean of both"
    return Figure(
        name, (sampled, mean_latent),
        f"Claim 1's curve without the posterior's spread, {who}, ε-greedy ({setting}): the MDN-RNN's error "
        "against the posterior mean learnt two ways. Red: with the paper's sampled latents "
        f"(`{sampled}`, the curiosity minus the recorded spread: the red curve of the curiosity-parts figure); "
        f"blue: with the posterior mean as the latent for acting, the memory and the curiosity (`{mean_latent}`, "
        "the paper's settings but `z=mean`: its curiosity, all of it error). y: squared latent distance, unitless, "
        "moving average over 1,000 steps; x: agent steps. Means over {seeds} seeds with 95 % confidence bands. "
        "Not in the paper.",
        _one(lambda p, ax: an.plot_error_without_spread(p[sampled], p[mean_latent], ax, "eps"), size=(10, 3.8)))


def _figures() -> tuple[Figure, ...]:
    from mjx_curio import analysis as an

    curiosity = ("Curiosity reward over training, {who}, one panel per policy (ε-greedy ε = 0.2, Boltzmann T = 1.5, "
                 "UCB c = 1). x: agent steps; y: the curiosity reward, the squared distance between the MDN-RNN's "
                 "predicted and the encoder's actual next latent (eq. 3, unitless). Thin line: the reward at every "
                 "20th step, mean over {seeds} seeds; thick line: its trailing moving average over 50 such points "
                 "(1,000 steps), mean over seeds; band: 95 % confidence interval of that mean across seeds "
                 "(Student t). Paper: {paper}, one run each.")
    return (
        Figure("multi_agent_curiosity", ("multi_agent",),
               curiosity.replace("{who}", "two agents (green and purple)").replace("{paper}", "figs. 17, 18 and 20"),
               _policy_panels("multi_agent", an.plot_curiosity)),
        Figure("single_agent_curiosity", ("single_agent",),
               curiosity.replace("{who}", "one agent").replace("{paper}", "fig. 8 (ε-greedy)"),
               _policy_panels("single_agent", an.plot_curiosity)),
        Figure("single_agent_walls_different", ("single_agent_walls_different",),
               "One agent, ε-greedy (ε = 0.2), a different texture on every wall. Top: the curiosity reward "
               "(squared latent distance, unitless; thin line every 20th step, thick line its moving average over "
               "1,000 steps). Middle: the share of agent steps touching each object, averaged over bins of 500 "
               "steps. Bottom: how often each action was chosen over the whole run. x: agent steps (top, middle), "
               "the seven actions (bottom). Means over {seeds} seeds with 95 % confidence bands and error bars "
               "across seeds. Paper: figs. 15, 14 and 12 (one run, 80,000 steps).",
               _walls_single),
        Figure("single_agent_objects", ("single_agent",),
               "How often the single agent touches each of the four objects over training, one panel per policy. "
               "x: agent steps; y: the share of agent steps in contact with the object, averaged over bins of 500 "
               "steps; mean over {seeds} seeds with 95 % confidence bands. Pushed, the sphere and the cylinder (once "
               "toppled) roll; the pyramid and the disc can only slide. Paper: fig. 9 (ε-greedy, one run).",
               _policy_panels("single_agent", lambda s, ax, g: an.plot_interaction_frequency(s, ax, g, every=500),
                              height=2.6)),
        Figure("multi_agent_walls_different_curiosity", ("multi_agent_walls_different",),
               curiosity.replace("{who}", "two agents (green and purple), a different texture on every wall")
               .replace("Paper: {paper}, one run each.", "Paper: none (section 3.1 says both arenas were run; "
                        "only section 4.1.1's one-agent run is named as having different walls)."),
               _policy_panels("multi_agent_walls_different", an.plot_curiosity)),
        Figure("single_agent_actions", ("single_agent",),
               "How often the single agent chose each action over the whole run, one panel per policy. x: the seven "
               "actions; y: number of agent steps the action was chosen, mean over {seeds} seeds, error bars 95 % "
               "confidence intervals across seeds. Paper: fig. 10 (ε-greedy, one run).",
               _policy_panels("single_agent", an.plot_action_histogram, height=2.6)),
        Figure("multi_agent_policies", ("multi_agent",),
               "The three policies' curiosity on one axis, two agents (their mean). x: agent steps; y: curiosity "
               "reward (squared latent distance, unitless), moving average over 1,000 steps, mean over {seeds} seeds "
               "with 95 % confidence bands. Paper: fig. 11 is the single agent's (next figure).",
               _one(lambda p, ax: an.plot_curiosity_groups(p["multi_agent"], ax))),
        Figure("single_agent_policies", ("single_agent",),
               "The three policies' curiosity on one axis, one agent, as claims 10 and 11 compare them. x: agent "
               "steps; y: curiosity reward (squared latent distance, unitless), moving average over 1,000 steps, mean "
               "over {seeds} seeds with 95 % confidence bands. Paper: fig. 11 (one run each).",
               _one(lambda p, ax: an.plot_curiosity_groups(p["single_agent"], ax))),
        Figure("multi_agent_interactions", ("multi_agent",),
               "Cumulative contacts per policy, two agents. Left: agent-object contact steps (both agents, all four "
               "objects); right: steps with the two agents touching. x: agent steps; y: the running total as a "
               "percentage of the largest final total of any run group (the number it stands for is in the panel "
               "title); mean over {seeds} seeds with 95 % confidence bands. Paper: figs. 21 and 22 (one run per "
               "policy, 80,000 steps).",
               _interactions),
        Figure("multi_agent_actions", ("multi_agent",),
               "How often each agent chose each action over the whole run, one panel per policy. x: the seven "
               "actions; y: number of agent steps the action was chosen, mean over {seeds} seeds, error bars 95 % "
               "confidence intervals across seeds. Paper: fig. 10 (single agent).",
               _policy_panels("multi_agent", an.plot_action_histogram, height=2.6)),
        Figure("single_vs_multi", ("single_agent", "multi_agent"),
               "One agent against two, UCB (the paper's comparison). Top: curiosity reward (squared latent distance, "
               "unitless), moving average over 1,000 steps, of the single agent and of each of the two agents; "
               "bottom: the VAE's loss per image (nats: summed squared pixel error plus KL; the two-agent loss sums "
               "both views and is halved here). x: agent steps. Means over seeds with 95 % confidence bands. "
               "Paper: figs. 23 and 24.",
               _single_vs_multi),
        Figure("multi_agent_observational", ("multi_agent",),
               "Curiosity by what an agent did or saw in each 20-step window, all runs of the two-agent sweep and "
               "both agents. x: the four kinds of window (the number of windows below each); y: the agent's mean "
               "curiosity in such windows minus its own trailing 1,000-step moving average (squared latent distance, "
               "unitless), mean over runs with 95 % confidence intervals. Paper: section 5 (videos only).",
               _one(lambda p, ax: an.plot_observational(p["multi_agent"], ax), size=(8, 3.8))),
        Figure("multi_agent_turn_reversals", ("multi_agent.order",),
               "Trembling (claim 6b), two agents, from the side experiment that records the order of actions "
               "(`multi_agent.order`: the paper's settings, its own seeds and length). Left: how often an agent turns "
               "the other way than at the step before, per pair of consecutive steps, mean over bins of 1,000 steps "
               "(dotted: a uniformly random choice of the 7 actions, 2/49). Right: those reversals over the number a "
               "random order of each 20-step window's own actions would give (1: turns in no particular order; "
               "below 1: turns in runs of one direction). x: agent steps. Means over {seeds} seeds with 95 % "
               "confidence bands. Paper: section 5 (videos only).",
               _one(lambda p, axes: an.plot_turn_reversals(p["multi_agent.order"], axes), size=(12, 3.8),
                    panels=2)),
        Figure("multi_agent_self_model_tracking", ("multi_agent.per_step",),
               "Does the self-model know what will surprise it (claim 8)? Two agents, from the side experiment that "
               "records each window's moments of predicted and obtained curiosity (`multi_agent.per_step`: the "
               "paper's settings, its own seeds and length). Solid: the correlation of each step's predicted "
               "curiosity (of the action taken) with the curiosity obtained, within 20-step windows, pooled over "
               "bins of 1,000 steps and averaged over both agents; dashed: the same for a predictor that knows only "
               "each action's running mean curiosity over the previous 1,000 steps. x: agent steps. Means over "
               "{seeds} seeds with 95 % confidence bands. Paper: sections 3.2 and 5 (no figure).",
               _one(lambda p, ax: an.plot_self_model_tracking(p["multi_agent.per_step"], ax), size=(10, 3.8))),
        _curiosity_parts_figure("single_agent_curiosity_parts", "single_agent.spread", "eps", 1,
                                "ε-greedy", "fig. 8"),
        _curiosity_parts_figure("multi_agent_curiosity_parts", "multi_agent.spread", "eps", 2,
                                "ε-greedy (fig. 17's setting)", "fig. 17"),
        _curiosity_parts_figure("multi_agent_ucb_curiosity_parts", "multi_agent.spread_ucb", "ucb", 2,
                                "UCB (fig. 18's setting)", "fig. 18"),
        _curiosity_parts_figure("single_agent_ucb_curiosity_parts", "single_agent.spread_ucb", "ucb", 1,
                                "UCB (claim 3's setting)", "fig. 23"),
        _curiosity_parts_figure("single_agent_boltzmann_curiosity_parts", "single_agent.spread_boltzmann", "boltzmann",
                                1, "Boltzmann (claim 10's setting)", "fig. 11"),
        _error_without_spread_figure("single_agent_error_without_spread", "single_agent", 1, "fig. 8's setting"),
        _error_without_spread_figure("multi_agent_error_without_spread", "multi_agent", 2, "fig. 17's setting"),
        *_temperature_figures("boltzmann_temperatures", "Boltzmann temperatures T = 0.5 to 2.5", "0.5", "2.5",
                              curves="Paper: fig. 19.", actions="Paper: fig. 19 shows only curiosity."),
        *_temperature_figures("boltzmann_low_temperatures",
                              "Boltzmann at low temperatures, T = 0.005 to 0.05, where its softmax starts to favour "
                              "the actions its self-models predict most surprising", "0.005", "0.05",
                              curves="Not in the paper (its fig. 19 has T = 0.5 to 2.5).", actions="Not in the paper."),
        Figure("boltzmann_temperature_measures", ("boltzmann_temperatures", "boltzmann_low_temperatures"),
               "What the Boltzmann temperature changes, from T = 0.005 to 2.5: the paper's temperatures and the low "
               "ones read as one sweep over the steps both ran, two agents. One panel a measure, against T (log "
               "scale): claim 7's late curiosity (mean over the last quarter of the steps, squared latent distance, "
               "unitless), the entropy of the action choice over ln 7 (1: every action equally often), the most "
               "chosen action's share of the steps, object contacts per 1,000 agent-steps (both agents), and the "
               "0.25 m squares of floor an agent stood in at some 20-step window's end (mean of the agents). Dots: "
               "runs; line: mean over {seeds} seeds with 95 % confidence intervals; grey span: the paper's "
               "temperatures; dashed: a uniform choice. Not in the paper.",
               _one(lambda p, axes: an.plot_temperature_measures(_all_temperatures(p), axes), size=(20, 3.6),
                    panels=5)),
    )


def _all_temperatures(presets: dict):
    """The paper's Boltzmann temperatures and the low ones as one sweep (a sweep standing for
    both presets is itself)."""
    from mjx_curio import analysis as an

    paper, low = presets["boltzmann_temperatures"], presets["boltzmann_low_temperatures"]
    return paper if paper is low else an.merge_sweeps([paper, low], differ=("temperature", "preset"))


def _temperature_figures(preset: str, what: str, low: str, high: str, curves: str, actions: str):
    """A Boltzmann temperature sweep's two figures: curiosity per T, and the actions per T."""
    from mjx_curio import analysis as an

    return (
        Figure(preset, (preset,),
               f"{what}, two agents: curiosity reward (squared latent distance, unitless; mean of both agents), "
               "moving average over 1,000 steps, mean over {seeds} seeds with 95 % confidence bands. x: agent steps. "
               + curves,
               _one(lambda p, ax: an.plot_temperatures(p[preset], ax), size=(9.5, 3.8))),
        Figure(f"{preset}_actions", (preset,),
               f"How often each agent chose each action over the whole run under the Boltzmann policy, one panel "
               f"per temperature T ({low} at the top to {high} at the bottom), two agents. x: the seven actions; y: "
               "number of agent steps the action was chosen, mean over {seeds} seeds, error bars 95 % confidence "
               "intervals across seeds. A uniform choice would give each action 1/7 of the steps. " + actions,
               _policy_panels(preset, an.plot_action_histogram, height=2.4)),
    )


def _seeds(presets: dict, needs) -> str:
    ns = sorted({g.n for p in needs for g in presets[p].groups()})
    return "/".join(map(str, ns))


def figures_block(presets: dict, out: pathlib.Path | None = FIGURES) -> str:
    """Markdown for every figure whose presets exist, drawing each into `out` (None: draw none)."""
    parts = []
    for f in _figures():
        if not all(p in presets for p in f.needs):
            continue
        if out is not None:
            import matplotlib

            matplotlib.use("Agg")
            import matplotlib.pyplot as plt

            from mjx_curio import analysis as an

            fig = f.draw(presets)
            an.save_figure(fig, out, f.name, dpi=DPI)
            plt.close(fig)
        steps = ", ".join(f"{presets[p].steps_done:,} steps ({p})" for p in f.needs)
        caption = f.caption.replace("{seeds}", _seeds(presets, f.needs))
        parts.append(f"![{f.name}](figures/results/{f.name}.png)\n\n*{caption} Sweeps: {steps}.*\n")
    return "\n".join(parts) if parts else "No figure yet: no preset sweep has been snapshotted.\n"


def _preset_names() -> list[str]:
    from mjx_curio.presets import load_presets as presets_toml

    return list(presets_toml())


# ------------------------------------------------------------------------------------ the page


def blocks(page: str) -> dict[str, str]:
    """{name: text} of the page's generated blocks."""
    return {m.group(1): m.group(2) for m in _BLOCK.finditer(page)}


_BLOCK = re.compile(r"<!-- generated: (\w+) -->\n(.*?)<!-- end: \1 -->", re.S)


def fill(page: str, new: dict[str, str]) -> str:
    """`page` with the blocks named in `new` replaced. KeyError if the page lacks one."""
    missing = set(new) - set(blocks(page))
    if missing:
        raise KeyError(f"{PAGE} has no generated block named {', '.join(sorted(missing))}")
    return _BLOCK.sub(lambda m: f"<!-- generated: {m.group(1)} -->\n{new.get(m.group(1), m.group(2))}"
                                f"<!-- end: {m.group(1)} -->", page)


def computed_blocks(presets: dict) -> dict[str, str]:
    """The blocks that are pure functions of the committed results: the snapshots' metrics, and
    reconstructions.json for the reconstructions block (what `check` compares)."""
    return {"scale": scale_block(presets), "claims": claims_block(presets), "power": power_block(presets),
            "curiosity_parts": curiosity_parts_block(presets), "paper_numbers": paper_numbers_block(presets),
            "history": history_block(), "authors_memory": authors_memory_block(),
            **{block: side_by_side_block(presets, block) for block in SIDE_BY_SIDE},
            "temperatures": temperatures_block(presets), "walls": walls_block(presets),
            "reconstructions": reconstructions_block(), "full_length": full_length_block()}


def write_page(src: pathlib.Path = SNAPSHOTS) -> None:
    from mjx_curio import analysis as an

    presets = load_presets(src)
    new = computed_blocks(presets)
    new["figures"] = figures_block(presets)
    claim_effects_figure(presets)
    paper_readings_figure(presets)
    full_length_figure(FULL_LENGTH, FIGURES, DPI)
    PAGE.write_text(fill(PAGE.read_text(), new))
    CLAIMS_CSV.parent.mkdir(parents=True, exist_ok=True)
    CLAIMS_CSV.write_text(an.claims_table(presets).to_csv())
    WALLS_CSV.write_text(an.walls_table(presets).to_csv())
    print(f"wrote {PAGE}, {CLAIMS_CSV}, {WALLS_CSV} and {len(list(FIGURES.glob('*.png')))} figures in {FIGURES}")


def check_page(src: pathlib.Path = SNAPSHOTS) -> list[str]:
    """Names of the computed blocks where the page differs from the snapshots."""
    have = blocks(PAGE.read_text())
    want = computed_blocks(load_presets(src))
    return [k for k, v in want.items() if have.get(k) != v]


def main(argv: list[str]) -> int:
    import mjx_curio  # noqa: F401  (the package's XLA flags, should anything start JAX)

    from mjx_curio.analysis import SweepError
    from mjx_curio.cli import wants_help

    cmd = argv[0] if argv else ""
    usage = __doc__.split("\n\n")[1]
    if wants_help(argv):
        print(usage)
        return 0
    takes = {"snapshot": "at most one directory", "page": "no arguments", "check": "no arguments"}
    if cmd not in takes or len(argv) > (2 if cmd == "snapshot" else 1):
        why = (f"unknown command {cmd!r}; want snapshot, page or check" if cmd not in takes else
               f"{cmd} takes {takes[cmd]}, got {' '.join(argv[1:])}") if argv else "want a command"
        print(f"results.py: {why}\n{usage}", file=sys.stderr)
        return 2
    if cmd == "snapshot":
        try:
            snapshot(argv[1] if len(argv) == 2 else ROOT / "runs" / "paper")
        except (SweepError, ValueError) as err:
            print(f"results.py snapshot: {err}", file=sys.stderr)
            return 2
    elif cmd == "page":
        write_page()
    else:
        stale = check_page()
        if stale:
            print(f"{PAGE}: the {', '.join(stale)} block(s) differ from experiments/results; "
                  "run `python experiments/results.py page`")
            return 1
        print(f"{PAGE} matches experiments/results")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
