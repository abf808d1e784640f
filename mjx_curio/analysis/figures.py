"""Figures: one function per figure of the paper (section 4), each drawing into a matplotlib
Axes (or Figure) it is given and returning it (the list is in the package docstring), the
colours and labels they share, and saving figures and text under a sweep's `figures/`
(`figures_dir`, `save_figure`, `save_text`, `empty_axes`, `slug`). matplotlib is imported only
where a colour map is needed; imports `sweeps`, `stats`, `recon`, `action_values`,
`temperatures` and, when drawn, `paper_numbers` (`plot_claim_effects` takes the `power` table it
draws).
"""

from __future__ import annotations

import pathlib
import re
import warnings
from typing import Any, Iterable, Sequence

import numpy as np

from mjx_curio.analysis.action_values import ActionValues, action_values
from mjx_curio.analysis.curiosity_parts import PARTS, curiosity_parts
from mjx_curio.analysis.recon import Reconstructions, reconstructions
from mjx_curio.analysis.self_model import tracking_over_time
from mjx_curio.analysis.stats import (
    OBS_CLASSES,
    action_totals,
    bin_windows,
    cumulative_interactions,
    interaction_frequency,
    mean_ci,
    moving_average,
    observation_classes,
    per_agent_vae_loss,
    reversal_rates,
)
from mjx_curio.analysis.sweeps import SWEEP_OUTPUTS, Group, Sweep, SweepError
from mjx_curio.analysis.temperatures import MEASURES, temperature_measures

FIGURES_DIRNAME = "figures"  # where the notebook saves figures inside a sweep directory (never written by a sweep)

# The paper's colours in figs 21 and 22: eps blue, UCB orange, Boltzmann green.
POLICY_COLORS = {"eps": "tab:blue", "ucb": "tab:orange", "boltzmann": "tab:green"}
AGENT_COLORS = ("#1e9e3c", "#8a3fb0")  # the green and the purple cube
TARGET_COLORS = {"pyramid": "#ff8000", "cylinder": "#d62020", "sphere": "#e0c000", "disc": "#2050d0",
                 "other_agent": "#707070"}
STEPS_LABEL = "agent steps"
CURIOSITY_LABEL = "curiosity reward (squared latent distance)"


# ----------------------------------------------------------------------------------- plotting


def _group_list(sweep: Sweep, groups) -> list[Group]:
    if groups is None:
        return sweep.groups()
    if isinstance(groups, (str, Group, int, np.integer)):
        return [sweep.group(groups)]
    return [sweep.group(g) for g in groups]


def _band(ax, x, lo, hi, color, label=None, floor: float | None = 0.0):
    """A 95% confidence band; clipped at `floor` (the quantities drawn with the default 0 cannot
    be negative)."""
    if np.any(np.isfinite(lo)):
        if floor is not None:
            lo = np.maximum(lo, floor)
        ax.fill_between(x, lo, hi, color=color, alpha=0.2, linewidth=0, label=label)


def _finish(ax, title, xlabel, ylabel, legend=True, loc="best"):
    ax.set_title(title, fontsize=10)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    if legend and ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7, loc=loc)
    return ax


def _group_colors(gs: Sequence[Group]) -> list:
    """One colour per group: the policy's (figs 21, 22: eps blue, UCB orange, Boltzmann green),
    in shades of it when a policy has several settings."""
    import matplotlib

    maps = {"eps": "Blues", "ucb": "Oranges", "boltzmann": "Greens"}
    out = []
    for i, g in enumerate(gs):
        same = [h for h in gs if h.policy == g.policy]
        if len(same) == 1 or g.policy not in maps:
            out.append(POLICY_COLORS.get(g.policy, f"C{i}"))
        else:
            j = same.index(g)
            out.append(matplotlib.colormaps[maps[g.policy]](0.45 + 0.5 * j / (len(same) - 1)))
    return out


def plot_curiosity(sweep: Sweep, ax, group: Any = None, window: int = 50, raw: bool = True,
                   metric: str = "curiosity_sample"):
    """Curiosity reward per agent over training for one group (figs 8, 15, 17, 18, 20).

    Thin line: the raw reward sampled every `metrics_every` (20) steps (the paper's blue line;
    with several seeds, their mean). Thick line: its trailing moving average over `window`
    points (the paper's red line), mean over seeds, with the 95% confidence band across seeds.
    metric="curiosity" uses each window's mean reward instead of its last step's."""
    g = sweep.group(group)
    x = sweep.steps
    for a in range(sweep.n_agents):
        v = sweep.metrics[metric][g.indices, :, a]
        color = AGENT_COLORS[a % len(AGENT_COLORS)] if sweep.n_agents > 1 else "tab:red"
        name = sweep.agent_label(a)
        if raw:
            raw_color = color if sweep.n_agents > 1 else "tab:blue"
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                ax.plot(x, np.nanmean(v, axis=0), color=raw_color, alpha=0.3, linewidth=0.7,
                        label=f"{name}: raw, every {sweep.metrics_every} steps")
        mean, lo, hi, _ = mean_ci(moving_average(v, window, axis=1))
        ax.plot(x, mean, color=color, linewidth=2, label=f"{name}: moving average ({window} points)")
        _band(ax, x, lo, hi, color, label="95% CI across seeds" if a == 0 else None)
    agents = "per agent" if sweep.n_agents > 1 else "single agent"
    return _finish(ax, f"Curiosity reward, {agents}: {g.label}, {g.seeds_text}", STEPS_LABEL, CURIOSITY_LABEL)


