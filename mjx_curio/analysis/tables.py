"""Tables: the headline table, mean +- sd across seeds per group of a sweep's key numbers
(`headline_table`), as a `Table` that prints as Markdown and writes CSV. Imports `sweeps` and
`stats`.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import math
import warnings

import numpy as np

from mjx_curio.analysis.stats import agent_contacts, mean_sd, object_contacts, per_agent_vae_loss
from mjx_curio.analysis.sweeps import Sweep


# ---------------------------------------------------------------------------------- headline table


@dataclasses.dataclass
class Table:
    """Rows of formatted cells (`rows`) and the numbers behind them (`values`: one dict per row)."""

    columns: list[str]
    rows: list[list[str]]
    values: list[dict]
    note: str = ""

    def to_markdown(self) -> str:
        out = ["| " + " | ".join(self.columns) + " |", "|" + "---|" * len(self.columns)]
        out += ["| " + " | ".join(r) + " |" for r in self.rows]
        return "\n".join(out) + (f"\n\n{self.note}\n" if self.note else "\n")

    def to_csv(self) -> str:
        buf = io.StringIO()
        keys = list(self.values[0]) if self.values else []
        w = csv.DictWriter(buf, fieldnames=keys, lineterminator="\n")  # the same file on every OS
        w.writeheader()
        # 12 significant digits: the last bits of a float differ between CPUs and NumPy builds
        # (summation order), and a committed CSV should not change with the machine that wrote it.
        w.writerows({k: f"{v:.12g}" if isinstance(v, float) else v for k, v in row.items()} for row in self.values)
        return buf.getvalue()

    def _repr_markdown_(self) -> str:
        return self.to_markdown()

    def __str__(self) -> str:
        return self.to_markdown()


def headline_table(sweep: Sweep, final_fraction: float = 0.1) -> Table:
    """Per group, mean +- sd across seeds of: the final curiosity (mean over agents and the last
    `final_fraction` of the windows), total agent-object contact steps, steps with the agents
    touching, the final VAE loss per image and MDN-RNN NLL (same last windows), the share of
    'stop' actions, and the number of runs halted by a non-finite loss."""
    k = max(1, int(math.ceil(final_fraction * sweep.n_windows)))
    last = slice(sweep.n_windows - k, sweep.n_windows)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        final_cur = np.nanmean(sweep.metrics["curiosity"][:, last], axis=(1, 2))
        final_vae = np.nanmean(per_agent_vae_loss(sweep)[:, last], axis=1)
        final_nll = np.nanmean(sweep.metrics["nll"][:, last], axis=1)
    obj = object_contacts(sweep).sum(axis=1)
    agt = agent_contacts(sweep).sum(axis=1)
    acts = sweep.metrics["action_counts"].sum(axis=(1, 2))  # [runs, actions]
    stop = acts[:, sweep.actions.index("stop")] / np.maximum(acts.sum(axis=1), 1) if "stop" in sweep.actions else np.full(sweep.n_runs, np.nan)
    halted = np.zeros(sweep.n_runs, bool)
    for r in sweep.progress.get("halted", {}):
        halted[int(r)] = True
    span = f"last {k * sweep.metrics_every:,} steps"
    cols = ["group", "runs", f"curiosity ({span})", "agent-object contact steps", "agent-agent contact steps",
            f"VAE loss per image ({span})", f"MDN-RNN NLL ({span})", "'stop' share of actions", "halted runs"]
    rows, values = [], []
    for g in sweep.groups():
        ix = g.indices
        stats = {}
        for key, v in (("curiosity", final_cur), ("object_contacts", obj), ("agent_contacts", agt),
                       ("vae_loss", final_vae), ("nll", final_nll), ("stop_share", stop)):
            mean, sd, _ = mean_sd(v[ix])
            stats[key] = (float(mean), float(sd))
        fmt = lambda ms, d=3: _pm(*ms, d)  # noqa: E731
        rows.append([g.label, str(g.n), fmt(stats["curiosity"]), fmt(stats["object_contacts"], 0),
                     fmt(stats["agent_contacts"], 0) if sweep.n_agents > 1 else "n/a", fmt(stats["vae_loss"], 1),
                     fmt(stats["nll"], 2), fmt(stats["stop_share"], 3), str(int(halted[ix].sum()))])
        row = {"group": g.label, "policy": g.policy, g.setting: g.value, "runs": g.n}
        for key, (m, s) in stats.items():
            row[f"{key}_mean"], row[f"{key}_sd"] = m, s
        row["halted"] = int(halted[ix].sum())
        values.append(row)
    keys = list(dict.fromkeys(k for v in values for k in v))  # every row's columns, in order
    values = [{k: v.get(k, "") for k in keys} for v in values]
    note = (f"{sweep.path.name}: {sweep.n_agents} agent(s), {sweep.steps_done:,} steps, image {sweep.image} px. "
            "Each cell: mean ± sd across seeds (sd omitted with one seed). Contact steps: agent steps in contact, "
            "summed over agents and objects for agent-object; steps with the two agents touching for agent-agent.")
    return Table(cols, rows, values, note)


def _pm(mean: float, sd: float, digits: int) -> str:
    if not np.isfinite(mean):
        return "n/a"
    if not np.isfinite(sd):
        return f"{mean:,.{digits}f}"
    return f"{mean:,.{digits}f} ± {sd:,.{digits}f}"
