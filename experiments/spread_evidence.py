"""Where the posterior's spread comes from, checkpoint by checkpoint (claim 1's parts)

    python experiments/spread_evidence.py runs/paper/single_agent.spread

Every run's VAE at every kept checkpoint encodes the same views, every 10th of the replay buffer
kept at the newest checkpoint (`analysis.posterior_dims`), and gives each latent dimension's
posterior variance sigma_d^2, mean over those views. Per run and checkpoint: the spread (the mean
over the dimensions, the part of the curiosity no prediction removes), the median dimension's
variance, and how many of the dimensions have a variance above NEAR_PRIOR, closer to the prior's 1
than to a precise code: ones the VAE has all but stopped using, each of which adds its
sigma_d^2 / latent to every step's curiosity whatever the world model learns. A spread that rises
while the median falls is a code growing more unequal: some dimensions sharper, others left to
noise.

Writes docs/results/posterior_dims.json (one entry per sweep, replacing an earlier entry of the
same sweep) and prints the entry as `results.py page` puts it in docs/results.md, under claim 1's
parts (a Markdown table, one row per group): with the runs of every seed part of the experiment
saved there, measured on buffers of the same step (`multi_agent.per_step` and
`multi_agent.per_step.seeds-3-5` as one).
"""

from __future__ import annotations

import pathlib
import sys

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

import numpy as np

OUT = pathlib.Path(__file__).resolve().parents[1] / "docs" / "results" / "posterior_dims.json"
NEAR_PRIOR = 0.5  # sigma_d^2 above this: the dimension's code is mostly noise
EVERY = 10  # every 10th view of the buffer


def evidence(path: str) -> dict:
    from mjx_curio import analysis as an
    from mjx_curio.analysis.action_values import replay_step

    sweep = an.load(path)
    step = replay_step(sweep)  # SweepError, before anything is computed, where none kept the buffers
    reduce = np.mean if sweep.learner_config().curiosity == "mean" else np.sum  # as curiosity reduces
    runs = []
    for i, r in enumerate(sweep.runs):
        dims = an.posterior_dims(sweep, i, every=EVERY, step=step)
        runs.append({"run": r.name, "group": r.group_label, "seed": r.seed,
                     "by_checkpoint": {str(k): {"spread": float(reduce(v)), "median": float(np.median(v)),
                                                "near_prior": int((v > NEAR_PRIOR).sum()),
                                                "sigma2": [round(float(x), 4) for x in v]} for k, v in dims.items()}})
    entry = {"sweep": sweep.name, "replay_step": step,
             "every": EVERY, "near_prior": NEAR_PRIOR, "latent": sweep.learner_config().latent, "runs": runs}
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
    import results  # the page's own table of an entry
    from evidence_cli import save_part

    print(results.posterior_dims_table(save_part(OUT, entry, keys=("sweep",), same=results.POSTERIOR_DIMS_POOLED_BY)))
    print(f"wrote {OUT}")
    return entry


def main(argv: list[str]) -> int:
    """Bad input (no such sweep, no checkpoints or replay buffers) is a one-line message and exit
    status 2, before anything is written."""
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
    from evidence_cli import one_sweep_main

    return one_sweep_main("spread_evidence.py", __doc__, evidence, argv)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
