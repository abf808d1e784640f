"""Claims: the paper's findings (sections 4 and 5) tested on the preset sweeps, as one table.

    from mjx_curio import analysis as an
    table = an.claims_table("runs/paper")      # or a list of Sweeps, or {preset name: Sweep}
    print(table.to_markdown())

The paper shows one run per experiment; the presets (presets.toml) run several seeds of each, so
each claim here becomes a statistic across seeds: a mean with its 95% confidence interval
(`stats.mean_ci`, Student t across runs) or a named test with its p-value. Every claim has its own
function below (`claim_*`), whose docstring says exactly what is measured and how the verdict is
decided; `claims_table` runs them all.

Verdicts, and the rules every claim shares:
  holds            the statistic shows the paper's effect at the 5% level in the paper's direction
                   (the 95% CI excludes the null on the paper's side, or p < 0.05 with the sign the
                   paper reports; a claim of *no* difference holds when p >= 0.05).
  does not hold    the sweeps are at the scale the claim needs, and the statistic does not show
                   the effect (no significant effect, or a significant one the other way; the
                   reason follows the colon). Not significant is not the same as refuted: with
                   8 seeds a small effect can go undetected (`power` says how small, from the
                   values each claim's tests compared, `ClaimResult.tests`).
  not testable ... a preset sweep the claim needs is not loaded ("not testable: ..."), the metrics
                   cannot show it, or the sweeps are smaller than the claim needs: "not testable at
                   this scale (needs ...)", naming the run length and seeds that would test it.
                   The statistic is still computed where the data allow, for inspection.

Scale: every comparison needs at least `MIN_SEEDS` runs in each compared group (a 95% t interval
over 2 runs spans +-12.7 sd, which decides nothing), and each claim names the run length its
phenomenon needs, from where the paper sees it (e.g. the curiosity minimum between 10,000 and
30,000 steps).

Sweeps are matched to presets (`assign_presets`) by the `preset` their manifest records, else by
their directory or dict name, else by their settings (agents, walls, policies, temperatures), so a
sweep run by hand with a preset's settings stands in for it. A sweep named `<preset>.<label>`
(e.g. `multi_agent.order`) is a side experiment of that preset: its own seeds and length, kept
apart from the preset's sweep, read by the claims that name it (claim 6b reads `multi_agent.*`
where the `multi_agent` sweep does not record the order of actions).

The claims live by subject: `curiosity` (its level and course: claims 1, 3, 4, 7, 10, 11; and the
VAE's loss beside it: 14),
`behaviour` (what the agents do: 2, 5, 6a, 6b, 6c, 13, 15) and `surprise` (what surprises an agent: 8,
9, 12), on what they share in `common` (`Tested`, `ClaimResult`, `assign_presets`, the verdict
rules); this module gathers them in the table's order (`CLAIMS`) and re-exports their names.

Tests with p-values use only NumPy and the standard library (`significance`). Imports `self_model`,
`significance`, `sweeps`, `stats` and `tables`.
"""

from __future__ import annotations

from typing import Callable, Mapping

from mjx_curio.analysis.sweeps import Sweep
from mjx_curio.analysis.tables import Table
from mjx_curio.analysis.claims.common import (
    ALPHA,
    ClaimResult,
    MIN_SEEDS,
    PAPER_SETTING,
    PRESET_SETTINGS,
    SMOOTH,
    Tested,
    VERDICTS,
    assign_presets,
    block_mean,
    paper_group,
    preset_and_sides,
    seed_table,
)
from mjx_curio.analysis.claims.curiosity import (
    MEAN_LATENT_SIDE,
    agent_curiosity_coupling,
    claim_agents_move_together,
    claim_boltzmann_least_curious,
    claim_curiosity_dip_and_rise,
    claim_temperatures_alike,
    claim_two_agent_vae_unsettled,
    claim_two_agents_higher,
    claim_ucb_more_curious,
    curiosity_fall_rise,
    fall_rise,
    late_curiosity,
    run_curiosity,
    seed_coupling,
    vae_volatility,
)
from mjx_curio.analysis.claims.behaviour import (
    AGENT_PHASE_STEPS,
    CONTACT_ONSET,
    MOVING_OBJECTS,
    action_shares,
    agent_contact_order,
    balanced_rotation_share,
    claim_boltzmann_agents_meet,
    claim_boltzmann_trembles,
    claim_contact_ranking,
    claim_contacts_begin_late,
    claim_prefers_moving_objects,
    claim_rotations_less,
    claim_stop_least,
    contact_onset,
    move_rotation_margin,
    moving_object_shares,
    reversal_rate,
    reversals_against_shuffled,
    rotation_share,
)
from mjx_curio.analysis.claims.surprise import (
    beyond_view,
    claim_contacts_raise_curiosity,
    claim_observational_curiosity,
    claim_self_model_predicts,
    contact_excess,
    running_action_baseline,
    self_model_tracking,
    watching_excess,
)