def plot_curiosity_groups(sweep: Sweep, ax, groups=None, window: int = 50, colors=None, title=None,
                          metric: str = "curiosity_sample"):
    """Curiosity reward (mean of the agents) per group: moving average over `window` points,
    mean over seeds, 95% confidence band across seeds (fig 11: one curve per policy)."""
    gs = _group_list(sweep, groups)
    x = sweep.steps
    colors = colors if colors is not None else _group_colors(gs)
    for i, g in enumerate(gs):
        v = sweep.metrics[metric][g.indices].mean(axis=2)  # agents averaged, per run
        mean, lo, hi, _ = mean_ci(moving_average(v, window, axis=1))
        color = colors[i]
        ax.plot(x, mean, color=color, linewidth=2, label=f"{g.label}, {g.seeds_text}")
        _band(ax, x, lo, hi, color)
    who = "mean of both agents" if sweep.n_agents > 1 else "single agent"
    title = title or f"Curiosity reward per policy ({who}; moving average of {window} points, 95% CI band across seeds)"
    return _finish(ax, title, STEPS_LABEL, CURIOSITY_LABEL)


def plot_temperatures(sweep: Sweep, ax, window: int = 50):
    """Boltzmann temperatures compared: curiosity per temperature (fig 19)."""
    gs = sorted(sweep.groups("boltzmann"), key=lambda g: g.value)
    if not gs:
        raise SweepError(f"{sweep.path} has no Boltzmann runs")
    import matplotlib

    cmap = matplotlib.colormaps["viridis"]
    colors = [cmap(i / max(1, len(gs) - 1) * 0.85) for i in range(len(gs))]
    who = "mean of both agents" if sweep.n_agents > 1 else "single agent"
    return plot_curiosity_groups(sweep, ax, gs, window, colors,
                                 title=f"Boltzmann policy: curiosity per temperature T ({who}; moving average of "
                                       f"{window} points, 95% CI band)")


def _policy_group(sweep: Sweep, policy: str) -> Group:
    gs = sweep.groups(policy)
    if not gs:
        raise SweepError(f"{sweep.path} has no {policy!r} runs; policies: {', '.join(sorted({r.policy for r in sweep.runs}))}")
    return gs[0]


def _check_pair(single: Sweep, multi: Sweep):
    if single.n_agents != 1:
        raise SweepError(f"{single.path} is not a single-agent sweep ({single.n_agents} agents)")
    if multi.n_agents < 2:
        raise SweepError(f"{multi.path} is not a multi-agent sweep ({multi.n_agents} agent)")


def plot_single_vs_multi(single: Sweep, multi: Sweep, ax, policy: str = "ucb", window: int = 50):
    """Curiosity of the single agent against each agent of the multi-agent sweep (fig 23):
    moving averages over `window` points, means over seeds with 95% bands."""
    _check_pair(single, multi)
    gs, gm = _policy_group(single, policy), _policy_group(multi, policy)
    v = single.metrics["curiosity_sample"][gs.indices, :, 0]
    mean, lo, hi, _ = mean_ci(moving_average(v, window, axis=1))
    ax.plot(single.steps, mean, color="black", linewidth=2, label=f"single agent ({gs.seeds_text}, {single.image} px)")
    _band(ax, single.steps, lo, hi, "black")
    for a in range(multi.n_agents):
        v = multi.metrics["curiosity_sample"][gm.indices, :, a]
        mean, lo, hi, _ = mean_ci(moving_average(v, window, axis=1))
        c = AGENT_COLORS[a % len(AGENT_COLORS)]
        ax.plot(multi.steps, mean, color=c, linewidth=2,
                label=f"multi-agent: {multi.agent_label(a)} ({gm.seeds_text}, {multi.image} px)")
        _band(ax, multi.steps, lo, hi, c)
    return _finish(ax, f"Curiosity reward, single- vs multi-agent: {gm.label} (moving average of {window} points, "
                       "95% CI band)", STEPS_LABEL, CURIOSITY_LABEL)


