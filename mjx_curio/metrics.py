"""What a sweep records, and how it lands on disk.

Metrics are kept per window of `metrics_every` agent steps (20 by default, the paper's sampling
interval): window w covers steps [w * metrics_every, (w + 1) * metrics_every). Each metric is one
NumPy `.npy` file under `<sweep>/metrics/`, shape `[runs, windows, ...]`, so any tool that reads
NumPy arrays (numpy.load, or numpy.lib.format for other languages) reads a sweep without this
package. `metrics/steps.npy` holds the step at the end of each window, and `manifest.json` lists
the runs (policy, seed, settings) in the order of the first axis, and `SCHEMA` below as text.

Files are preallocated at their full size (NaN / 0 where nothing was written yet) and filled as
chunks finish; `progress.json` says how many windows are final. A resumed sweep rewrites the
windows after its checkpoint with identical values (runs are deterministic).
"""

from __future__ import annotations

import dataclasses
import json
import os
import pathlib
import numpy as np

from mjx_curio.arena import ACTIONS, OBJECTS

VIEW_TARGETS = OBJECTS + ("other_agent",)


DIM_SIZES = {"actions": len(ACTIONS), "objects": len(OBJECTS), "view_targets": len(VIEW_TARGETS), "pose": 3, "xyz": 3}


@dataclasses.dataclass(frozen=True)
class Metric:
    dtype: str
    dims: tuple  # trailing dimensions after [runs, windows], by name ("agents" = n_agents)
    unit: str
    meaning: str

    def shape(self, n_agents: int) -> tuple:
        return tuple(n_agents if d == "agents" else DIM_SIZES[d] for d in self.dims)


A = ("agents",)
SCHEMA: dict[str, Metric] = {
    "curiosity": Metric("float32", A, "squared latent distance",
                        "curiosity reward r (eq. 3): squared error between z_{t+1} and E[z_hat_{t+1}], averaged "
                        "(curiosity=mean) or summed (curiosity=sum) over the latent dimensions; mean over the "
                        "window's steps, per agent"),
    # What the authors' code logs as curiosity: a statistic of each training batch (eq. 3 on the
    # latents the memory trains on), not the reward the agent gets along its own trajectory.
    "batch_curiosity": Metric("float32", A, "squared latent distance",
                              "curiosity of the learner update's training batch: eq. 3 on the latents the MDN-RNN "
                              "trains on (re-encoded by the current VAE, batch normalisation by the batch's own "
                              "statistics), the self-models' targets, mean over its transitions; mean over the "
                              "window's updates, per agent"),
    "curiosity_sample": Metric("float32", A, "squared latent distance",
                               "curiosity reward at the window's last step (the paper's raw sample every 20 steps), per agent"),
    # Curiosity's expectation over the latent's sampling noise is the MDN-RNN's error against the
    # posterior mean plus this spread: curiosity minus it separates what learning can reduce.
    "curiosity_spread": Metric("float32", A, "squared latent distance",
                               "posterior variance sigma^2 of z_{t+1}, averaged (curiosity=mean) or summed "
                               "(curiosity=sum) over the latent dimensions: the part of the curiosity's expectation "
                               "over the latent's sampling noise that no prediction removes (0 under z=mean); mean "
                               "over the window's steps, per agent"),
    "predicted": Metric("float32", A, "squared latent distance",
                        "self-model's predicted curiosity of the action taken, mean over the window, per agent"),
    # Within-window second moments of the per-step (predicted, obtained) pairs: the window means
    # above cannot say whether the self-model tracks curiosity step by step, and these four give
    # the pooled within-window correlation without storing every step (analysis: claim 8).
    "predicted_var": Metric("float32", A, "(squared latent distance)^2",
                            "variance over the window's steps of the predicted curiosity of the action taken, per agent"),
    "curiosity_var": Metric("float32", A, "(squared latent distance)^2",
                            "variance over the window's steps of the curiosity obtained, per agent"),
    "predicted_curiosity_cov": Metric("float32", A, "(squared latent distance)^2",
                                      "covariance over the window's steps of the predicted and the obtained curiosity, "
                                      "per agent"),
    "curiosity_by_action": Metric("float32", ("agents", "actions"), "squared latent distance",
                                  "mean curiosity obtained at the window's steps that took each action (manifest "
                                  "'actions' order; NaN where none did), per agent"),
    "action_counts": Metric("int32", ("agents", "actions"), "steps",
                            "how often each action (manifest 'actions' order) was taken in the window, per agent"),
    "rotation_reversals": Metric("int32", A, "steps",
                                 "steps of the window at which the agent turned the other way than at the step before "
                                 "(rotate_left right after rotate_right, or the reverse), both steps in the window (its "
                                 "first step never counts), per agent: alternating turns, whose order action_counts "
                                 "does not keep"),
    "contact_object": Metric("int32", ("agents", "objects"), "steps",
                             "steps of the window in which the agent touched each object (manifest 'objects' order)"),
    "contact_agent": Metric("int32", A, "steps", "steps of the window in which the agent touched the other agent"),
    "view_fraction": Metric("float32", ("agents", "view_targets"), "fraction of pixels",
                            "share of the agent's view showing each object, then the other agent; mean over the window"),
    "agent_pose": Metric("float32", ("agents", "pose"), "m, m, rad", "x, y and heading of each agent at the window's end (frozen once the run is halted)"),
    "object_pos": Metric("float32", ("objects", "xyz"), "m", "position of each object's body origin at the window's end (frozen once the run is halted)"),
    "steps_taken": Metric("int32", (), "steps", "steps the run actually took in the window (fewer once halted)"),
    "vae_loss": Metric("float32", (), "nats (summed over pixels and agents)",
                       "VAE loss (eq. 5: reconstruction + beta * KL, with free bits if kl_tolerance > 0), "
                       "mean over the window's updates"),
    "recon": Metric("float32", (), "sum of squared pixel errors",
                    "VAE reconstruction error per image, summed over agents, mean over the window's updates"),
    "kl": Metric("float32", (), "nats", "VAE KL divergence, summed over agents, mean over updates"),
    "nll": Metric("float32", (), "nats", "MDN-RNN negative log-likelihood per transition (eq. 6), mean over updates"),
    "self_loss": Metric("float32", (), "squared curiosity error", "self-model loss (eq. 4) summed over agents, mean over updates"),
    "self_loss_agents": Metric("float32", A, "squared curiosity error", "each agent's self-model loss, mean over updates"),
    "updates": Metric("int32", (), "updates", "learner updates done in the window (0 before replay holds a sequence)"),
    "non_finite": Metric("int32", (), "updates", "updates discarded because a loss was not finite (the run halts)"),
}


