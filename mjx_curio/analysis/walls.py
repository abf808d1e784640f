"""What a different texture on every wall changes: each walls-different sweep against the sweep
of the same agents with identical walls, policy by policy, over the steps both ran
(`walls_table`). The paper runs both arenas (its section 3.1) but names only one one-agent run as
having different walls, and compares nothing; this table is the comparison it leaves out.

Runs are the units (Welch's t-test across seeds); where a difference is not significant, how large
a one the data rule out (two one-sided tests) and the seeds a side the test would need to find it
8 times in 10 (`power.seeds_needed`, the observed
spread taken as the truth). A run whose simulation diverged counts only where its windows are data
(`sweeps.drop_diverged` blanks the rest). Imports `claims`, `power`, `significance`,
`stats`, `sweeps` and `tables`.
"""

from __future__ import annotations

import math
import warnings
from typing import Mapping

import numpy as np

from mjx_curio.analysis.claims import ALPHA, Tested
from mjx_curio.analysis.power import MAX_SEEDS, seeds_needed
from mjx_curio.analysis.significance import finite, tost_bound, welch_t
from mjx_curio.analysis.stats import object_contacts, per_agent_vae_loss
from mjx_curio.analysis.sweeps import Group, Sweep
from mjx_curio.analysis.tables import Table

# (walls different, identical walls): the presets compared.
WALLS_PAIRS = (("single_agent_walls_different", "single_agent"), ("multi_agent_walls_different", "multi_agent"))

# (key, what, format): the measures, each one number a run.
MEASURES = (
    ("curiosity", "curiosity", ".3g"),
    ("vae_loss", "VAE loss per image", ".1f"),
    ("recon", "of which reconstruction", ".1f"),
    ("object_contacts", "object contacts per 1,000 agent-steps", ".3g"),
)


