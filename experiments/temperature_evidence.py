"""How far apart the self-models' predictions lie, and so how much a Boltzmann temperature can matter.

    python experiments/temperature_evidence.py runs/paper/boltzmann_temperatures
    python experiments/temperature_evidence.py runs/paper/boltzmann_low_temperatures

At the sweep's newest checkpoint (the one that keeps the replay buffers), every Boltzmann run's
self-models predict the curiosity of all seven actions on every state of its replay buffer
(`analysis.action_values`). Per run this gives the spread of those predictions (largest minus
smallest, per state and agent) and what the Boltzmann policy softmax(q / T) makes of them: the
probability of the most favoured action (uniform: 1/7) and the entropy relative to a uniform
choice at the run's own temperature, and the temperature at which the favoured action would get
half the probability. From the metrics up to that step: each temperature's range of action
shares (each action's share of the steps, mean over seeds), and how much the runs of the lowest
and the highest temperature share when they share a seed (`analysis.seed_coupling`: windows with
identical action counts, correlation of the curiosity curves), against runs of different seeds.
Writes docs/results/boltzmann_action_values.json (one entry per sweep and step, replacing an
earlier entry of the same sweep and step) and docs/figures/<sweep>_greediness.png
(`analysis.plot_boltzmann_greediness`; one figure a sweep, so the paper's temperatures and the low
ones keep theirs), and prints Markdown tables, one row per temperature.
"""

from __future__ import annotations

import pathlib
import sys

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

import numpy as np

DOCS = pathlib.Path(__file__).resolve().parents[1] / "docs"
OUT = DOCS / "results" / "boltzmann_action_values.json"
FIGURES = DOCS / "figures"
# Where to look for the temperature at which the favoured action gets half the probability.
T_GRID = np.geomspace(1e-4, 10.0, 401)


def _entropy_rel(p: np.ndarray) -> float:
    """Mean over states and agents of the policy's entropy over log(n_actions)."""
    return float((-(p * np.log(np.maximum(p, 1e-300))).sum(-1) / np.log(p.shape[-1])).mean())


def run_figures(v) -> dict:
    t = v.run.temperature
    spread = v.spread()
    favoured = v.favoured_probability(T_GRID)  # falls as T rises
    half = T_GRID[favoured >= 0.5]
    return {"run": v.run.name, "temperature": t, "seed": v.run.seed, "states": int(v.q.shape[0]),
            "spread_median": float(np.median(spread)), "spread_p90": float(np.quantile(spread, 0.9)),
            "q_mean": float(v.q.mean()), "max_prob": float(v.favoured_probability([t])[0]),
            "entropy_rel": _entropy_rel(v.boltzmann(t)),
            "half_mass_temperature": float(half.max()) if half.size else float("nan")}


def metrics_figures(sweep) -> dict:
    """Action shares per temperature and the same-seed coupling of the lowest and highest T."""
    from mjx_curio import analysis as an

    groups = sorted(sweep.groups("boltzmann"), key=lambda g: g.value)
    shares = {f"{g.value:g}": an.action_shares(sweep, g).mean(axis=0).tolist() for g in groups}
    return {"steps": sweep.steps_done, "action_shares": shares,
            "coupling_temperatures": [groups[0].value, groups[-1].value],
            "coupling": an.seed_coupling(sweep, groups[0], groups[-1])}


def evidence(path: str) -> dict:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mjx_curio import analysis as an

    sweep = an.load(path)
    values = [an.action_values(sweep, int(i)) for i in sweep.select(policy="boltzmann")]  # SweepError if none
    step = values[0].step
    entry = {"sweep": sweep.name, "step": step, "uniform_prob": 1 / len(sweep.actions),
             "runs": [run_figures(v) for v in values], "metrics": metrics_figures(sweep)}
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
    from evidence_cli import save_entry

    save_entry(OUT, entry, keys=("sweep", "step"), indent=2)
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    an.plot_boltzmann_greediness(sweep, ax, values=values)
    fig.tight_layout()
    figure = FIGURES / f"{sweep.name}_greediness.png"
    fig.savefig(figure, dpi=110)
    print(table(entry))
    print(f"wrote {OUT} and {figure}")
    return entry


def table(entry: dict) -> str:
    """Markdown: per temperature, the range over its runs of each figure."""
    def cell(rows, key, fmt):
        vals = [r[key] for r in rows]
        return f"{min(vals):{fmt}}–{max(vals):{fmt}}"

    lines = [f"{entry['sweep']}, step {entry['step']:,} (uniform probability {entry['uniform_prob']:.3f}); "
             "ranges over the seeds",
             "",
             "| T | runs | spread of q, median | spread, 90th percentile | P(most favoured action) | entropy / uniform "
             "| T for P = 0.5 |",
             "| ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for t in sorted({r["temperature"] for r in entry["runs"]}):
        rows = [r for r in entry["runs"] if r["temperature"] == t]
        lines.append(f"| {t:g} | {len(rows)} | {cell(rows, 'spread_median', '.3f')} | {cell(rows, 'spread_p90', '.3f')} "
                     f"| {cell(rows, 'max_prob', '.3f')} | {cell(rows, 'entropy_rel', '.4f')} "
                     f"| {cell(rows, 'half_mass_temperature', '.4f')} |")
    m = entry["metrics"]
    lines += ["", f"metrics up to step {m['steps']:,}", "",
              "| T | action shares (mean over seeds), lowest–highest |",
              "| ---: | ---: |"]
    lines += [f"| {t} | {100 * min(v):.1f}–{100 * max(v):.1f} % |" for t, v in m["action_shares"].items()]
    lo, hi = m["coupling_temperatures"]
    c = m["coupling"]

    def span(v, scale=1.0, fmt=".2f"):
        return f"{scale * min(v):{fmt}}–{scale * max(v):{fmt}}"

    same, other = c["same"], c["other"]
    lines += ["", f"runs at T = {lo:g} against T = {hi:g}: windows with identical action counts "
              f"{span(same['identical'], 100, '.0f')} % for the same seed, "
              f"{span(other['identical'], 100, '.0f')} % for different seeds; curiosity curves correlate at "
              f"r = {span(same['r'])} for the same seed, {span(other['r'])} across seeds"]
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    """Bad input (no such sweep, no Boltzmann runs, no checkpoints or replay buffers) is a one-line
    message and exit status 2, before anything is written."""
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
    from evidence_cli import one_sweep_main

    return one_sweep_main("temperature_evidence.py", __doc__, evidence, argv)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