def fill_value(dtype: str):
    return np.nan if dtype.startswith("float") else 0


class MetricsStore:
    """The `metrics/` directory of a sweep: one preallocated .npy memmap per metric. `names`: the
    metrics it holds, every one of SCHEMA by default; a sweep made before a metric was added
    goes on without it when resumed (its manifest lists what it records)."""

    def __init__(self, directory: pathlib.Path, n_runs: int, n_windows: int, n_agents: int, create: bool,
                 names=None):
        self.directory = pathlib.Path(directory)
        self.n_runs, self.n_windows, self.n_agents = n_runs, n_windows, n_agents
        self.arrays: dict[str, np.memmap] = {}
        if create:
            self.directory.mkdir(parents=True, exist_ok=False)
        for name, spec in SCHEMA.items():
            if names is not None and name not in names:
                continue
            path = self.directory / f"{name}.npy"
            shape = (n_runs, n_windows) + spec.shape(n_agents)
            if create:
                arr = np.lib.format.open_memmap(path, mode="w+", dtype=spec.dtype, shape=shape)
                arr[...] = fill_value(spec.dtype)
            else:
                arr = np.lib.format.open_memmap(path, mode="r+")
                if arr.shape != shape or arr.dtype != np.dtype(spec.dtype):
                    raise ValueError(f"{path}: shape {arr.shape} {arr.dtype}, expected {shape} {spec.dtype}")
            self.arrays[name] = arr

    def write(self, first_window: int, chunk: dict) -> None:
        """Store a chunk's metrics (each [n_runs, windows, ...]) from window `first_window`."""
        for name, arr in self.arrays.items():
            values = np.asarray(chunk[name])
            arr[:, first_window : first_window + values.shape[1]] = values

    def flush(self) -> None:
        for arr in self.arrays.values():
            arr.flush()


def write_steps(directory: pathlib.Path, n_windows: int, every: int) -> None:
    np.save(pathlib.Path(directory) / "steps.npy", (np.arange(n_windows, dtype=np.int64) + 1) * every)


def schema_doc() -> dict:
    """SCHEMA as plain data for the manifest."""
    return {
        name: {"dtype": m.dtype, "dims": ["runs", "windows", *m.dims], "unit": m.unit, "meaning": m.meaning}
        for name, m in SCHEMA.items()
    }


def write_json_atomic(path: pathlib.Path, obj) -> None:
    """Write JSON so a reader (or a crash) never sees half a file: temp file, fsync, rename."""
    path = pathlib.Path(path)
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "w") as f:
        json.dump(obj, f, indent=2, sort_keys=True, default=str)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)
