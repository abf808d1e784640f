"""Read a sweep directory and redraw the paper's figures from it.

    from mjx_curio import analysis
    sweep = analysis.load("runs/paper/multi_agent")  # one sweep: manifest, metrics, checkpoints
    sweep.runs, sweep.steps, sweep.metrics["curiosity"]   # [runs], [windows], [runs, windows, agents]
    ucb = sweep.select(policy="ucb")                 # run indices
    fig, ax = plt.subplots(); analysis.plot_curiosity(sweep, ax, "ucb")

A sweep (written by `python -m mjx_curio.sweep`, see sweep.py and metrics.py) holds metrics per
window of `metrics_every` (20) agent steps; `Sweep.metrics` holds the windows that are final
(`progress.json`), so a sweep still running can be read too. Runs that share a policy and its
setting (eps, temperature or c) but differ in seed form a `Group`; every figure pools a group's
seeds into a mean and a 95% confidence band of that mean (Student t, across seeds).

One function per figure of the paper (section 4), each drawing into a matplotlib Axes (or
Figure) it is given and returning it:

    plot_curiosity                 figs 8, 15, 17, 18, 20: curiosity per agent, raw + moving average
    plot_curiosity_groups          fig 11: curiosity per policy
    plot_temperatures              fig 19: Boltzmann temperatures compared
    plot_temperature_measures      what T changes (curiosity, action choice, contacts, roaming), over decades of T
    plot_single_vs_multi           fig 23: curiosity, single- vs multi-agent sweep
    plot_vae_single_vs_multi       fig 24: VAE loss, single- vs multi-agent sweep
    plot_cumulative_interactions   figs 21 (objects), 22 (agent-agent), normalised to the maximum
    plot_interaction_frequency     figs 9, 14: contacts per object over time, 100-step bins
    plot_action_histogram          figs 10, 12: actions chosen per agent
    plot_reconstructions           figs 7, 13: real views and VAE reconstructions, early vs late
    plot_boltzmann_greediness      how greedy softmax(q / T) is on the runs' states, over T (fig 19's why)
    plot_claim_effects             every test of the claims on one axis: effect / spread, 95% interval
    plot_paper_readings            a curiosity figure's curve beside the numbers the paper reads off it
    plot_paper_readings_panels     that for figs 8, 17, 18 and 20, a panel each, from the sweeps
    plot_view_fractions            what each agent looks at over time (objects, other agent)
    plot_observational             curiosity in windows where an agent only watches the other act
    plot_losses                    the world model's training losses
    plot_turn_reversals            trembling (section 5): turning back over time, against chance
    plot_self_model_tracking       claim 8: the self-model's predictions against the curiosity obtained, per step
    plot_curiosity_parts           claim 1's curve taken apart: the error against the posterior mean and its spread
    plot_error_without_spread      that error from a z=sample sweep beside a z=mean sweep's curiosity
    headline_table                 mean +- sd across seeds per group of the key numbers
    temperature_table              per Boltzmann temperature: curiosity, action entropy, contacts;
                                   each tested across T, blocked by seed
    policy_measures_table          the same measures per policy of any sweep
    walls_table                    different walls against identical ones, policy by policy
    power_table                    per test of each claim: the seeds it needs, the effect it detects

and the numbers behind them (`moving_average`, `mean_ci`, `cumulative_interactions`,
`interaction_frequency`, `action_totals`, `observation_classes`, `reconstructions`,
`reconstruction_quality`, `action_values`), which the tests check. Loading needs only NumPy (and
orbax for checkpoints); plotting needs matplotlib.

The package, by job; each module imports only those above it (sweeps none; stats, recon and
action_values sweeps; curiosity_noise and authors_memory sweeps and action_values; tables sweeps and stats;
significance none; self_model significance, stats and sweeps; claims self_model, significance,
sweeps, stats and tables; curiosity_parts claims, significance, stats, sweeps and tables;
temperatures claims, significance, stats and tables; power claims, significance and tables; walls
claims, power, significance, stats, sweeps and tables; paper_numbers claims, stats, sweeps and
tables; figures sweeps, stats, recon,
action_values, curiosity_parts, self_model, temperatures and paper_numbers):

    sweeps    loading: `load`, `find_sweeps`, `load_sweeps`, `merge_sweeps` (one experiment's seeds
              from several sweeps), `join_seed_parts` (every such experiment of a list merged),
              `pick_single_multi`, `side_experiment` (a `<preset>.<label>` sweep, kept apart from
              the preset's own), `experiment_name` and `seeds_name` (a seed part's name less its
              seeds, and an experiment's with the seeds it holds); `Sweep`, `Run`, `Group`,
              `SweepError`; the configs a sweep ran with (`learner_config`, `run_config`,
              `run_specs`) rebuilt from its manifest
    stats     statistics: `t_quantile_975`, `mean_ci`, `mean_sd`, `moving_average`, `bin_windows`
              and the numbers the figures draw (`per_agent_vae_loss`, `object_contacts`,
              `agent_contacts`, `cells_visited`, `cumulative_interactions`, `interaction_frequency`,
              `action_totals`, `observation_classes`, `turn_reversals`, `reversal_rates`)
    recon     reconstructions: `reconstructions` (a run's VAE restored from its checkpoints,
              JAX) and the `Reconstructions` it returns; `reconstruction_quality` (every run's VAE
              at every checkpoint on the other runs' replay frames: error and `edge_error`)
    action_values  what a run's self-models predict for every action on the states of its replay
              buffer, and the Boltzmann policy's probabilities there: `action_values` (JAX) and
              the `ActionValues` it returns
    curiosity_noise  how much of each step's curiosity is the sampling noise of the latent, which
              no self-model can foresee, and so the ceiling of a per-step test of it:
              `curiosity_noise` (JAX) and the `CuriosityNoise` it returns; `posterior_spread`,
              the part of the curiosity the noise alone adds, at every kept checkpoint, and
              `posterior_dims`, that variance dimension by dimension
    authors_memory  the curiosity the authors' code logs, rebuilt on a run's replay buffer: their
              memory (an LSTM stepped once from a zero state, a linear head per agent) trained
              with their pairing of a two-agent batch (`authors_pairing`: views beside other
              transitions' actions) or with every view beside its own (`matched_pairing`):
              `logged_curiosity` (JAX)
    tables    the headline table: `headline_table` and its `Table` (Markdown, CSV)
    significance  the tests, in NumPy alone: `welch_t`, `one_way_anova`, `block_anova`,
              `equivalence_bound` and `tost_bound` (two one-sided tests), `holm`, `pearson_r`, `fisher_z`,
              and the t and F tails behind them (`t_pvalue`, `f_pvalue`, `t_critical`, `betainc`)
    self_model  does the self-model track the curiosity obtained step by step (claim 8): the
              window moments sweeps record, pooled within windows (`step_tracking`,
              `tracking_over_time`, `records_steps`, `STEP_METRICS`)
    claims    the paper's claims tested across seeds: `claims_table` (one row per claim: statistic,
              95% CI or p-value, verdict), a `claim_*` function per claim, and `assign_presets`;
              a package, the claims by subject (`curiosity`, `behaviour`, `surprise`) on what
              they share (`common`)
    temperatures  what a Boltzmann sweep's temperatures change, run by run: `temperature_table`
              and the `temperature_measures` behind it; `policy_measures_table`, the same per
              policy
    power     how many seeds each claim's tests need, the smallest effect they detect and the
              largest the runs do not rule out: `power_table`, and `seeds_needed`, `detectable`,
              `largest_allowed`, `p_value`, `standardised_effect`, `t_power`, `noncentral_t_sf` behind it
    curiosity_parts  claim 1's fall and rise split into the world model's error against the posterior
              mean and the posterior's spread, from sweeps that record the spread:
              `curiosity_parts_table`, `parts_fall_rise`, `curiosity_parts`, `records_spread`,
              `samples_latent` (z=sample; under z=mean the curiosity is all error); claim 3 (one
              agent against two) part by part: `agents_parts_table`; claims 10 and 11 (one
              policy against another): `policies_parts_table`; and claims 9 and 12 (watching
              something move, touching an object): `situation_parts_table`
    walls     what a different texture on every wall changes: `walls_table` (each walls-different
              preset against its identical-walls preset, per policy) and `walls_measures`
    paper_numbers  the numbers the paper reads off its figures beside the same measured on the
              sweeps: `paper_numbers_table` over `READINGS`, on every run's curve in 1,000-step
              bins (`run_curves`, also what a full-length sweep's JSON keeps)
    figures   every `plot_*` function, the colours and labels they share, and saving
              (`figures_dir`, `save_figure`, `save_text`, `empty_axes`, `slug`)

This module re-exports all of them, so `from mjx_curio import analysis as an; an.load(...)` reads
as before.
"""

