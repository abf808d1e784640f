"""Evidence for the MDN-RNN's training latents: `latents=stored` against `latents=reencode`.

    python experiments/latents_evidence.py staleness runs/latents/stored
    python experiments/latents_evidence.py curves runs/latents/stored runs/latents/reencode

`staleness SWEEP` measures, at the sweep's newest checkpoint (the one that keeps the replay
buffers), how far the latents stored in replay when each step was acted lie from what the
current encoder makes of the same frames, relative to the spread of latents, and appends the
figures to docs/latents/staleness.json (one entry per sweep and step; run it at 1k, 5k, ...
by resuming the sweep to each step in turn).

`curves STORED REENCODE` draws both sweeps' curiosity (and MDN-RNN loss) with 95 % confidence
bands across seeds into docs/figures/latents_*.png and writes docs/latents/curves.json: per
seed, the mean curiosity over the last quarter of the run, and Welch's t-test between modes.
"""

from __future__ import annotations

import json
import pathlib
import sys

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

import numpy as np

DOCS = pathlib.Path(__file__).resolve().parents[1] / "docs"


def staleness(path: str) -> dict:
    import jax
    import jax.numpy as jnp

    from mjx_curio import analysis as an
    from mjx_curio import world_model as wm
    from mjx_curio.analysis.action_values import replay_step

    sweep = an.load(path)
    cfg = sweep.learner_config()
    step = replay_step(sweep)  # SweepError, before anything is computed, where none kept the buffers
    replay = sweep.restore_replay(step, keys=("frames", "latents", "size", "index"))
    state = sweep.restore_raw(step)
    enc = jax.jit(lambda params, stats, frames: wm.encode(cfg, params, frames, stats))
    rows = []
    for r in range(sweep.n_runs):
        size, head = int(replay["size"][r]), int(replay["index"][r])
        frames, stored = replay["frames"][r, :size], replay["latents"][r, :size]  # [N, agents, ...]
        vae = jax.tree.map(lambda x: x[r], state["learner"]["vae"])
        stats = jax.tree.map(lambda x: x[r], state["learner"].get("vae_stats", {}))
        mus, sigmas = [], []
        for lo in range(0, size, 512):
            mu, logvar = enc(vae, stats, jnp.asarray(frames[lo:lo + 512]))
            mus.append(np.asarray(mu))
            sigmas.append(np.exp(0.5 * np.asarray(logvar)))
        mu, sigma = np.concatenate(mus), np.concatenate(sigmas)
        # Age of each slot in agent steps: the slot just before the write head is the newest.
        age = (head - 1 - np.arange(size)) % replay["frames"].shape[1] + 1
        rng = np.random.default_rng(r)
        fresh = mu + sigma * rng.standard_normal(mu.shape)  # what the current encoder would store now
        d_stored = np.linalg.norm(stored - mu, axis=-1)  # [N, agents]
        d_fresh = np.linalg.norm(fresh - mu, axis=-1)
        i, j = rng.integers(0, size, 4000), rng.integers(0, size, 4000)
        spread = float(np.mean(np.linalg.norm(mu[i] - mu[j], axis=-1)))
        old = age > np.median(age)
        rows.append({"run": sweep.runs[r].name, "entries": size, "spread": spread,
                     "stored_vs_current": float(d_stored.mean()), "fresh_sample_vs_current": float(d_fresh.mean()),
                     "stored_vs_current_older_half": float(d_stored[old].mean()),
                     "stored_vs_current_newer_half": float(d_stored[~old].mean())})
    summary = {k: float(np.mean([row[k] for row in rows])) for k in rows[0] if k not in ("run", "entries")}
    result = {"sweep": str(path), "step": step, "z": cfg.z, "latents": cfg.latents, "runs": rows, "mean": summary,
              "relative": {"stored": summary["stored_vs_current"] / summary["spread"],
                           "fresh_sample": summary["fresh_sample_vs_current"] / summary["spread"],
                           "stored_older_half": summary["stored_vs_current_older_half"] / summary["spread"],
                           "stored_newer_half": summary["stored_vs_current_newer_half"] / summary["spread"]}}
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
    from evidence_cli import save_entry

    save_entry(DOCS / "latents" / "staleness.json", result, keys=("sweep", "step"), indent=2)
    print(json.dumps({"step": step, **result["relative"]}, indent=1))
    return result


def curves(stored_path: str, reencode_path: str) -> dict:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mjx_curio import analysis as an

    sweeps = {"stored": an.load(stored_path), "reencode": an.load(reencode_path)}
    colors = {"stored": "tab:blue", "reencode": "tab:orange"}
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    result = {}
    for name, sweep in sweeps.items():
        steps = sweep.steps[: sweep.steps_done // sweep.manifest["metrics"]["every"]]
        n = len(steps)
        for ax, metric, label in ((axes[0], "curiosity", "curiosity"), (axes[1], "nll", "MDN-RNN loss")):
            x = sweep.metrics[metric][:, :n]
            x = x.mean(axis=-1) if x.ndim == 3 else x  # both agents
            sm = an.moving_average(x, 50, axis=1)
            mean, lo, hi, _ = an.mean_ci(sm, axis=0)
            ax.plot(steps, mean, color=colors[name], label=f"latents={name} ({x.shape[0]} seeds)")
            ax.fill_between(steps, lo, hi, color=colors[name], alpha=0.25, lw=0)
            ax.set_xlabel("agent step")
            ax.set_ylabel(label + (" (mean squared latent error per dimension)" if metric == "curiosity" else " (nats)"))
            ax.legend()
        cur = sweep.metrics["curiosity"][:, :n].mean(axis=-1)
        last = cur[:, 3 * n // 4:].mean(axis=1)
        result[name] = {"seeds": int(cur.shape[0]), "steps": int(steps[-1]), "last_quarter_curiosity": last.tolist()}
    axes[0].set_title("Curiosity, moving average of 50 windows, 95 % CI across seeds")
    axes[1].set_title("MDN-RNN negative log-likelihood")
    fig.tight_layout()
    out = DOCS / "figures" / "latents_curves.png"
    fig.savefig(out, dpi=90)
    a, b = np.array(result["stored"]["last_quarter_curiosity"]), np.array(result["reencode"]["last_quarter_curiosity"])
    w = an.welch_t(a, b)
    result["welch_last_quarter"] = {"t": w["t"], "p": w["p"], "stored_mean": float(a.mean()),
                                    "reencode_mean": float(b.mean())}
    (DOCS / "latents").mkdir(parents=True, exist_ok=True)
    (DOCS / "latents" / "curves.json").write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result["welch_last_quarter"], indent=1))
    return result


COMMANDS = {"staleness": (1, "SWEEP"), "curves": (2, "STORED REENCODE")}


def main(argv: list[str]) -> int:
    """`staleness SWEEP` or `curves STORED REENCODE`; anything else, or a sweep that cannot be read
    (SweepError), is a message and exit status 2, before anything is written."""
    from mjx_curio.analysis import SweepError
    from mjx_curio.cli import wants_help

    what, args = (argv[0], argv[1:]) if argv else (None, [])
    usage = "\n".join(f"    python experiments/latents_evidence.py {k} {v}" for k, (_, v) in COMMANDS.items())
    if wants_help(argv):
        print(usage)
        return 0
    if what not in COMMANDS or len(args) != COMMANDS[what][0]:
        print(f"latents_evidence.py: want one of\n{usage}", file=sys.stderr)
        return 2
    try:
        {"staleness": staleness, "curves": curves}[what](*args)
    except SweepError as err:
        print(f"latents_evidence.py: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
