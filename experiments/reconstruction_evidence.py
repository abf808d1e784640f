"""Whether the VAE's reconstructions get better over training (the paper's figs. 7 and 13), in numbers.

    python experiments/reconstruction_evidence.py runs/paper/multi_agent

The paper shows one run's reconstructions early and late and says they become noticeably
sharper. Here every run's VAE, restored from each checkpoint the sweep kept (by default the
steps 500 and 5,000, every 20,000th and the two newest), encodes and decodes the same kind of
view it never trained on: frames of the *other* runs' replay buffers at the newest checkpoint
(`analysis.reconstruction_quality`, 32 slots a run, every agent's view of each). Per run and checkpoint:
the mean summed squared pixel error of a reconstruction (pixels in [0, 1], the VAE loss's
reconstruction term) and the edge error (`analysis.edge_error`: how far the reconstruction's
neighbouring-pixel differences are from the real image's, relative to the real ones; 0 is every
edge kept, about 1 a blur that keeps none). Each earlier checkpoint is compared with the newest,
run by run (a paired t-test across runs); at the newest, the policies are compared (one-way
ANOVA), beside the error each run's VAE makes on its own training views (the `recon` metric).

Writes docs/results/reconstructions.json (one entry per sweep and newest step, replacing an
earlier entry of the same sweep and step) and docs/figures/<sweep>_reconstructions.png (the real
views and run 0's reconstructions at the first, 5,000th and newest steps, as figs. 7 and 13 show
them; `analysis.plot_reconstructions`), and prints the entry as `results.py page` puts it in
docs/results.md (a Markdown table, one row per checkpoint).
"""

from __future__ import annotations

import math
import pathlib
import sys

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

import numpy as np

DOCS = pathlib.Path(__file__).resolve().parents[1] / "docs"
OUT = DOCS / "results" / "reconstructions.json"
FIGURES = DOCS / "figures"
FRAMES_PER_RUN = 32
# The checkpoints the figure shows: the first, this one if kept (fig. 13's early step), the newest.
FIGURE_STEP = 5_000
TRAIN_WINDOWS = 50  # the training error beside the held-out one: its last 1,000 steps (20-step windows)


def paired(earlier: np.ndarray, newest: np.ndarray) -> dict:
    """Mean of earlier - newest across runs, its 95 % CI and the two-sided paired t-test's p."""
    from mjx_curio import analysis as an

    d = np.asarray(earlier, float) - np.asarray(newest, float)
    d = d[np.isfinite(d)]
    mean, lo, hi, n = an.mean_ci(d)
    out = {"diff": float(mean), "low": float(lo), "high": float(hi), "n": int(n), "p": math.nan}
    if n >= 2 and d.std(ddof=1) > 0:
        out["p"] = an.t_pvalue(float(mean / (d.std(ddof=1) / math.sqrt(n))), n - 1)
    return out


def cell(x) -> dict:
    from mjx_curio import analysis as an

    mean, lo, hi, n = an.mean_ci(np.asarray(x, float))
    return {"mean": float(mean), "low": float(lo), "high": float(hi), "n": int(n)}


def by_policy(sweep, q) -> dict:
    """At the newest checkpoint, per policy group: the held-out error and edge error, the held-out
    error on each group's views apart (whose VAE generalises worse, whose views are harder), and
    the error on the run's own training views (the `recon` metric per image, the last TRAIN_WINDOWS windows up
    to that step; there the latent is sampled, not its mean); each tested across the groups
    (one-way ANOVA)."""
    from mjx_curio import analysis as an

    upto = np.flatnonzero(np.asarray(sweep.steps) <= q.steps[-1])[-TRAIN_WINDOWS:]
    own = np.nanmean(sweep.metrics["recon"][:, upto], axis=1) / sweep.n_agents  # [runs]
    groups = sweep.groups()
    measures = {"error": q.error[:, -1], "edge_error": q.edge_error[:, -1], "train_recon": own}
    by_source = q.error_by_source[..., -1]  # [VAE's run, views' run], NaN on the diagonal

    def on_views(vae, views):  # mean over the pairs of runs, a run's own views left out
        return float(np.nanmean(by_source[np.ix_(vae.indices, views.indices)]))

    return {"train_windows": int(len(upto)),
            "groups": [{"group": g.label, **{k: cell(v[g.indices]) for k, v in measures.items()},
                        "on_views_of": {h.label: on_views(g, h) for h in groups}} for g in groups],
            "anova_p": {k: an.one_way_anova([v[g.indices] for g in groups])["p"] for k, v in measures.items()}}


def evidence(path: str) -> dict:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mjx_curio import analysis as an

    sweep = an.load(path)
    q = an.reconstruction_quality(sweep, frames_per_run=FRAMES_PER_RUN)
    runs = [{"run": r.name, "policy": r.policy, "seed": r.seed, "error": q.error[r.index].tolist(),
             "edge_error": q.edge_error[r.index].tolist()} for r in sweep.runs]
    summary = []
    for k, step in enumerate(q.steps):
        row = {"step": step}
        for key, x in (("error", q.error), ("edge_error", q.edge_error)):
            row[key] = cell(x[:, k])
            row[key + "_vs_newest"] = paired(x[:, k], x[:, -1])
        summary.append(row)
    entry = {"sweep": sweep.name, "step": q.steps[-1], "replay_step": q.replay_step,
             "by_policy": by_policy(sweep, q),
             "frames_per_run": q.frames_per_run, "heldout_frames_per_vae": int(
                 (sweep.n_runs - 1) * q.frames_per_run * sweep.n_agents),
             "image": sweep.image, "steps": q.steps, "summary": summary, "runs": runs}
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
    import results  # the page's own table of an entry
    from evidence_cli import save_entry

    save_entry(OUT, entry, keys=("sweep", "step"), indent=2)

    shown = list(dict.fromkeys([q.steps[0]] + [s for s in q.steps if s == FIGURE_STEP] + [q.steps[-1]]))
    fig = plt.figure(figsize=(9.0, 1.0 + 1.25 * len(shown)))
    an.plot_reconstructions(sweep, fig, run=0, steps=shown, n_frames=8)
    fig.subplots_adjust(left=0.07, right=0.99, bottom=0.02, top=0.8, wspace=0.08, hspace=0.12)  # the title on top
    figure = FIGURES / f"{sweep.name}_reconstructions.png"
    fig.savefig(figure, dpi=110)
    print(results.reconstructions_table(entry))
    print(f"wrote {OUT} and {figure}")
    return entry


def main(argv: list[str]) -> int:
    """Bad input (no such sweep, no checkpoints or replay buffers) is a one-line message and exit
    status 2, before anything is written."""
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
    from evidence_cli import one_sweep_main

    return one_sweep_main("reconstruction_evidence.py", __doc__, evidence, argv)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
