"""The curiosity the authors' code logs, rebuilt on a sweep's replay buffers, with their memory and
their pairing of its training batches

    python experiments/authors_memory_evidence.py runs/paper/multi_agent.spread_ucb

The authors' code logs, as the curiosity of its figures, the mean over each update's replay batch
of its memory's error predicting the next latent one step from a zero state, with a memory of its
own (an LSTM with a linear head per agent, trained by mean squared error one step from a zero
state), and with two agents its batches put each view beside the actions, and the other agent's
view, of other transitions (`analysis.authors_memory`; README, Fidelity). At the sweep's newest
checkpoint (the one that keeps the replay buffers), for every run, a fresh memory of theirs learns
from the consecutive steps of the buffer, its views encoded by the run's VAE there and drawn from
the posterior afresh at every update, for as many updates as the buffer's steps saw (one every 4
steps), once with the authors' pairing and once with every view beside its own transition
(`pairing="matched"`; with one agent the two are one). Per run: the mean of the logged number over
the last quarter of those updates each way, the posterior's floor (the mean posterior variance,
which any memory logs), and the sweep's own curiosity over the buffer's steps (its metrics).

Writes docs/results/authors_memory.json (one entry per sweep, replacing an earlier entry of the same
sweep) and prints the entry as `results.py page` puts it in docs/results.md, under "The paper's
numbers beside ours" (a Markdown table, one row per group).
"""

from __future__ import annotations

import pathlib
import sys

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

import numpy as np

OUT = pathlib.Path(__file__).resolve().parents[1] / "docs" / "results" / "authors_memory.json"
UPDATE_EVERY = 4  # the authors' UPDATE_EVERY_N_STEPS


def evidence(path: str) -> dict:
    from mjx_curio import analysis as an
    from mjx_curio.analysis import authors_memory as am
    from mjx_curio.analysis.action_values import replay_step

    sweep = an.load(path)
    step = replay_step(sweep)  # SweepError, before anything is computed, where none kept the buffers
    size = sweep.restore_replay(step, keys=("size",))["size"]
    runs = []
    for i, r in enumerate(sweep.runs):
        n = int(size[r.index])
        updates = max(n // UPDATE_EVERY, 1)
        late = slice(updates - max(updates // 4, 1), updates)
        got = {"run": r.name, "group": r.group_label, "seed": r.seed, "steps": n, "updates": updates}
        for name in am.PAIRINGS if sweep.n_agents > 1 else ("matched",):  # one agent: one pairing
            out = am.logged_curiosity(sweep, i, step=step, pairing_name=name, updates=updates, seed=r.seed)
            got[name] = float(out["logged"][late].mean())
            got["floor"] = out["floor"]
        got.setdefault("authors", got["matched"])
        # The windows of the sweep's metrics that lie in the buffer's last n steps.
        recent = (sweep.steps > step - n) & (sweep.steps <= step)
        got["logged"] = float(np.nanmean(sweep.metrics["curiosity"][i][recent]))
        runs.append(got)
    entry = {"sweep": sweep.name, "replay_step": step, "agents": sweep.n_agents, "runs": runs}
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
    import results  # the page's own table of an entry
    from evidence_cli import save_entry

    save_entry(OUT, entry)
    print(results.authors_memory_table(entry))
    print(f"wrote {OUT}")
    return entry


def main(argv: list[str]) -> int:
    """Bad input (no such sweep, no checkpoints or replay buffers) is a one-line message and exit
    status 2, before anything is written."""
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
    from evidence_cli import one_sweep_main

    return one_sweep_main("authors_memory_evidence.py", __doc__, evidence, argv)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