def plot_vae_single_vs_multi(single: Sweep, multi: Sweep, ax, policy: str = "ucb", window: int = 50, raw: bool = True):
    """The VAE's loss in the single- and the multi-agent sweep (fig 24), per image (the
    multi-agent loss of eq. 5 sums both agents' views; it is halved here so the two compare)."""
    _check_pair(single, multi)
    for sw, color, who in ((single, "black", "single agent"), (multi, "tab:purple", "multi-agent")):
        g = _policy_group(sw, policy)
        v = per_agent_vae_loss(sw)[g.indices]
        if raw:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                ax.plot(sw.steps, np.nanmean(v, axis=0), color=color, alpha=0.3, linewidth=0.7)
        mean, lo, hi, _ = mean_ci(moving_average(v, window, axis=1))
        ax.plot(sw.steps, mean, color=color, linewidth=2,
                label=f"{who}: {g.label}, {g.seeds_text}, {sw.image} px")
        _band(ax, sw.steps, lo, hi, color)
    return _finish(ax, f"VAE loss, single- vs multi-agent (thin: every {multi.metrics_every} steps; thick: moving "
                       f"average of {window} points, 95% CI band)", STEPS_LABEL,
                   "VAE loss per image (nats: squared pixel error sum + KL)")


def plot_cumulative_interactions(sweep: Sweep, ax, kind: str = "object", groups=None):
    """Cumulative interactions per policy, as % of the global maximum (fig 21: objects, both
    agents summed; fig 22: agent-agent contacts). Bands: 95% CI across seeds."""
    gs = _group_list(sweep, groups)
    data = cumulative_interactions(sweep, kind, gs)
    top = data.pop("_max")
    colors = _group_colors(gs)
    for i, (label, d) in enumerate(data.items()):
        g = d["group"]
        color = colors[i]
        ax.plot(d["steps"], 100 * d["mean"], color=color, linewidth=2, label=f"{label}, {g.seeds_text}")
        _band(ax, d["steps"], 100 * d["low"], 100 * d["high"], color)
    what = "contact steps, both agents summed" if kind == "object" else "steps with the agents touching"
    title = ("Cumulative agent-object interactions per policy" if kind == "object"
             else "Cumulative agent-agent interactions per policy")
    note = f"100% = {top:,.0f} {what}" if top > 0 else f"no {what} recorded"
    if kind == "agent" and sweep.n_agents == 1:
        note = "single-agent sweep: no other agent to touch"
    ax.set_ylim(-2, 110)  # bands above 110% (few seeds) are cut
    return _finish(ax, f"{title}\n({note})", STEPS_LABEL,
                   "cumulative interactions (% of the global maximum;\nmean over seeds, 95% CI band)", loc="upper left")


def plot_interaction_frequency(sweep: Sweep, ax, group: Any = None, every: int = 100, agent: int | None = None):
    """How often the agent(s) touch each object over time, averaged over bins of `every` steps
    (figs 9, 14), mean over seeds with a 95% band."""
    g = sweep.group(group)
    steps, f = interaction_frequency(sweep, g, every, agent)
    for k, obj in enumerate(sweep.objects):
        mean, lo, hi, _ = mean_ci(f[:, :, k])
        c = TARGET_COLORS.get(obj, f"C{k}")
        ax.plot(steps, mean, color=c, linewidth=1.5, marker="." if len(steps) < 30 else None, label=obj)
        _band(ax, steps, lo, hi, c)
    who = sweep.agent_label(agent) if agent is not None else ("both agents" if sweep.n_agents > 1 else "agent")
    return _finish(ax, f"Agent-object interactions over time, {who}: {g.label}, {g.seeds_text}",
                   STEPS_LABEL, f"share of steps touching the object\n(averaged over {every} steps)")


def plot_action_histogram(sweep: Sweep, ax, group: Any = None):
    """How often each agent chose each action over the whole run (figs 10, 12); bars are means
    over seeds, error bars 95% CIs."""
    g = sweep.group(group)
    tot = action_totals(sweep, g).astype(float)  # [n, agents, actions]
    n_a = sweep.n_agents
    width = 0.8 / n_a
    x = np.arange(len(sweep.actions))
    for a in range(n_a):
        mean, lo, hi, _ = mean_ci(tot[:, a])
        err = np.where(np.isfinite(lo), np.vstack([mean - np.maximum(lo, 0), hi - mean]), 0.0)
        ax.bar(x + (a - (n_a - 1) / 2) * width, mean, width, yerr=err if g.n > 1 else None, capsize=2,
               color=AGENT_COLORS[a % len(AGENT_COLORS)] if n_a > 1 else "tab:blue", label=sweep.agent_label(a))
    ax.set_xticks(x)
    ax.set_xticklabels([s.replace("_", "\n") for s in sweep.actions], fontsize=8)
    return _finish(ax, f"Actions chosen over {sweep.steps_done:,} steps: {g.label}, {g.seeds_text}", "action",
                   "times chosen\n(agent steps, mean over seeds)", legend=n_a > 1)