from __future__ import annotations

from mjx_curio.analysis.action_values import ActionValues, action_values
from mjx_curio.analysis.curiosity_noise import CuriosityNoise, curiosity_noise, posterior_dims, posterior_spread
from mjx_curio.analysis.authors_memory import authors_pairing, logged_curiosity, matched_pairing
from mjx_curio.analysis.claims import (
    CLAIMS,
    ClaimResult,
    Tested,
    VERDICTS,
    action_shares,
    agent_curiosity_coupling,
    assign_presets,
    balanced_rotation_share,
    beyond_view,
    agent_contact_order,
    claim_agents_move_together,
    claim_boltzmann_agents_meet,
    claim_boltzmann_least_curious,
    claim_boltzmann_trembles,
    claim_contact_ranking,
    claim_contacts_begin_late,
    claim_contacts_raise_curiosity,
    claim_curiosity_dip_and_rise,
    claim_observational_curiosity,
    claim_prefers_moving_objects,
    claim_results,
    claim_rotations_less,
    claim_self_model_predicts,
    claim_stop_least,
    claim_temperatures_alike,
    claim_two_agent_vae_unsettled,
    claim_two_agents_higher,
    claim_ucb_more_curious,
    claims_table,
    contact_excess,
    contact_onset,
    curiosity_fall_rise,
    fall_rise,
    late_curiosity,
    move_rotation_margin,
    moving_object_shares,
    reversal_rate,
    reversals_against_shuffled,
    rotation_share,
    run_curiosity,
    running_action_baseline,
    seed_coupling,
    self_model_tracking,
    vae_volatility,
    watching_excess,
)
from mjx_curio.analysis.curiosity_parts import (
    MEAN_LATENT_PART,
    PARTS,
    POLICY_PAIRS,
    agents_parts_table,
    curiosity_parts,
    curiosity_parts_table,
    parts_fall_rise,
    policies_parts_table,
    records_spread,
    samples_latent,
    situation_parts_table,
)
from mjx_curio.analysis.self_model import STEP_METRICS, records_steps, step_tracking, tracking_over_time
from mjx_curio.analysis.significance import (
    betainc,
    block_anova,
    equivalence_bound,
    f_pvalue,
    fisher_z,
    holm,
    one_way_anova,
    pearson_r,
    t_critical,
    t_pvalue,
    tost_bound,
    welch_t,
)
from mjx_curio.analysis.figures import (
    AGENT_COLORS,
    CURIOSITY_LABEL,
    EFFECT_COLORS,
    FIGURES_DIRNAME,
    POLICY_COLORS,
    STEPS_LABEL,
    TARGET_COLORS,
    empty_axes,
    figures_dir,
    plot_action_histogram,
    plot_boltzmann_greediness,
    plot_claim_effects,
    plot_paper_readings,
    plot_paper_readings_panels,
    plot_cumulative_interactions,
    plot_curiosity,
    plot_curiosity_groups,
    plot_curiosity_parts,
    plot_error_without_spread,
    plot_interaction_frequency,
    plot_losses,
    plot_observational,
    plot_reconstructions,
    plot_self_model_tracking,
    plot_single_vs_multi,
    plot_temperature_measures,
    plot_temperatures,
    plot_turn_reversals,
    plot_vae_single_vs_multi,
    plot_view_fractions,
    save_figure,
    save_text,
    slug,
)
from mjx_curio.analysis.recon import (
    ReconstructionQuality,
    Reconstructions,
    edge_error,
    heldout_slots,
    reconstruction_quality,
    reconstructions,
)
from mjx_curio.analysis.stats import (
    OBS_CLASSES,
    action_totals,
    agent_contacts,
    bin_windows,
    cells_visited,
    cumulative_interactions,
    interaction_frequency,
    mean_ci,
    mean_sd,
    moving_average,
    nan_ratio,
    object_contacts,
    observation_classes,
    per_agent_vae_loss,
    reversal_rates,
    t_quantile_975,
    turn_reversals,
)
from mjx_curio.analysis.sweeps import (
    FORMAT,
    POLICY_LABELS,
    SETTINGS,
    SWEEP_OUTPUTS,
    Group,
    Run,
    Sweep,
    SweepError,
    _quiet_orbax,  # video.py reads checkpoints with it
    drop_diverged,
    experiment_name,
    find_sweeps,
    join_seed_parts,
    learner_config,
    load,
    load_sweeps,
    merge_sweeps,
    pick_single_multi,
    run_config,
    run_specs,
    seeds_name,
    side_experiment,
)
from mjx_curio.analysis.tables import Table, headline_table
from mjx_curio.analysis.power import (
    detectable,
    largest_allowed,
    standardised_effect,
    noncentral_t_sf,
    p_value,
    power_table,
    seeds_needed,
    t_power,
)
from mjx_curio.analysis.temperatures import policy_measures_table, temperature_measures, temperature_table
from mjx_curio.analysis.walls import WALLS_PAIRS, walls_measures, walls_table
from mjx_curio.analysis.paper_numbers import (
    READING_PANELS,
    READINGS,
    Reading,
    paper_numbers_table,
    readings_side_by_side,
    reading_value,
    run_curves,
)

