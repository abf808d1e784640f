"""How well could the self-model track each step's curiosity at all? (claim 8, step by step)

    python experiments/self_model_evidence.py runs/paper/multi_agent.per_step

At the sweep's newest checkpoint (the one that keeps the replay buffers), every run's networks
are evaluated on every pair of consecutive steps in its replay buffer (`analysis.curiosity_noise`):
the mean and variance of each step's curiosity over the sampling noise of the next latent, and
the self-model's prediction for the action taken. Per run and agent: the mean curiosity and the
share of it that the noise alone adds (mean_d sigma_d^2), and that part with the VAE of every
kept checkpoint on the same views (`analysis.posterior_spread`); within 20-step windows (the sweep's): the share of the curiosity's variance that is that noise; the ceiling it puts on any
prediction's correlation with the curiosity obtained, sqrt(1 - share); and how the self-model's
prediction correlates with the part that could be foreseen (the mean over the noise), against the
mean of each action over the buffer. From the metrics, the sweep's own per-step test over the
last third of the run (`analysis.step_tracking`) beside it.

Writes docs/results/self_model_noise.json (one entry per sweep and step, replacing an earlier
entry of the same sweep and step) and prints a Markdown table, one row per policy, over the runs
of every seed part of the experiment saved there (`multi_agent.per_step` and
`multi_agent.per_step.seeds-3-5` as one).
"""

from __future__ import annotations

import pathlib
import sys

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

import numpy as np

OUT = pathlib.Path(__file__).resolve().parents[1] / "docs" / "results" / "self_model_noise.json"
WINDOW = 20  # steps, the sweeps' metrics_every


def run_figures(cn) -> dict:
    """One run's figures, each a list over its agents."""
    tr = cn.tracking(WINDOW)
    return {"run": cn.run.name, "policy": cn.run.policy, "seed": cn.run.seed, "steps": int(cn.expected.shape[0]),
            "curiosity_mean": cn.expected.mean(axis=0).tolist(),
            "spread_share": (cn.spread.mean(axis=0) / cn.expected.mean(axis=0)).tolist(),
            "noise_share": cn.noise_share(WINDOW).tolist(), "ceiling": tr["ceiling"].tolist(),
            "r_self_foreseeable": tr["self"].tolist(), "r_actions_foreseeable": tr["actions"].tolist()}


def evidence(path: str) -> dict:
    from mjx_curio import analysis as an

    sweep = an.load(path)
    noise = [an.curiosity_noise(sweep, i) for i in range(sweep.n_runs)]
    step, runs = noise[0].step, [run_figures(cn) for cn in noise]
    for i, r in enumerate(runs):
        r["spread_by_checkpoint"] = {str(k): v for k, v in an.posterior_spread(sweep, i).items()}
    tracked = an.step_tracking(sweep) if an.records_steps(sweep) else None
    for i, r in enumerate(runs):
        r["r_self_obtained_late"] = float(np.tanh(tracked["self_late"][i])) if tracked is not None else None
        r["r_actions_obtained_late"] = float(np.tanh(tracked["base_late"][i])) if tracked is not None else None
    entry = {"sweep": sweep.name, "step": step, "window": WINDOW, "runs": runs}
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
    from evidence_cli import save_part

    print(table(save_part(OUT, entry, keys=("sweep", "step"), same=("step", "window"), indent=2)))
    print(f"wrote {OUT}")
    return entry


def table(entry: dict) -> str:
    """Markdown: per policy, the mean over its runs and agents of each figure (range over runs)."""
    def cell(rows, key, fmt=".2f"):
        per_run = [float(np.mean(r[key])) for r in rows if r[key] is not None]
        if not per_run:
            return "—"
        return f"{np.mean(per_run):{fmt}} ({min(per_run):{fmt}}–{max(per_run):{fmt}})"

    lines = [f"{entry['sweep']}, the replay buffers of step {entry['step']:,} (the last {entry['runs'][0]['steps'] + 1:,} "
             f"steps of each run), {entry['window']}-step windows; mean over runs and agents (range over runs)",
             "",
             "| policy | runs | curiosity | from sigma^2 | noise share | ceiling on r | r(self-model, foreseeable) | r(action means, foreseeable) "
             "| r(self-model, obtained), last third | r(action running means, obtained), last third |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for policy in dict.fromkeys(r["policy"] for r in entry["runs"]):
        rows = [r for r in entry["runs"] if r["policy"] == policy]
        lines.append(f"| {policy} | {len(rows)} | {cell(rows, 'curiosity_mean', '.3f')} "
                     f"| {cell(rows, 'spread_share')} | {cell(rows, 'noise_share')} | {cell(rows, 'ceiling')} "
                     f"| {cell(rows, 'r_self_foreseeable', '.3f')} | {cell(rows, 'r_actions_foreseeable', '.3f')} "
                     f"| {cell(rows, 'r_self_obtained_late', '.3f')} | {cell(rows, 'r_actions_obtained_late', '.3f')} |")
    checkpoints = list(entry["runs"][0]["spread_by_checkpoint"])
    lines += ["", "the part of the mean curiosity the noise alone adds (mean_d sigma_d^2), each checkpoint's VAE on "
              "every 10th view of the same buffer; mean over runs (range over runs)", "",
              "| policy | " + " | ".join(f"step {int(k):,}" for k in checkpoints) + " |",
              "| --- |" + " ---: |" * len(checkpoints)]
    for policy in dict.fromkeys(r["policy"] for r in entry["runs"]):
        rows = [r for r in entry["runs"] if r["policy"] == policy]
        vals = [[r["spread_by_checkpoint"][k] for r in rows] for k in checkpoints]
        lines.append(f"| {policy} | " + " | ".join(f"{np.mean(v):.3f} ({min(v):.3f}–{max(v):.3f})" for v in vals) + " |")
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    """Bad input (no such sweep, no checkpoints or replay buffers) is a one-line message and exit
    status 2, before anything is written."""
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
    from evidence_cli import one_sweep_main

    return one_sweep_main("self_model_evidence.py", __doc__, evidence, argv)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