def walls_measures(sweep: Sweep, end: int, late_steps: int) -> dict[str, np.ndarray]:
    """{measure: [runs]} over the sweep's first `end` steps. Over the windows lying wholly in the
    last `late_steps` of them: `curiosity`, the mean of the agents, then of the windows;
    `vae_loss`, the VAE's loss per image (`stats.per_agent_vae_loss`), and `recon`, its
    reconstruction term (summed squared pixel error per image; the rest is the KL term). Over all
    `end` steps: `object_contacts`, agent-object contact steps (agents and objects summed) per
    1,000 agent-steps taken. NaN for a run with no such window (one that diverged before)."""
    e = sweep.metrics_every
    late = slice(-(-max(end - late_steps, 0) // e), end // e)
    whole = slice(0, end // e)
    steps = sweep.metrics["steps_taken"][:, whole].astype(float).sum(axis=1) * sweep.n_agents
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a diverged run's all-NaN windows
        curiosity = np.nanmean(np.nanmean(sweep.metrics["curiosity"][:, late], axis=2), axis=1)
        vae = np.nanmean(per_agent_vae_loss(sweep)[:, late], axis=1)
        recon = np.nanmean(sweep.metrics["recon"][:, late] / sweep.n_agents, axis=1)
    contacts = object_contacts(sweep)[:, whole].astype(float).sum(axis=1)
    return {"curiosity": curiosity, "vae_loss": vae, "recon": recon,
            "object_contacts": np.where(steps > 0, 1000 * contacts / np.maximum(steps, 1), np.nan)}


def _same_group(sweep: Sweep, g: Group) -> Group | None:
    for h in sweep.groups(g.policy):
        if np.isclose(h.value, g.value):
            return h
    return None


def walls_table(presets: Mapping[str, Sweep], late_steps: int = 5000) -> Table:
    """One row per policy group of each walls-different preset that its identical-walls preset
    (`WALLS_PAIRS`) also ran, over the walls-different sweep's steps (the identical-walls runs cut
    to the same length; a pair where they are shorter is left out): per measure
    (`walls_measures`), the mean with different walls, the mean with identical walls, and the
    two-sided Welch p of their difference, and where p >= 0.05 the difference the data rule out
    (`significance.tost_bound`: two one-sided tests at 5 %) and the seeds a side that would find
    the observed difference with 80 % power (`power.seeds_needed`). `values`: per row the presets,
    group, steps compared, runs a side (those with a finite value), and per measure both means,
    the difference, p, that bound and those seeds (NaN where significant or no difference was
    seen)."""
    if not (isinstance(late_steps, (int, np.integer)) and late_steps > 0):
        raise ValueError(f"walls_table: late_steps={late_steps!r}; want a positive whole number of steps")
    columns = ["agents", "policy", "runs (different / same walls)"]
    columns += [f"{what}{', steps {late}' if key != 'object_contacts' else ', steps {whole}'}"
                for key, what, _ in MEASURES]
    rows, values, spans = [], [], set()
    for different, same in WALLS_PAIRS:
        d, s = presets.get(different), presets.get(same)
        if d is None or s is None or s.steps_done < d.steps_done:
            continue
        end = d.steps_done
        start = max(end - late_steps, 0)
        spans.add((start, end))
        md, ms = walls_measures(d, end, late_steps), walls_measures(s, end, late_steps)
        for g in d.groups():
            h = _same_group(s, g)
            if h is None:
                continue
            n_d = int(np.isfinite(md["curiosity"][g.indices]).sum())
            n_s = int(np.isfinite(ms["curiosity"][h.indices]).sum())
            row = [str(d.n_agents), g.label, f"{n_d} / {n_s}"]
            vals = {"different": different, "same": same, "agents": d.n_agents, "group": g.label, "steps": end,
                    "runs different": n_d, "runs same": n_s}
            for key, _, fmt in MEASURES:
                t = welch_t(md[key][g.indices], ms[key][h.indices])
                a, b = _nanmean(md[key][g.indices]), _nanmean(ms[key][h.indices])
                need = _seeds_for_power(md[key][g.indices], ms[key][h.indices], t)
                bound = tost_bound(t["diff"], t["se"], t["df"], ALPHA) if t["p"] >= ALPHA else math.nan
                p = f"p = {t['p']:.2g}" if math.isfinite(t["p"]) else "p n/a"
                if math.isfinite(bound):
                    p += f"; Δ within ±{bound:{fmt}}"
                if math.isfinite(need):
                    p += f"; {int(need):,} seeds"
                elif math.isinf(need):
                    p += f"; > {MAX_SEEDS:,} seeds"
                row.append(f"{a:{fmt}} vs {b:{fmt}} ({p})")
                vals.update({f"{key} different": a, f"{key} same": b, f"{key} diff": t["diff"], f"{key} p": t["p"],
                             f"{key} equivalence bound": bound, f"{key} seeds for 80 % power": need})
            rows.append(row)
            values.append(vals)
    if len(spans) == 1:
        (start, end), = spans
        columns = [c.replace("{late}", f"{start:,}-{end:,}").replace("{whole}", f"0-{end:,}") for c in columns]
    else:  # pairs of different lengths: each row's length is its values' "steps"
        columns = [c.replace(", steps {late}", f", last {late_steps:,} steps").replace(", steps {whole}", "")
                   for c in columns]
    note = ("Walls different vs identical walls, the same agents and policy: means over runs (seeds), the "
            "identical-walls runs cut to the walls-different runs' length; p: Welch's two-sided t-test, runs as "
            "units; where not significant, after p: Δ within ±, the bound the data put on the difference (two one-sided "
            "Welch tests at 5 %: the far end of its 90 % interval), and the seeds a side that would find the "
            "difference seen 8 times in 10, its spread taken as the truth. Curiosity: the mean of the agents; VAE loss: per image (a two-agent loss "
            "halved), nats, of which the reconstruction term, the summed squared pixel error (the rest is the KL "
            "term).")
    return Table(columns, rows, values, note)


def _seeds_for_power(x, y, welch: dict) -> float:
    """Seeds a side for 80 % power at the observed difference of a test that did not find it
    (p >= ALPHA); NaN where it did, or where the test had nothing to go on."""
    if not (math.isfinite(welch["p"]) and welch["p"] >= ALPHA and welch["diff"] != 0):
        return math.nan
    hi, lo = (x, y) if welch["diff"] > 0 else (y, x)  # a two-sided test: either way is the effect
    return seeds_needed(Tested(np.asarray(hi, float), np.asarray(lo, float)))


def _nanmean(x) -> float:
    x = finite(x)
    return float(x.mean()) if len(x) else math.nan