def plot_view_fractions(sweep: Sweep, ax, group: Any = None, agent: int = 0, every: int = 100):
    """What an agent looks at over time: the share of its view's pixels showing each object and
    the other agent, stacked, averaged over bins of `every` steps and over seeds (the rest of the
    view is floor, walls and sky)."""
    g = sweep.group(group)
    v = sweep.metrics["view_fraction"][g.indices, :, agent]  # [n, W, targets]
    steps, b = bin_windows(sweep, v, every, reduce="mean")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        m = np.nanmean(b, axis=0)  # [bins, targets]
    targets = list(sweep.view_targets)
    if sweep.n_agents == 1:
        targets, m = targets[:-1], m[:, :-1]
    labels = [t.replace("_", " ") for t in targets]
    ax.stackplot(steps, 100 * np.nan_to_num(m.T), labels=labels,
                 colors=[TARGET_COLORS.get(t, f"C{i}") for i, t in enumerate(targets)], alpha=0.85)
    return _finish(ax, f"What the {sweep.agent_label(agent)} looks at: {g.label}, {g.seeds_text}",
                   STEPS_LABEL, f"share of its view (% of pixels, mean over {every} steps;\nthe rest: floor, walls, sky)",
                   loc="upper left")


def plot_observational(sweep: Sweep, ax, window: int = 50):
    """Curiosity when an agent only watches the other agent act, against when it acts itself
    or nothing happens (per 20-step window, relative to its moving average; bars: mean over
    runs of every group, error bars 95% CI across runs)."""
    d = observation_classes(sweep, window)
    mean, lo, hi, n = mean_ci(d["per_run"])
    x = np.arange(len(OBS_CLASSES))
    err = np.where(np.isfinite(lo), np.vstack([mean - lo, hi - mean]), 0.0)  # excess: may be negative
    colors = ["tab:red", "tab:purple", "tab:gray", "lightgray"]
    ax.bar(x, np.nan_to_num(mean), yerr=err, capsize=3, color=colors)
    ax.axhline(0, color="black", linewidth=0.8)
    ax.set_xticks(x)
    ax.set_xticklabels([f"{c}\n({k:,} windows)" for c, k in zip(_wrap_all(OBS_CLASSES, 22), d["count"])], fontsize=7)
    return _finish(ax, f"Curiosity by what the agent did or saw in each {sweep.metrics_every}-step window\n"
                       f"(all {sweep.n_runs} runs, both agents; relative to the agent's moving average of {window} windows)",
                   "in the window, the agent ...", "curiosity above its moving average\n(squared latent distance)",
                   legend=False)


def plot_losses(sweep: Sweep, axes, groups=None, window: int = 50):
    """The world model's training losses per group (moving average, 95% band): the VAE loss per
    image, the MDN-RNN negative log-likelihood, the self-models' loss per agent. `axes`: 3 Axes."""
    gs = _group_list(sweep, groups)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        self_loss = np.nanmean(sweep.metrics["self_loss_agents"], axis=2)
    series = (  # (y label, what, values, lowest possible value for the bands)
        ("VAE loss per image (nats)", "VAE (eq. 5, per image)", per_agent_vae_loss(sweep), 0.0),
        ("MDN-RNN NLL per transition (nats)", "MDN-RNN (eq. 6)", sweep.metrics["nll"], None),
        ("self-model loss per agent\n(squared curiosity error)", "self-models (eq. 4)", self_loss, 0.0),
    )
    colors = _group_colors(gs)
    for ax, (ylabel, what, v, floor) in zip(axes, series):
        for i, g in enumerate(gs):
            mean, lo, hi, _ = mean_ci(moving_average(v[g.indices], window, axis=1))
            color = colors[i]
            ax.plot(sweep.steps, mean, color=color, linewidth=1.5, label=f"{g.label}, {g.seeds_text}")
            _band(ax, sweep.steps, lo, hi, color, floor=floor)
        _finish(ax, f"{what} loss (moving average of {window} windows)", STEPS_LABEL, ylabel)
    return axes


def plot_turn_reversals(sweep: Sweep, axes, groups=None, every: int = 1000):
    """Trembling (section 5) over time, per group (mean over seeds, 95% band), in bins of `every`
    steps: how often an agent turns the other way than at the step before, per pair of
    consecutive steps (left; dotted: a uniformly random choice of the actions), and that over what
    a random order of each window's own actions would give (right; 1: turns in no particular
    order, below 1: turns in runs of one direction). `axes`: 2 Axes. Needs a sweep that records
    `rotation_reversals`."""
    gs = _group_list(sweep, groups)
    colors = _group_colors(gs)
    for i, g in enumerate(gs):
        steps, rate, ratio = reversal_rates(sweep, g, every)
        for ax, v in zip(axes, (rate, ratio)):
            mean, lo, hi, _ = mean_ci(v)
            ax.plot(steps, mean, color=colors[i], linewidth=1.5, marker="." if len(steps) < 30 else None,
                    label=f"{g.label}, {g.seeds_text}")
            _band(ax, steps, lo, hi, colors[i])
    n = len(sweep.actions)
    axes[0].axhline(2 / n**2, color="black", linestyle=":", linewidth=1, label=f"uniformly random (2/{n**2})")
    axes[1].axhline(1, color="black", linestyle=":", linewidth=1, label="turns in a random order")
    _finish(axes[0], f"Turning back (mean over {every} steps)", STEPS_LABEL,
            "reversals per pair of consecutive steps\n(both agents)")
    _finish(axes[1], "Turning back beyond how often the agent turns", STEPS_LABEL,
            "reversals / reversals in a random order\nof each window's actions")
    return axes