__all__ = [
    # sweeps
    "FORMAT", "POLICY_LABELS", "SETTINGS", "SWEEP_OUTPUTS", "Group", "Run", "Sweep", "SweepError", "drop_diverged",
    "experiment_name", "find_sweeps", "join_seed_parts", "learner_config", "load", "load_sweeps", "merge_sweeps",
    "pick_single_multi", "run_config", "run_specs", "seeds_name", "side_experiment",
    # stats
    "OBS_CLASSES", "action_totals", "agent_contacts", "bin_windows", "cells_visited", "cumulative_interactions",
    "interaction_frequency", "mean_ci", "mean_sd", "moving_average", "nan_ratio", "object_contacts",
    "observation_classes", "per_agent_vae_loss", "reversal_rates", "t_quantile_975", "turn_reversals",
    # recon, action_values
    "ReconstructionQuality", "Reconstructions", "heldout_slots", "reconstruction_quality", "reconstructions",
    "edge_error", "ActionValues", "action_values",
    # curiosity_noise, authors_memory
    "CuriosityNoise", "curiosity_noise", "posterior_dims", "posterior_spread",
    "authors_pairing", "logged_curiosity", "matched_pairing",
    # curiosity_parts
    "MEAN_LATENT_PART", "PARTS", "POLICY_PAIRS", "agents_parts_table", "curiosity_parts", "curiosity_parts_table",
    "parts_fall_rise", "policies_parts_table",
    "records_spread", "samples_latent", "situation_parts_table",
    # tables
    "Table", "headline_table",
    # temperatures
    "policy_measures_table", "temperature_measures", "temperature_table",
    # walls
    "WALLS_PAIRS", "walls_measures", "walls_table",
    # paper_numbers
    "READING_PANELS", "READINGS", "Reading", "paper_numbers_table", "reading_value", "readings_side_by_side", "run_curves",
    # power
    "detectable", "largest_allowed", "noncentral_t_sf", "p_value", "power_table", "seeds_needed", "standardised_effect", "t_power",
    # self_model
    "STEP_METRICS", "records_steps", "step_tracking", "tracking_over_time",
    # significance
    "betainc", "block_anova", "equivalence_bound", "f_pvalue", "fisher_z", "holm", "one_way_anova", "pearson_r",
    "t_critical", "t_pvalue", "tost_bound", "welch_t",
    # claims
    "CLAIMS", "ClaimResult", "Tested", "VERDICTS", "action_shares", "agent_curiosity_coupling", "assign_presets",
    "balanced_rotation_share", "beyond_view", "claim_agents_move_together", "claim_boltzmann_trembles",
    "claim_contact_ranking", "claim_curiosity_dip_and_rise", "claim_observational_curiosity",
    "claim_boltzmann_least_curious", "claim_prefers_moving_objects", "claim_rotations_less", "claim_self_model_predicts",
    "claim_stop_least",
    "claim_temperatures_alike", "claim_ucb_more_curious", "claim_contacts_raise_curiosity",
    "claim_contacts_begin_late", "contact_excess", "contact_onset",
    "claim_two_agents_higher", "claim_results", "claims_table", "curiosity_fall_rise", "fall_rise",
    "late_curiosity", "move_rotation_margin", "moving_object_shares", "reversal_rate", "run_curiosity",
    "reversals_against_shuffled", "rotation_share", "running_action_baseline", "seed_coupling",
    "self_model_tracking", "watching_excess", "agent_contact_order", "claim_boltzmann_agents_meet",
    "claim_two_agent_vae_unsettled", "vae_volatility",
    # figures
    "AGENT_COLORS", "CURIOSITY_LABEL", "EFFECT_COLORS", "FIGURES_DIRNAME", "POLICY_COLORS", "STEPS_LABEL", "TARGET_COLORS",
    "empty_axes", "figures_dir", "plot_action_histogram", "plot_boltzmann_greediness", "plot_claim_effects",
    "plot_paper_readings", "plot_paper_readings_panels",
    "plot_cumulative_interactions",
    "plot_curiosity", "plot_curiosity_groups", "plot_curiosity_parts", "plot_error_without_spread",
    "plot_interaction_frequency", "plot_losses", "plot_observational",
    "plot_reconstructions", "plot_self_model_tracking", "plot_single_vs_multi", "plot_temperature_measures",
    "plot_temperatures", "plot_turn_reversals", "plot_vae_single_vs_multi", "plot_view_fractions", "save_figure",
    "save_text", "slug",
]
