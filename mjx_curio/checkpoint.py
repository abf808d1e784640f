"""Orbax checkpoints of a sweep: save, find the newest complete one, restore.

Layout under `<sweep>/checkpoints/`:
    state/<step>/    every run's RunState without its replay buffer: networks, optimiser
                     states, MDN-RNN memory, current views and latents, UCB counts, RNG keys,
                     arena state, counters. Small (about 20 MB a run at the paper's sizes).
                     Kept: the newest `keep_last`, every multiple of `keep_every`, and `keep_steps`
                     (early steps for the notebook's early-versus-late reconstructions).
    replay/<step>/   every run's replay buffer (about 245 MB a run at 64 x 64 and 10,000 steps),
                     newest only. Absent when the sweep runs with save_replay=false.

Orbax writes each item into a temporary directory and renames it when complete, so a process
killed mid-write leaves no half checkpoint that looks whole. A checkpoint is complete when its
state, and (unless save_replay=false) its replay, both exist; `latest_complete` returns the
newest such step, so a kill between the two writes falls back to the previous checkpoint.

Asynchronous (the sweep's async_checkpoints, by default on a GPU or TPU): `save` returns once
orbax holds the arrays on the host (a copy from an accelerator; on a CPU, views that keep the
buffers alive, so the next chunk cannot donate them and allocates its own), and the compression
and writing go on in background threads while the sweep steps on. `writing()` says whether they
still run, `wait()` ends them; the next `save` waits for the previous one first. The files are
the same either way.
"""

from __future__ import annotations

import math
import os
import pathlib
import shutil
import signal
from typing import Collection

import jax
import numpy as np
import orbax.checkpoint as ocp
from orbax.checkpoint.checkpoint_managers import preservation_policy as pp

from mjx_curio import run as run_lib

# Fault injection for tests/test_sweep.py: "<point>:<step>" kills this process with SIGKILL at
# that point of saving checkpoint <step>. The only point: "after-state" (state written, replay not).
CRASH_ENV = "MJX_CURIO_CRASH_AT"


class Checkpoints:
    def __init__(
        self,
        directory: pathlib.Path,
        save_replay: bool = True,
        keep_last: int = 2,
        keep_every: int | None = None,
        keep_steps: tuple = (),
        read_only: bool = False,
        asynchronous: bool = False,
    ):
        self.directory = pathlib.Path(directory)
        self.save_replay = save_replay
        self.asynchronous = asynchronous
        policies = [pp.LatestN(keep_last)]
        if keep_every:
            policies.append(pp.EveryNSteps(keep_every))
        if keep_steps:
            policies.append(pp.CustomSteps(list(keep_steps)))
        self.state = self._manager("state", pp.AnyPreservationPolicy(policies), read_only)
        replay_dir = self.directory / "replay"
        self.replay = None
        if save_replay or replay_dir.exists():
            self.replay = self._manager("replay", pp.LatestN(1), read_only)

    def _manager(self, name: str, policy, read_only: bool) -> ocp.CheckpointManager:
        options = ocp.CheckpointManagerOptions(
            preservation_policy=policy,
            enable_async_checkpointing=self.asynchronous,
            # Written in the background, the state's and the replay's writes run at once, and each
            # manager's threads meet the other processes' at barriers named alike: without a prefix
            # of its own, one manager's barrier can pair with the other's, and a process finalises
            # a checkpoint before the others have written their parts.
            multiprocessing_options=ocp.options.MultiprocessingOptions(barrier_sync_key_prefix=name),
            create=not read_only,
            read_only=read_only,
        )
        return ocp.CheckpointManager((self.directory / name).absolute(), options=options)

    # ------------------------------------------------------------------------------ save

    def save(self, step: int, states: run_lib.RunState) -> None:
        """Checkpoint `step`: written when this returns, or, asynchronous, under way (`wait`)."""
        self.wait()  # the previous checkpoint complete first, whatever orbax would do
        state, replay = run_lib.split_replay(states)
        self.state.save(step, args=ocp.args.StandardSave(to_nested(state)))
        if _crash_requested("after-state", step):
            self.state.wait_until_finished()
            os.kill(os.getpid(), signal.SIGKILL)
        if self.save_replay:
            self.replay.save(step, args=ocp.args.StandardSave(to_nested(replay)))
        if not self.asynchronous:
            self.wait()

    def writing(self) -> bool:
        """Whether a checkpoint is still being written in the background."""
        return any(m.is_saving_in_progress() for m in self._managers())

    def wait(self) -> None:
        """Block until every checkpoint started is complete on disk."""
        for m in self._managers():
            m.wait_until_finished()

    def _managers(self) -> list[ocp.CheckpointManager]:
        return [m for m in (self.state, self.replay) if m is not None]

    # ------------------------------------------------------------------------------ find

    def state_steps(self) -> list[int]:
        self.state.reload()
        return sorted(self.state.all_steps())

    def replay_steps(self) -> list[int]:
        if self.replay is None:
            return []
        self.replay.reload()
        return sorted(self.replay.all_steps())

    def latest_complete(self) -> int | None:
        steps = set(self.state_steps())
        if self.save_replay:
            steps &= set(self.replay_steps())
        return max(steps) if steps else None

    def drop_after(self, step: int) -> list[int]:
        """Delete checkpoints newer than `step` (left incomplete by a crash; a resumed sweep
        rewrites them identically). Returns the steps removed."""
        removed = []
        for mgr in (self.state, self.replay):
            if mgr is None:
                continue
            for s in mgr.all_steps():
                if s > step:
                    mgr.delete(s)
                    removed.append(s)
        return sorted(set(removed))

    # ------------------------------------------------------------------------------ restore

    def restore(self, step: int, abstract: run_lib.RunState, with_replay: bool = True) -> run_lib.RunState:
        """The sweep state of checkpoint `step`, laid out like `abstract` (ShapeDtypeStructs with
        shardings, e.g. from jax.eval_shape of the sweep's init). Without the replay (or when it
        was not saved) the buffers come back as `abstract.replay` describes them: zeros."""
        a_state, a_replay = run_lib.split_replay(abstract)
        nested = self.state.restore(step, args=ocp.args.StandardRestore(to_nested(a_state)))
        state = from_nested(nested, a_state)
        if with_replay and self.replay is not None and step in self.replay.all_steps():
            nested = self.replay.restore(step, args=ocp.args.StandardRestore(to_nested(a_replay)))
            replay = from_nested(nested, a_replay)
        else:
            replay = jax.tree.map(lambda a: jax.numpy.zeros(a.shape, a.dtype, device=a.sharding), a_replay)
        return run_lib.with_replay(state, replay)

    def restore_raw(self, step: int, item: str = "state", keys: Collection[str] | None = None) -> dict:
        """Checkpoint `step`'s `item` ("state", or "replay" where one was saved) as nested dicts of
        NumPy arrays, no target structure needed (what mjx_curio.analysis uses to decode with saved
        parameters). Reads a sweep saved on any number of devices, e.g. on a GPU host, on a one-CPU
        laptop. With `keys`, only those top-level entries are read and the others are left out: a
        paper-size replay's frames alone are 245 MB a run."""
        path = (self.directory / item / str(step) / "default").absolute()  # orbax wants absolute paths
        with ocp.PyTreeCheckpointer() as reader:
            meta = reader.metadata(path)
            tree = dict(getattr(meta, "item_metadata", meta).items())
            unknown = sorted(set(keys or ()) - set(tree))
            if unknown:
                raise KeyError(f"{path} has no {', '.join(unknown)}; it holds {', '.join(sorted(tree))}")
            wanted = {k: keys is None or k in keys for k in tree}
            # One tree serves as both the structure to restore and the per-leaf arguments: NumPy
            # arrays for the leaves wanted (no device or sharding involved), ocp.PLACEHOLDER for
            # the leaves to leave on disk.
            args = {k: jax.tree.map(lambda _: ocp.RestoreArgs(restore_type=np.ndarray) if wanted[k] else ocp.PLACEHOLDER, v)
                    for k, v in tree.items()}
            out = reader.restore(path, args=ocp.args.PyTreeRestore(item=args, restore_args=args))
        return {k: v for k, v in out.items() if wanted[k]}

    def close(self) -> None:
        """Wait for any write under way, then release orbax's threads."""
        self.wait()
        self.state.close()
        if self.replay is not None:
            self.replay.close()