def plot_self_model_tracking(sweep: Sweep, ax, groups=None, every: int = 1000):
    """Claim 8 over time, per group (mean over seeds, 95% band), in bins of `every` steps: the
    correlation of each step's predicted curiosity (of the action taken) with the curiosity it
    obtained, within 20-step windows (solid), and the same for a predictor that knows only each
    action's running mean curiosity (dashed). Needs a sweep that records the window moments
    (`self_model.records_steps`)."""
    gs = _group_list(sweep, groups)
    colors = _group_colors(gs)
    for i, g in enumerate(gs):
        steps, r_self, r_base = tracking_over_time(sweep, g, every)
        marker = "." if len(steps) < 30 else None
        for r, style, who in ((r_self, "-", "self-model"), (r_base, "--", "action running mean")):
            mean, lo, hi, _ = mean_ci(r)
            ax.plot(steps, mean, color=colors[i], linestyle=style, linewidth=1.5, marker=marker,
                    label=f"{g.label}, {who}, {g.seeds_text}")
            _band(ax, steps, lo, hi, colors[i])
    ax.axhline(0, color="black", linestyle=":", linewidth=1)
    _finish(ax, f"Does the self-model know what will surprise it? (per step, bins of {every} steps)", STEPS_LABEL,
            "corr(predicted, obtained curiosity)\nwithin 20-step windows")
    return ax


def plot_curiosity_parts(sweep: Sweep, ax, group: Any = None, window: int = 50):
    """Claim 1's curve taken apart (`curiosity_parts`), one group, the agents' mean: the curiosity
    obtained, the posterior spread (the part no prediction removes) and the error against the
    posterior mean (the rest), each a trailing moving average over `window` points, mean over
    seeds with 95% bands. Needs a sweep that records the spread (`records_spread`)."""
    g = sweep.group(group)
    x = sweep.steps
    styles = {"curiosity": ("black", "-"), "spread": ("tab:purple", "--"), "error": ("tab:red", "-")}
    for part, v in curiosity_parts(sweep, g).items():
        color, style = styles[part]
        mean, lo, hi, _ = mean_ci(moving_average(v, window, axis=1))
        ax.plot(x, mean, color=color, linestyle=style, linewidth=2 if part != "spread" else 1.5,
                label=f"{PARTS[part]}, {g.seeds_text}")
        _band(ax, x, lo, hi, color)
    who = "mean of both agents" if sweep.n_agents > 1 else "single agent"
    return _finish(ax, f"Curiosity = error + posterior spread, {who}: {g.label}", STEPS_LABEL, CURIOSITY_LABEL)


def plot_error_without_spread(sampled: Sweep, mean_latent: Sweep, ax, group: Any = None, window: int = 50):
    """The world model's error against the posterior mean from two sweeps of one setting: one
    that samples its latents and records the spread (its curiosity minus the spread, red) and one
    whose latent is the posterior mean (z=mean: its curiosity, all error, blue), each a trailing
    moving average over `window` points, mean over seeds with 95% bands, the agents' mean. What
    claim 1's curve would be without the posterior's spread, learnt either way."""
    for s, part, color, what in ((sampled, "error", "tab:red", "z=sample: curiosity minus spread"),
                                 (mean_latent, "curiosity", "tab:blue", "z=mean: curiosity")):
        g = s.group(group)
        mean, lo, hi, _ = mean_ci(moving_average(curiosity_parts(s, g)[part], window, axis=1))
        ax.plot(s.steps, mean, color=color, linewidth=2, label=f"{what}, {g.seeds_text}")
        _band(ax, s.steps, lo, hi, color)
    g = sampled.group(group)
    who = "mean of both agents" if sampled.n_agents > 1 else "single agent"
    return _finish(ax, f"The world model's error against the posterior mean, {who}: {g.label}", STEPS_LABEL,
                   CURIOSITY_LABEL)


