"""What the memory's history is worth to the curiosity: the curiosity the authors' code logs

    python experiments/history_evidence.py runs/paper/multi_agent.spread

The authors' code logs, as the curiosity of its figures, the mean over each update's replay batch
of the memory's error predicting the next latent one step from a zero state (README, Fidelity);
the curiosity here is each step's reward from the memory's live state. At the sweep's newest
checkpoint (the one that keeps the replay buffers), every run's networks are evaluated on every
pair of consecutive steps in its replay buffer (`analysis.curiosity_noise`) twice: from the memory
carry the agents acted with, and from a zero carry. Per run, the mean over those steps and the
agents of the curiosity's expectation each way, of the posterior's spread (the same both ways),
and of the sweep's own curiosity over the same last steps (its metrics). The memory here learned
from the carries it acted with, never from zero, so its error from a zero carry is likely above
what a memory trained from zero (the authors') makes there, and that is likely above the error
with the history: the authors' kind of number should lie between the two.

Writes docs/results/history.json (one entry per sweep, replacing an earlier entry of the same
sweep) and prints the entry as `results.py page` puts it in docs/results.md, under "The paper's
numbers beside ours" (a Markdown table, one row per group).
"""

from __future__ import annotations

import pathlib
import sys

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

import numpy as np

OUT = pathlib.Path(__file__).resolve().parents[1] / "docs" / "results" / "history.json"


def evidence(path: str) -> dict:
    from mjx_curio import analysis as an
    from mjx_curio.analysis.action_values import replay_step

    sweep = an.load(path)
    step = replay_step(sweep)  # SweepError, before anything is computed, where none kept the buffers
    runs = []
    for i, r in enumerate(sweep.runs):
        live = an.curiosity_noise(sweep, i, step=step)
        zero = an.curiosity_noise(sweep, i, step=step, zero_state=True)
        n = live.expected.shape[0]
        # The windows of the sweep's metrics that lie in the buffer's last n + 1 steps.
        recent = (sweep.steps > step - (n + 1)) & (sweep.steps <= step)
        runs.append({"run": r.name, "group": r.group_label, "seed": r.seed, "steps": int(n),
                     "live": float(live.expected.mean()), "zero": float(zero.expected.mean()),
                     "spread": float(live.spread.mean()),
                     "logged": float(np.nanmean(sweep.metrics["curiosity"][i][recent]))})
    entry = {"sweep": sweep.name, "replay_step": step, "runs": runs}
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
    import results  # the page's own table of an entry
    from evidence_cli import save_entry

    save_entry(OUT, entry)
    print(results.history_table(entry))
    print(f"wrote {OUT}")
    return entry


def main(argv: list[str]) -> int:
    """Bad input (no such sweep, no checkpoints or replay buffers) is a one-line message and exit
    status 2, before anything is written."""
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
    from evidence_cli import one_sweep_main

    return one_sweep_main("history_evidence.py", __doc__, evidence, argv)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