__all__ = [
    "AGENT_PHASE_STEPS", "ALPHA", "CLAIMS", "CONTACT_ONSET", "ClaimResult", "MEAN_LATENT_SIDE", "MIN_SEEDS",
    "MOVING_OBJECTS", "PAPER_SETTING", "PRESET_SETTINGS", "SMOOTH", "Tested", "VERDICTS", "action_shares",
    "agent_contact_order", "agent_curiosity_coupling", "assign_presets", "balanced_rotation_share", "beyond_view",
    "block_mean", "claim_agents_move_together", "claim_boltzmann_agents_meet", "claim_boltzmann_least_curious",
    "claim_boltzmann_trembles", "claim_contact_ranking", "claim_contacts_begin_late",
    "claim_contacts_raise_curiosity", "claim_curiosity_dip_and_rise", "claim_observational_curiosity",
    "claim_prefers_moving_objects", "claim_results", "claim_rotations_less", "claim_self_model_predicts",
    "claim_stop_least", "claim_temperatures_alike", "claim_two_agent_vae_unsettled", "claim_two_agents_higher",
    "claim_ucb_more_curious", "claims_table", "contact_excess", "contact_onset", "curiosity_fall_rise",
    "fall_rise", "late_curiosity", "move_rotation_margin", "moving_object_shares", "paper_group",
    "preset_and_sides", "reversal_rate", "reversals_against_shuffled", "rotation_share", "run_curiosity",
    "running_action_baseline", "seed_coupling", "seed_table", "self_model_tracking", "vae_volatility",
    "watching_excess",
]


CLAIMS: tuple[Callable[[Mapping[str, Sweep]], ClaimResult], ...] = (
    claim_curiosity_dip_and_rise, claim_contact_ranking, claim_two_agents_higher, claim_agents_move_together,
    claim_prefers_moving_objects, claim_stop_least, claim_boltzmann_trembles, claim_rotations_less,
    claim_temperatures_alike, claim_self_model_predicts, claim_observational_curiosity, claim_boltzmann_least_curious,
    claim_ucb_more_curious, claim_contacts_raise_curiosity, claim_contacts_begin_late, claim_two_agent_vae_unsettled,
    claim_boltzmann_agents_meet,
)


def claim_results(sweeps) -> list[ClaimResult]:
    """Every claim of `CLAIMS` tested on `sweeps` (see `assign_presets` for what they may be)."""
    presets = assign_presets(sweeps)
    return [f(presets) for f in CLAIMS]


def claims_table(sweeps) -> Table:
    """The claims table: one row per claim (the claim, the paper's evidence, our statistic, the
    verdict), as a `tables.Table` (`to_markdown`, `to_csv`); `values` holds each row's numbers."""
    presets = assign_presets(sweeps)
    results = [f(presets) for f in CLAIMS]
    cols = ["#", "claim", "paper's evidence", "our statistic", "verdict"]
    rows = [[r.key, r.claim, r.evidence, r.statistic, r.verdict] for r in results]
    values = [{"key": r.key, "claim": r.claim, "verdict": r.verdict, **r.values} for r in results]
    keys = list(dict.fromkeys(k for v in values for k in v))
    values = [{k: v.get(k) for k in keys} for v in values]
    used = ", ".join(f"{p} = {s.name}" + (f" ({' + '.join(part.name for part in s.parts)})" if s.parts else "")
                     for p, s in presets.items()) or "none"
    note = (f"Sweeps as presets: {used}. Means are across runs (seeds) with 95% Student-t intervals in brackets; "
            f"p-values two-sided. holds: the paper's effect at the 5% level in its direction (claim 7: no significant "
            f"difference); does not hold: at the needed scale, the effect is not significant (or reversed); not "
            f"testable: a preset is missing, the metrics cannot show it, or the sweeps are too small (>= {MIN_SEEDS} "
            "seeds per group and each claim's run length).")
    return Table(cols, rows, values, note)