def plot_reconstructions(sweep: Sweep, fig, run: int | str = 0, steps: Sequence[int] | None = None, n_frames: int = 8,
                         rec: Reconstructions | None = None):
    """Real views (top row) and run `run`'s VAE reconstructions of them after an early and a
    late checkpoint (one row per checkpoint), figs 7 and 13."""
    rec = rec or reconstructions(sweep, run, steps, n_frames)
    rows = 1 + len(rec.steps)
    n = len(rec.frames)
    axes = fig.subplots(rows, n, squeeze=False)
    for j in range(n):
        s, i, a = rec.sources[j]
        who = "" if sweep.n_agents == 1 else f", {sweep.agent_names[a]}"
        axes[0, j].imshow(rec.frames[j], interpolation="nearest")
        axes[0, j].set_title(f"run {i}{who}\nstep {s:,}", fontsize=7)
        for k, st in enumerate(rec.steps):
            axes[k + 1, j].imshow(rec.decoded[st][j], interpolation="nearest")
    for row in axes:
        for ax in row:
            ax.set_xticks([])
            ax.set_yticks([])
    axes[0, 0].set_ylabel("real view", fontsize=8)
    for k, st in enumerate(rec.steps):
        axes[k + 1, 0].set_ylabel(f"VAE after\n{st:,} steps", fontsize=8)
    fig.suptitle(f"VAE reconstructions, {rec.run.name}: the agents' real {sweep.image}x{sweep.image} views (top; each "
                 f"from the checkpoint named) encoded and decoded\nby this run's VAE restored from checkpoints at "
                 f"{' and '.join(f'{s:,}' for s in rec.steps)} agent steps", fontsize=9)
    return fig


def plot_boltzmann_greediness(sweep: Sweep, ax, runs: Sequence[int] | None = None, temperatures=None,
                              values: Sequence[ActionValues] | None = None):
    """How greedy the Boltzmann policy softmax(q / T) is on each run's own states over a range of
    T: the mean probability of the most favoured action, q from each run's self-models at the
    newest checkpoint on the states of its replay buffer (`action_values`). Each run's own
    temperature is marked on its curve; dashed: a uniform choice. Default runs: the Boltzmann ones,
    or every run when there are none (the curve says what Boltzmann would do with their q)."""
    temperatures = np.geomspace(1e-3, 10.0, 81) if temperatures is None else np.asarray(temperatures, float)
    if values is None:
        if runs is None:
            runs = sweep.select(policy="boltzmann") if len(sweep.select(policy="boltzmann")) else range(sweep.n_runs)
        values = [action_values(sweep, int(r)) for r in runs]
    gs = [g for g in sweep.groups() if any(v.run.index in g.indices for v in values)]
    colors = dict(zip((g.label for g in gs), _group_colors(gs)))
    labelled = set()
    for v in values:
        g = next(g for g in gs if v.run.index in g.indices)
        label = None if g.label in labelled else g.label
        labelled.add(g.label)
        ax.plot(temperatures, v.favoured_probability(temperatures), color=colors[g.label], lw=1.2, label=label)
        if v.run.policy == "boltzmann":
            ax.plot([v.run.temperature], v.favoured_probability([v.run.temperature]), "o", ms=4,
                    color=colors[g.label])
    ax.axhline(1 / len(sweep.actions), color="0.4", ls="--", lw=0.8, label=f"uniform (1/{len(sweep.actions)})")
    own = [v.run.temperature for v in values if v.run.policy == "boltzmann"]
    if own:
        ax.axvspan(min(own), max(own), color="0.85", alpha=0.5, lw=0, label="the runs' temperatures")
    ax.set_xscale("log")
    ax.set_ylim(0, 1.02)
    steps = sorted({v.step for v in values})
    return _finish(ax, f"Boltzmann policy on the states the runs visited: how greedy softmax(q / T) is\n(self-models at "
                       f"{' and '.join(f'{s:,}' for s in steps)} steps, each run's replay buffer; dots: the run's own T)",
                   "temperature T (log scale)", "P(most favoured action)\n(mean over states and agents)")


def plot_temperature_measures(sweep: Sweep, axes, paper_range=(0.5, 2.5), late_fraction: float = 0.25):
    """What the Boltzmann temperature changes, against T (log scale): one panel per measure of
    `temperatures.MEASURES` (claim 7's late curiosity, the action entropy over ln(actions), the
    most chosen action's share, object contacts per 1,000 agent-steps, floor squares visited per
    agent), each run a dot and each
    T's mean over seeds with its 95% confidence interval; grey span: `paper_range`; dashed: what a
    uniform choice gives. Made for temperatures spanning decades, e.g. the paper's Boltzmann sweep
    and the low-temperature one read as one (`merge_sweeps(..., differ=("temperature", "preset"))`)."""
    gs = sorted(sweep.groups("boltzmann"), key=lambda g: g.value)
    if not gs:
        raise SweepError(f"{sweep.path} has no Boltzmann runs")
    axes = list(np.ravel(axes))
    if len(axes) != len(MEASURES):
        raise ValueError(f"plot_temperature_measures draws {len(MEASURES)} panels; got {len(axes)} axes")
    m = temperature_measures(sweep, late_fraction)
    t = np.array([g.value for g in gs])
    uniform = {"action_entropy": 1.0, "top_share": 1.0 / len(sweep.actions)}
    for ax, (key, heading, _) in zip(axes, MEASURES):
        for g in gs:
            ax.plot(np.full(g.n, g.value), m[key][g.indices], "o", ms=3, color="0.55", alpha=0.7)
        mean, lo, hi, _ = (np.array(v, float) for v in zip(*(mean_ci(m[key][g.indices]) for g in gs)))
        ax.errorbar(t, mean, yerr=[mean - lo, hi - mean], fmt="o-", color=POLICY_COLORS["boltzmann"], ms=5,
                    capsize=3, lw=1.2, label=f"mean over seeds, 95% CI ({gs[0].n} seeds)")
        if key in uniform:
            ax.axhline(uniform[key], color="0.4", ls="--", lw=0.8, label="uniform choice")
        ax.axvspan(*paper_range, color="0.85", alpha=0.5, lw=0, label="the paper's temperatures")
        ax.set_xscale("log")
        _finish(ax, heading, "temperature T (log scale)", heading, legend=ax is axes[0] or key in uniform)
    return axes