def to_nested(tree) -> dict:
    """A pytree as nested dicts keyed by field / key / index names, leaving out empty arrays.

    Orbax refuses zero-size arrays, and MJX's Data has several (e.g. `act` in a model without
    actuators); names keep the checkpoint readable without this package (e.g.
    state/<step>/learner/vae/...). `from_nested` rebuilds the pytree from its abstract twin.
    """
    out: dict = {}
    for path, leaf in jax.tree_util.tree_flatten_with_path(tree)[0]:
        if _size(leaf) == 0:
            continue
        names = [_key_name(k) for k in path]
        node = out
        for name in names[:-1]:
            node = node.setdefault(name, {})
        node[names[-1]] = leaf
    return out


def from_nested(nested: dict, like):
    """Inverse of `to_nested`: leaves of `like` (arrays or ShapeDtypeStructs) in order, taken
    from `nested`, empty ones recreated as zeros."""
    flat, treedef = jax.tree_util.tree_flatten_with_path(like)
    leaves = []
    for path, a in flat:
        if _size(a) == 0:  # placed like its twin, or shard_map refuses the restored state
            leaves.append(jax.numpy.zeros(a.shape, a.dtype, device=getattr(a, "sharding", None)))
            continue
        node = nested
        for k in path:
            node = node[_key_name(k)]
        leaves.append(node)
    return jax.tree_util.tree_unflatten(treedef, leaves)


def _size(x) -> int:
    return int(math.prod(x.shape))


def _key_name(k) -> str:
    for attr in ("name", "key", "idx"):
        if hasattr(k, attr):
            return str(getattr(k, attr))
    return str(k)


def _crash_requested(point: str, step: int) -> bool:
    spec = os.environ.get(CRASH_ENV, "")
    return bool(spec) and spec == f"{point}:{step}"


def remove_tmp_dirs(directory: pathlib.Path) -> list[pathlib.Path]:
    """Leftovers of writes killed mid-way (orbax's '*.orbax-checkpoint-tmp*' directories)."""
    found = [p for p in pathlib.Path(directory).rglob("*") if p.is_dir() and "orbax-checkpoint-tmp" in p.name]
    for p in found:
        shutil.rmtree(p, ignore_errors=True)
    return found
