"""What a Boltzmann sweep's temperatures change: one row per temperature T of what its runs did,
and a last row testing each measure across T, blocked by seed (`temperature_table`); the same
measures per policy of any sweep (`policy_measures_table`), to set the temperatures beside them.

Runs of one seed draw the same random numbers, and where the policy is near-uniform they repeat
much of each other's course at every T (`claims.seed_coupling`), so each measure's test across T
removes each seed's own level first (`significance.block_anova`). Imports `claims`, `significance`, `stats`,
`tables`.
"""

from __future__ import annotations

import math

import numpy as np

from mjx_curio.analysis.claims import late_curiosity, seed_table
from mjx_curio.analysis.significance import block_anova
from mjx_curio.analysis.stats import cells_visited, mean_ci, object_contacts
from mjx_curio.analysis.sweeps import Sweep, SweepError
from mjx_curio.analysis.tables import Table

# (key, column heading, format): the measures, each one number a run. The action measures sit
# close to a uniform choice's (1 and 1/7) at the paper's temperatures, so they keep more digits.
MEASURES = (
    ("late_curiosity", "late curiosity (last quarter)", ".3g"),
    ("action_entropy", "action entropy / ln 7", ".5f"),
    ("top_share", "most chosen action's share", ".4f"),
    ("object_contacts", "object contacts per 1,000 agent-steps", ".3g"),
    ("floor_cells", "floor squares visited (0.25 m), per agent", ".3g"),
)


def temperature_measures(sweep: Sweep, late_fraction: float = 0.25) -> dict[str, np.ndarray]:
    """{measure: [runs]} for every run of the sweep. `late_curiosity`: mean curiosity over the last
    `late_fraction` of the windows, mean of the agents (claim 7's statistic). From the whole run,
    agents pooled: `action_entropy`, the entropy of the action shares over ln(number of actions)
    (1: every action equally often); `top_share`, the most chosen action's share of the steps;
    `object_contacts`, agent-object contact steps (summed over agents and objects) per 1,000
    agent-steps; `floor_cells`, the 0.25 m squares of floor an agent was in at the windows' ends
    (`stats.cells_visited`), mean of the agents: how far it roamed, and so how varied its views."""
    counts = sweep.metrics["action_counts"].astype(float).sum(axis=(1, 2))  # [runs, actions]
    shares = counts / np.maximum(counts.sum(axis=1, keepdims=True), 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        plogp = np.where(shares > 0, shares * np.log(shares), 0.0)
    agent_steps = sweep.metrics["steps_taken"].astype(float).sum(axis=1) * sweep.n_agents
    return {
        "late_curiosity": late_curiosity(sweep, late_fraction),
        "action_entropy": -plogp.sum(axis=1) / math.log(shares.shape[1]),
        "top_share": shares.max(axis=1),
        "object_contacts": 1000 * object_contacts(sweep).astype(float).sum(axis=1) / np.maximum(agent_steps, 1),
        "floor_cells": cells_visited(sweep.metrics["agent_pose"]).mean(axis=1).astype(float),
    }


def _measure_rows(m: dict[str, np.ndarray], groups, first: list[str], first_values: list[dict]):
    """Per group: its first cells (`first`, `first_values`), then each measure's mean and 95 % CI
    across seeds, formatted and as numbers (mean, low, high; F and p NaN)."""
    rows, values = [], []
    for g, head, head_values in zip(groups, first, first_values):
        row, vals = [head, str(g.n)], {**head_values, "runs": g.n}
        for key, _, fmt in MEASURES:
            mean, lo, hi, _ = (float(v) for v in mean_ci(m[key][g.indices]))
            band = f" [{lo:{fmt}}, {hi:{fmt}}]" if math.isfinite(lo) else ""
            row.append(f"{mean:{fmt}}{band}")
            vals.update({key: mean, f"{key} low": lo, f"{key} high": hi, f"{key} F": math.nan, f"{key} p": math.nan})
        rows.append(row)
        values.append(vals)
    return rows, values


def temperature_table(sweep: Sweep, late_fraction: float = 0.25) -> Table:
    """Per Boltzmann temperature (ascending): each measure's mean and 95 % CI across seeds; last
    row: for each measure, the ANOVA across temperatures blocked by seed, on the seeds that every
    temperature ran. `values` has the same keys in every row (NaN where a row has no such number):
    per measure its mean, low, high, F and p."""
    groups = sorted(sweep.groups("boltzmann"), key=lambda g: g.value)
    if not groups:
        raise SweepError(f"{sweep.path} has no Boltzmann runs")
    m = temperature_measures(sweep, late_fraction)
    columns = ["T", "runs"] + [heading for _, heading, _ in MEASURES]
    rows, values = _measure_rows(m, groups, [f"{g.value:g}" for g in groups], [{"T": float(g.value)} for g in groups])
    n_seeds = seed_table(sweep, groups, m["late_curiosity"]).shape[1]
    row, vals = ["across T, blocked by seed", f"{n_seeds} seeds"], {"T": math.nan, "runs": n_seeds}
    for key, _, _ in MEASURES:
        a = block_anova(seed_table(sweep, groups, m[key]))
        row.append(f"F({a['df1']}, {a['df2']}) = {a['F']:.3g}, p = {a['p']:.3g}" if math.isfinite(a["p"]) else "n/a")
        vals.update({key: math.nan, f"{key} low": math.nan, f"{key} high": math.nan, f"{key} F": a["F"],
                     f"{key} p": a["p"]})
    rows.append(row)
    values.append(vals)
    note = (f"{sweep.name}, {sweep.steps_done:,} steps a run: mean over seeds [95 % CI]; the last row tests each "
            "measure across temperatures after removing each seed's own level (runs of one seed share their "
            "random numbers).")
    return Table(columns, rows, values, note)


def policy_measures_table(sweep: Sweep, late_fraction: float = 0.25) -> Table:
    """The same measures per group of any sweep (a policy and its setting, in the sweep's order):
    where the Boltzmann temperatures sit among the other policies. `values`: per row the group's
    label, runs, and per measure its mean, low and high (F and p NaN)."""
    groups = sweep.groups()
    m = temperature_measures(sweep, late_fraction)
    columns = ["policy", "runs"] + [heading for _, heading, _ in MEASURES]
    rows, values = _measure_rows(m, groups, [g.label for g in groups], [{"policy": g.label} for g in groups])
    note = f"{sweep.name}, {sweep.steps_done:,} steps a run: mean over seeds [95 % CI]."
    return Table(columns, rows, values, note)