EFFECT_COLORS = {"paper": "tab:blue", "other way": "tab:red", "neither": "0.55"}


def plot_claim_effects(power, ax):
    """Every test the claims' verdicts rest on, on one axis: its effect in units of the spread
    across runs (`power.standardised_effect`, the paper's direction to the right) with its 95%
    interval, one row per test in the claims' order, labelled with the claim and the test. Blue:
    the interval lies on the paper's side of 0; red: on the other side; grey: it spans 0. Filled:
    significant after Holm's adjustment over all the tests; hollow: not. `power` is the
    `power_table` (its `values`); claim 7's claim of no difference has no such effect and is left
    out."""
    rows = [v for v in power.values if v.get("d") is not None and v.get("d_low") is not None]
    if not rows:
        raise ValueError("no test with an effect to draw")
    y = np.arange(len(rows))[::-1]
    for yi, v in zip(y, rows):
        side = "paper" if v["d_low"] > 0 else "other way" if v["d_high"] < 0 else "neither"
        color = EFFECT_COLORS[side]
        ax.plot([v["d_low"], v["d_high"]], [yi, yi], color=color, lw=1.6)
        held = v.get("p_holm") is not None and v["p_holm"] < 0.05
        ax.plot(v["d"], yi, "o", ms=5, color=color, mfc=color if held else "white")
    ax.axvline(0.0, color="0.2", lw=0.8)
    ax.set_yticks(y)
    ax.set_yticklabels([f"{v['key']}: {_short_test(v['test'])}" for v in rows], fontsize=6.5)
    ax.set_ylim(-0.7, len(rows) - 0.3)
    for side, color in EFFECT_COLORS.items():
        label = {"paper": "95% interval on the paper's side", "other way": "on the other side",
                 "neither": "spans 0"}[side]
        ax.plot([], [], color=color, lw=1.6, label=label)
    ax.plot([], [], "o", ms=5, color="0.3", label="significant after Holm")
    ax.plot([], [], "o", ms=5, color="0.3", mfc="white", label="not after Holm")
    _finish(ax, "The claims' tests: effect / spread across runs, 95% interval",
            "effect / sd across runs (the paper's direction > 0)", "", legend=False)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.07), ncol=3, frameon=False)
    ax.grid(True, axis="x", alpha=0.3)
    ax.grid(False, axis="y")
    return ax


def plot_paper_readings(ax, figure: str, sources, readings=None):
    """One of the paper's curiosity figures (`figure`, e.g. "fig. 8") beside what the paper reads
    off it. `sources`: (label, curves as `paper_numbers.run_curves` gives them, the runs of the
    figure's group) each, drawn as the mean over those runs of the binned curiosity with its 95% CI
    band; `readings` (default `paper_numbers.READINGS`): those of `figure` with a `box`, drawn as
    grey boxes where the paper puts its words ("about 0.55" around step 5,000)."""
    from mjx_curio.analysis.paper_numbers import READINGS

    boxes = [r for r in (READINGS if readings is None else readings) if r.figure == figure and r.box]
    for k, (label, cv, runs) in enumerate(sources):
        steps = np.asarray(cv["steps"], float)
        mean, lo, hi, _ = mean_ci(np.asarray(cv["runs"], float)[list(runs)])
        color = f"C{k}"
        ax.plot(steps, mean, color=color, lw=1.4, label=f"{label} ({len(runs)} runs)")
        _band(ax, steps, lo, hi, color)
    for i, r in enumerate(boxes):
        start, end, low, high = r.box
        ax.fill_between([start, end], low, high, color="0.45", alpha=0.35, lw=0,
                        label="the paper's reading" if i == 0 else None)
        ax.plot([start, end, end, start, start], [low, low, high, high, low], color="0.3", lw=0.7)
    return _finish(ax, f"{figure}: mean curiosity in 1,000-step bins, 95% CI; grey: the paper's words",
                   STEPS_LABEL, CURIOSITY_LABEL)


def plot_paper_readings_panels(fig, sweeps, long: dict | None = None) -> list:
    """`plot_paper_readings` for each of the paper's curiosity figures whose preset is among
    `sweeps` (`paper_numbers.READING_PANELS`: figs. 8, 17, 18 and 20; `sweeps` as
    `assign_presets` takes them), one panel under the other in `fig`, which is sized to hold them.
    `long`: {preset: (curves as `run_curves` gives them, {policy: run indices})}, longer runs of a
    preset drawn beside its sweep (the full-length runs of docs/results/full_length.json). Returns
    the panels' Axes; none where no preset of a panel is loaded (then `fig` is left empty)."""
    from mjx_curio.analysis.claims import assign_presets, paper_group
    from mjx_curio.analysis.paper_numbers import READING_PANELS, run_curves

    presets = assign_presets(sweeps)
    long = long or {}
    panels = [(name, preset, policy) for name, preset, policy in READING_PANELS if preset in presets]
    if not panels:
        return []
    fig.set_size_inches(8.0, 3.0 * len(panels))
    axes = fig.subplots(len(panels), 1, squeeze=False)[:, 0]
    for ax, (name, preset, policy) in zip(axes, panels):
        s = presets[preset]
        g = paper_group(s, policy)
        sources = [(f"{s.name}, {s.steps_done:,} steps", run_curves(s), g.indices)]
        if preset in long and policy in long[preset][1]:
            sources.append(("the full-length runs", long[preset][0], long[preset][1][policy]))
        plot_paper_readings(ax, name, sources)
        ax.set_title(f"{name}: {'one agent' if s.n_agents == 1 else 'two agents'}, {g.label}", fontsize=9)
        ax.set_ylabel("curiosity reward")  # stacked panels: the long label would run into the next
    return list(axes)


def _short_test(label: str) -> str:
    """A test's label without the seed range of a merged sweep's name ('multi_agent.seeds-0-7 ...')."""
    return re.sub(r"\.seeds-\d+-\d+", "", label)


# ---------------------------------------------------------------------------------- saving


def figures_dir(path: str | pathlib.Path, create: bool = True) -> pathlib.Path:
    """Where figures of the sweep (or directory of sweeps) at `path` go: `<path>/figures`, a
    name no sweep writes."""
    d = pathlib.Path(path).expanduser() / FIGURES_DIRNAME
    if create:
        d.mkdir(parents=True, exist_ok=True)
    return d


def empty_axes(fig) -> list[str]:
    """Titles of the visible axes of `fig` that show nothing: no line with a finite point, no
    bar, band, area or image."""
    empty = []
    for ax in fig.axes:
        if not ax.get_visible():
            continue
        lines = any(np.isfinite(np.asarray(ln.get_ydata(), float)).any() for ln in ax.lines)
        if not (lines or ax.collections or ax.patches or ax.images):
            empty.append(ax.get_title() or f"axes {fig.axes.index(ax)}")
    return empty


def save_figure(fig, directory: str | pathlib.Path, name: str, dpi: int = 110, check: bool = True) -> pathlib.Path:
    """Save `fig` as `<directory>/<name>.png` (name made file-safe). With `check`, raise
    SweepError if an axes shows nothing. Refuses to write inside a sweep's own outputs
    (metrics/, checkpoints/, manifest.json, progress.json)."""
    directory = pathlib.Path(directory)
    if check and empty_axes(fig):
        raise SweepError(f"figure {name!r} has empty axes: {'; '.join(empty_axes(fig))}")
    _check_not_sweep_output(directory)
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / f"{slug(name)}.png"
    fig.savefig(path, dpi=dpi, bbox_inches="tight")
    return path


def save_text(text: str, directory: str | pathlib.Path, name: str) -> pathlib.Path:
    directory = pathlib.Path(directory)
    _check_not_sweep_output(directory)
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / name
    path.write_text(text)
    return path


def _check_not_sweep_output(directory: pathlib.Path) -> None:
    d = directory.resolve()
    for parent in (d, *d.parents):
        if (parent / "manifest.json").is_file() and parent != d:
            rel = d.relative_to(parent).parts
            if rel and rel[0] in SWEEP_OUTPUTS:
                raise SweepError(f"refusing to write into {directory}: it is part of the sweep {parent}'s own output")
    if (d / "manifest.json").is_file():
        raise SweepError(f"refusing to write figures into the sweep directory {directory} itself; "
                         f"use {directory / FIGURES_DIRNAME}")


def slug(text: str) -> str:
    text = text.replace("ε", "eps").replace("±", "pm")
    return re.sub(r"[^A-Za-z0-9._-]+", "-", text).strip("-").lower() or "figure"


# ---------------------------------------------------------------------------------- helpers


def _wrap(text: str, width: int) -> str:
    words, lines, cur = text.split(), [], ""
    for w in words:
        if cur and len(cur) + 1 + len(w) > width:
            lines.append(cur)
            cur = w
        else:
            cur = f"{cur} {w}".strip()
    return "\n".join(lines + [cur])


def _wrap_all(texts: Iterable[str], width: int) -> list[str]:
    return [_wrap(t, width) for t in texts]
