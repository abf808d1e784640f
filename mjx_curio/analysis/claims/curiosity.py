"""The claims about curiosity's level and course: its fall and rise (claim 1), two agents against
one (3), the two agents' curves together (4), the Boltzmann temperatures alike (7), and the
policies' levels (10, 11); and beside claim 3, the two-agent VAE's loss against one agent's (14).
Imports `common`, `significance`, `stats` and `sweeps`.
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np

from mjx_curio.analysis.stats import mean_ci, moving_average, per_agent_vae_loss
from mjx_curio.analysis.significance import (
    block_anova,
    equivalence_bound,
    fisher_z,
    one_way_anova,
    pearson_r,
    tost_bound,
    welch_t,
)
from mjx_curio.analysis.sweeps import Group, Sweep
from mjx_curio.analysis.claims.common import (
    ALPHA,
    ClaimResult,
    SMOOTH,
    Tested,
    block_mean,
    paper_group,
    seed_table,
    _ci,
    _decide,
    _f,
    _missing,
    _nanmean,
    _num,
    _p,
    _scale_gap,
    _scale_gaps,
    _short,
    _source_groups,
)


def claim_curiosity_dip_and_rise(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 1: curiosity falls in the first few thousand steps, then rises again (figs. 8, 17, 18).

    Measured per run on the curiosity (window means, averaged over the agents), as means over
    fixed blocks of steps placed where the paper's figures put them: early = steps 0-2,000 (the
    initial high level), trough = steps 10,000-30,000 (the paper's minima: ~5,000-15,000 in fig. 8,
    20,000-25,000 in fig. 17, 10,000-30,000 in fig. 18), late = the last 10,000 steps.
    fall = early - trough, rise = late - trough. Fixed blocks, not each run's own minimum: a
    minimum picked out of noise lies below the curve's level, so `late - minimum` is positive even
    for a flat curve. Groups: single_agent eps (fig. 8), multi_agent eps (fig. 17) and ucb (fig. 18),
    those loaded. (Fig. 15, walls different, shows a fall and then a plateau, not a rise; left out.)
    Verdict: holds if in every group the 95% CIs of both fall and rise lie above 0. Scale: runs of
    >= 40,000 steps (the late block must start after the trough block), >= MIN_SEEDS seeds a group.
    """
    key, claim = "1", "Curiosity falls in the first few thousand steps, then rises again"
    evidence = "figs. 8 (single agent, ε-greedy), 17 (two agents, ε-greedy), 18 (two agents, UCB); one run each"
    sources = [("single_agent", "eps", "fig. 8"), ("multi_agent", "eps", "fig. 17"), ("multi_agent", "ucb", "fig. 18")]
    groups = _source_groups(presets, sources)
    if not groups:
        return ClaimResult(key, claim, evidence, "n/a", _missing(("single_agent", "multi_agent"), presets))
    parts, values, fails, tests = [], {}, [], {}
    for label, s, g in groups:
        d = curiosity_fall_rise(s, g)
        fall, rise = mean_ci(d["fall"]), mean_ci(d["rise"])
        tests.update({f"{label} fall": Tested(d["fall"]), f"{label} rise": Tested(d["rise"])})
        parts.append(f"{label}: fall {_ci(fall)}, rise {_ci(rise)}")
        values.update({f"{label} fall": _num(fall[0]), f"{label} fall low": _num(fall[1]),
                       f"{label} rise": _num(rise[0]), f"{label} rise low": _num(rise[1])})
        if not (fall[1] > 0 and rise[1] > 0):
            fails.append(f"{label}: {'fall' if not fall[1] > 0 else 'rise'} CI does not lie above 0")
    gap = _scale_gaps([(s, 40_000, {label: g.n}) for label, s, g in groups])
    gaps = [gap] if gap else []
    stat = ("mean over runs [95% CI] of fall = curiosity(steps 0-2k) - curiosity(10k-30k) and "
            "rise = curiosity(last 10k steps) - curiosity(10k-30k); " + "; ".join(parts))
    return ClaimResult(key, claim, evidence, stat, _decide(gaps, fails, "every fall and rise CI above 0"), values,
                       tests)


def curiosity_fall_rise(sweep: Sweep, group: Group) -> dict:
    """Per run of `group`: {"early", "trough", "late", "fall", "rise"} (arrays [runs]); the blocks
    of `claim_curiosity_dip_and_rise`, NaN where a block holds no window."""
    return fall_rise(sweep, _nanmean(sweep.metrics["curiosity"][group.indices].astype(float), axis=2))


def fall_rise(sweep: Sweep, c: np.ndarray) -> dict:
    """`curiosity_fall_rise` of any per-run series c [runs, windows] of `sweep`."""
    t = sweep.steps_done
    early = block_mean(sweep, c, 0, 2_000)
    trough = block_mean(sweep, c, 10_000, 30_000)
    late = block_mean(sweep, c, max(t - 10_000, 30_000), t)
    return {"early": early, "trough": trough, "late": late, "fall": early - trough, "rise": late - trough}


def claim_two_agents_higher(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 3: two agents have higher curiosity and a higher VAE loss than one (figs. 23, 24).

    Measured on the UCB runs (the paper's choice) of single_agent and multi_agent, per run, as
    means over the second half of the steps both sweeps have run (after the initial fall; the same
    steps on both sides when one sweep is longer): curiosity (averaged over the
    agents) and the VAE loss per image (`stats.per_agent_vae_loss`: the two-agent loss of eq. 5
    sums both views, so it is halved; the summed loss is ~2x a single agent's by construction).
    Welch t multi - single for each. Verdict: holds if both differences are positive with p < 0.05.
    Scale: runs of >= 10,000 steps (the second half then starts after the fall, ~5,000 steps in
    fig. 8), >= MIN_SEEDS seeds a side; the two sweeps must have the same image size.
    """
    key, claim = "3", "Two agents have higher curiosity and a higher VAE loss than one"
    evidence = "figs. 23, 24, section 4.2 (UCB; one single-agent and one two-agent run)"
    pair = _ucb_one_and_two(presets, key, claim, evidence)
    if isinstance(pair, ClaimResult):
        return pair
    single, multi, gs, gm, lo, hi = pair
    cur = {w: block_mean(s, _nanmean(s.metrics["curiosity"][g.indices].astype(float), axis=2), lo, hi)
           for w, s, g in (("single", single, gs), ("multi", multi, gm))}
    vae = {w: block_mean(s, per_agent_vae_loss(s)[g.indices].astype(float), lo, hi)
           for w, s, g in (("single", single, gs), ("multi", multi, gm))}
    values, parts, fails, tests = {}, [], [], {}
    for what, d in (("curiosity", cur), ("VAE loss per image", vae)):
        ms, mm = mean_ci(d["single"]), mean_ci(d["multi"])
        tests[f"{what}: two agents > one"] = Tested(d["multi"], d["single"])
        w = welch_t(d["multi"], d["single"])
        values.update({f"{what} single": _num(ms[0]), f"{what} multi": _num(mm[0]), f"{what} t": _num(w["t"]),
                       f"{what} p": _num(w["p"])})
        parts.append(f"{what}: one agent {_ci(ms)}, two agents {_ci(mm)}, Welch t={_f(w['t'])}, p={_p(w['p'])}")
        if not (w["p"] < ALPHA and w["diff"] > 0):
            fails.append(f"{what} not significantly higher with two agents")
    stat = (f"mean over steps {lo:,}-{hi:,} of each run (the second half of the steps both sweeps ran), "
            f"{single.name} vs {multi.name}: " + "; ".join(parts))
    return _ucb_one_and_two_verdict(pair, key, claim, evidence, stat, fails, "both Welch tests p < 0.05, multi > "
                                    "single", values, tests)


def _ucb_one_and_two(presets: Mapping[str, Sweep], key: str, claim: str, evidence: str):
    """The UCB groups of single_agent and multi_agent that claims 3 and 14 compare, and the steps
    they compare them over: (single, multi, single's group, multi's group, start, end), the second
    half of the steps both sweeps ran (curiosity and loss drift over training, so a longer sweep's
    later half would not be comparable with a shorter one's); or the ClaimResult saying what is
    missing."""
    single, multi = presets.get("single_agent"), presets.get("multi_agent")
    if single is None or multi is None:
        return ClaimResult(key, claim, evidence, "n/a", _missing(("single_agent", "multi_agent"), presets))
    gs, gm = paper_group(single, "ucb"), paper_group(multi, "ucb")
    if gs is None or gm is None:
        return ClaimResult(key, claim, evidence, "n/a", "not testable: " + " and ".join(
            f"{s.name} has no UCB runs" for s, g in ((single, gs), (multi, gm)) if g is None))
    common = min(single.steps_done, multi.steps_done)
    return single, multi, gs, gm, common // 2, common


def _ucb_one_and_two_verdict(pair, key, claim, evidence, stat, fails, rule, values, tests) -> ClaimResult:
    """Claims 3 and 14's verdict: their scale (runs of >= 10,000 steps, so that the second half
    starts after curiosity's initial fall, ~5,000 steps in fig. 8; MIN_SEEDS UCB runs a side) and
    the same image size on both sides."""
    single, multi, gs, gm, _, _ = pair
    gap = _scale_gaps([(single, 10_000, {f"{single.name} UCB": gs.n}), (multi, 10_000, {f"{multi.name} UCB": gm.n})])
    if single.image != multi.image:
        return ClaimResult(key, claim, evidence, stat,
                           f"not testable: {single.name} ({single.image} px) and {multi.name} ({multi.image} px) "
                           "differ in image size", values)
    return ClaimResult(key, claim, evidence, stat, _decide([gap] if gap else [], fails, rule), values, tests)


def claim_two_agent_vae_unsettled(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 14: the two-agent VAE's loss stays volatile and fails to converge where the one-agent
    VAE's decreases steadily (fig. 24, section 4.2.1; section 5: "the VAE reconstruction loss fails
    to fully converge in the multi-agent setting").

    Measured on the UCB runs (the paper's choice) of single_agent and multi_agent, per run, over the
    second half of the steps both sweeps ran (`vae_volatility`): the volatility = the sd of the
    VAE's loss per image (`stats.per_agent_vae_loss`) around its trailing moving average of 50
    windows (what fig. 24's smoothing leaves out), times sqrt(agents). The two-agent loss per image
    is a mean over twice the views of an update (both agents' frames of each sample), so the
    sampling noise of its views alone makes it sqrt(2) times steadier; scaled, views that vary
    independently give both sides the same volatility, and a larger two-agent value is fluctuation
    beyond what the batch size explains. (That scaling is the generous bound for the paper: views
    that vary together would not average out, and then the unscaled value is the fair one.) Welch t
    multi - single. Verdict: holds if the two-agent volatility is higher, p < 0.05. Reported beside
    it, not the verdict: the unscaled volatility, the loss's relative change from the first to the
    second half of the compared steps (a loss still converging falls), and the volatility of the
    loss as eq. 5 sums it over the views (presumably fig. 24's curve), twice the per-image one's
    with two agents by construction. Scale: as claim 3.
    """
    key, claim = "14", "The two-agent VAE's loss stays volatile where the one-agent VAE's settles"
    evidence = "fig. 24, sections 4.2.1 and 5 (UCB; one single-agent and one two-agent run)"
    pair = _ucb_one_and_two(presets, key, claim, evidence)
    if isinstance(pair, ClaimResult):
        return pair
    single, multi, gs, gm, lo, hi = pair
    d = {w: vae_volatility(s, g, lo, hi) for w, s, g in (("single", single, gs), ("multi", multi, gm))}
    values, parts, tests = {}, [], {}
    for what, name in (("scaled", "volatility x sqrt(agents)"), ("per_image", "volatility per image"),
                       ("late_change", "relative change, first to second half")):
        ms, mm = mean_ci(d["single"][what]), mean_ci(d["multi"][what])
        w = welch_t(d["multi"][what], d["single"][what])
        values.update({f"{what} single": _num(ms[0]), f"{what} multi": _num(mm[0]), f"{what} p": _num(w["p"])})
        parts.append(f"{name}: one agent {_ci(ms)}, two agents {_ci(mm)}, Welch t={_f(w['t'])}, p={_p(w['p'])}")
    summed = np.nanmean(d["multi"]["per_image"]) * multi.n_agents
    values["summed multi"] = _num(summed)
    tests["VAE loss volatility: two agents > one"] = Tested(d["multi"]["scaled"], d["single"]["scaled"])
    w = welch_t(d["multi"]["scaled"], d["single"]["scaled"])
    fails = [] if (w["p"] < ALPHA and w["diff"] > 0) else [
        "the two-agent loss is not significantly more volatile" + (", the other way" if w["diff"] < 0 else "")]
    stat = (f"steps {lo:,}-{hi:,} of each run (the second half of the steps both sweeps ran), {single.name} vs "
            f"{multi.name}, volatility = sd of the VAE loss per image around its moving average of {SMOOTH} "
            "windows: " + "; ".join(parts) + f". The loss summed over the views as eq. 5 has it (a curve like "
            f"fig. 24's): volatility {_f(summed)} with two agents, twice the per-image one by construction")
    return _ucb_one_and_two_verdict(pair, key, claim, evidence, stat, fails, "Welch p < 0.05, multi > single",
                                    values, tests)


def vae_volatility(sweep: Sweep, group: Group, start: int, end: int, window: int = SMOOTH) -> dict:
    """Per run of `group`, over the windows lying wholly in steps [start, end) (arrays [runs]):
    "per_image" the sd of the VAE's loss per image around its trailing moving average of `window`
    windows (taken over the whole run, so the span's first windows have their history),
    "scaled" that times sqrt(agents), "late_change" (mean of the span's second half - mean of its
    first half) / mean of its first half. See `claim_two_agent_vae_unsettled`."""
    x = per_agent_vae_loss(sweep)[group.indices].astype(float)
    excess = x - moving_average(x, window, axis=1)
    e = sweep.metrics_every
    first, last = -(-int(start) // e), min(int(end) // e, x.shape[1])
    with np.errstate(invalid="ignore"):
        sd = np.array([np.nanstd(r, ddof=1) if np.isfinite(r).sum() > 1 else np.nan for r in excess[:, first:last]])
    mid = (start + end) // 2
    a, b = block_mean(sweep, x, start, mid), block_mean(sweep, x, mid, end)
    with np.errstate(invalid="ignore", divide="ignore"):
        change = (b - a) / a
    return {"per_image": sd, "scaled": sd * math.sqrt(sweep.n_agents), "late_change": change}


MEAN_LATENT_SIDE = "multi_agent.z_mean"  # two agents with the posterior mean as the latent (README)


def claim_agents_move_together(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 4: the two agents' curiosity curves move together ("remarkably similar", 4.1.2, 5).

    Measured on every run of multi_agent: the Pearson correlation of the two agents' smoothed
    curiosity (trailing moving average of 50 windows, the curve of fig. 17), on Fisher's z scale,
    minus a baseline: the mean z of the correlation between an agent of this run and the other
    agent of each other run of the same group (same policy and setting, other seed), in both
    pairings. The baseline has the same learning trend and the same policy but no shared events,
    so the difference is what the shared run adds. Verdict: holds if the 95% CI of the mean
    difference across runs lies above 0. Context, not the verdict: the same on `MEAN_LATENT_SIDE`
    (the posterior mean as the latent, so each agent's curiosity is the world model's error alone,
    without the posterior spread of the VAE the agents share), where loaded. Scale: runs of >=
    10,000 steps (>= 10 stretches of 1,000 steps, the smoothing span), >= MIN_SEEDS runs with a
    baseline (2+ seeds in their group).
    """
    key, claim = "4", "The two agents' curiosity curves move together"
    evidence = "section 4.1.2 (fig. 17: 'remarkably similar'), section 5; one run"
    s = presets.get("multi_agent")
    if s is None:
        return ClaimResult(key, claim, evidence, "n/a", _missing(("multi_agent",), presets))
    d = agent_curiosity_coupling(s)
    within, cross, diff = mean_ci(d["within"]), mean_ci(d["cross"]), mean_ci(d["diff"])
    n = int(np.isfinite(d["diff"]).sum())
    values = {"within z": _num(within[0]), "cross-run z": _num(cross[0]), "diff": _num(diff[0]),
              "diff low": _num(diff[1]), "diff high": _num(diff[2]), "runs": n}
    stat = (f"{s.name}, runs: {n}: Fisher z of the agents' correlation (smoothed curiosity) within a run "
            f"{_ci(within)} (r={_f(np.tanh(within[0]))}), agents of different runs of the same group {_ci(cross)} "
            f"(r={_f(np.tanh(cross[0]))}); within - baseline {_ci(diff)}")
    gap = _scale_gap(s, 10_000, {"runs with a baseline": n})
    error_only = presets.get(MEAN_LATENT_SIDE)
    if error_only is not None:
        e = mean_ci(agent_curiosity_coupling(error_only)["diff"])
        values.update({f"{MEAN_LATENT_SIDE} diff": _num(e[0]), f"{MEAN_LATENT_SIDE} diff low": _num(e[1])})
        stat += (f". Context, not the verdict: {error_only.name} (z=mean: the world model's error alone), within - "
                 f"baseline {_ci(e)}")
    fails = [] if diff[1] > 0 else ["the within-run correlation is not above the cross-run baseline"]
    tests = {"within-run z - cross-run z": Tested(d["diff"], runs_per_seed=len(s.groups()))}
    return ClaimResult(key, claim, evidence, stat, _decide([gap] if gap else [], fails, "the CI above 0"), values,
                       tests)


def agent_curiosity_coupling(sweep: Sweep, window: int = SMOOTH) -> dict:
    """Per run: {"within" z of corr(agent 0, agent 1), "cross" the baseline z, "diff" within -
    cross} (arrays [runs], NaN where a run's group has no other run); see
    `claim_agents_move_together`."""
    c = moving_average(sweep.metrics["curiosity"].astype(float), window, axis=1)  # [R, W, 2]
    n = sweep.n_runs
    within, cross = np.full(n, np.nan), np.full(n, np.nan)
    for g in sweep.groups():
        for i in g.indices:
            within[i] = fisher_z(pearson_r(c[i, :, 0], c[i, :, 1]))
            others = [j for j in g.indices if j != i]
            if others:
                cross[i] = np.mean([(fisher_z(pearson_r(c[i, :, 0], c[j, :, 1]))
                                     + fisher_z(pearson_r(c[j, :, 0], c[i, :, 1]))) / 2 for j in others])
    return {"within": within, "cross": cross, "diff": within - cross}


def claim_temperatures_alike(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 7: Boltzmann temperatures 0.5-2.5 make no significant difference (fig. 19, 4.1.4).

    Measured on boltzmann_temperatures, per run: the late curiosity = mean over the last quarter
    of the run (after the initial drop, where fig. 19's curves converge), averaged over the agents.
    One-way ANOVA across the temperature groups (F test; p from the F distribution), with eta^2,
    and the same test blocked by seed (`block_anova` on the seeds every temperature ran): runs of
    one seed draw the same random numbers and, with a near-uniform policy, share much of their
    course (`seed_coupling`), so they are not independent samples and the one-way test's error term
    holds the seeds' variance. Verdict, from the blocked test where it is defined (else the
    one-way): holds if p >= 0.05 (no significant difference, the paper's claim; with few seeds a
    temperature, only a sizeable effect would be detected), does not hold if p < 0.05. Scale: >= 2
    temperatures, runs of >= 40,000 steps, >= MIN_SEEDS seeds a temperature.
    """
    key, claim = "7", "Boltzmann temperatures 0.5-2.5 make no significant difference"
    evidence = "fig. 19, section 4.1.4 (one run per temperature)"
    s = presets.get("boltzmann_temperatures")
    if s is None:
        return ClaimResult(key, claim, evidence, "n/a", _missing(("boltzmann_temperatures",), presets))
    gs = sorted(s.groups("boltzmann"), key=lambda g: g.value)
    late = late_curiosity(s)
    a = one_way_anova([late[g.indices] for g in gs])
    table = seed_table(s, gs, late)
    blocked = block_anova(table)
    cells = [f"T={g.value:g} {_ci(mean_ci(late[g.indices]))}" for g in gs]
    values = {"F": _num(a["F"]), "p": _num(a["p"]), "eta2": _num(a["eta2"]), "df1": a["df1"], "df2": a["df2"],
              "F_blocked": _num(blocked["F"]), "p_blocked": _num(blocked["p"]), "df2_blocked": blocked["df2"],
              "seed_share": _num(blocked["block_share"])}
    values.update({f"T={g.value:g}": _num(np.nanmean(late[g.indices])) for g in gs})
    stat = (f"{s.name}: late curiosity (last quarter of the run) per temperature: {', '.join(cells)}; one-way ANOVA "
            f"F({a['df1']}, {a['df2']})={_f(a['F'])}, p={_p(a['p'])}, eta²={_f(a['eta2'])}")
    use_blocked = math.isfinite(blocked["p"])
    if use_blocked:
        stat += (f"; blocked by seed ({blocked['b']} seeds, {_f(100 * blocked['block_share'], 2)} % of the variance) "
                 f"F({blocked['df1']}, {blocked['df2']})={_f(blocked['F'])}, p={_p(blocked['p'])}")
        eq = equivalence_bound(table, ALPHA)
        values.update(equivalence_bound=_num(eq["bound"]), largest_difference=_num(eq["largest"]))
        if math.isfinite(eq["bound"]):
            stat += (f"; equivalence (context, not the verdict: two one-sided tests at 5 % for every two "
                     f"temperatures, blocked by seed): the data rule out differences beyond ±{_f(eq['bound'])} "
                     f"(largest observed {_f(eq['largest'])})")
    p = blocked["p"] if use_blocked else a["p"]
    gaps = []
    if len(gs) < 2:
        gaps.append(f">= 2 temperatures; {s.name} has {len(gs)}")
    gap = _scale_gap(s, 40_000, {g.label: g.n for g in gs})
    if gap:
        gaps.append(gap)
    if gaps:
        return ClaimResult(key, claim, evidence, stat, f"not testable at this scale (needs {'; '.join(gaps)})", values)
    if not np.isfinite(p):
        return ClaimResult(key, claim, evidence, stat, "not testable: the ANOVA is undefined (no spread)", values)
    verdict = "holds" if p >= ALPHA else f"does not hold: the temperatures differ (p={_p(p)})"
    tests = {"late curiosity, two temperatures apart": Tested(table, blocked=True)} if use_blocked else {}
    return ClaimResult(key, claim, evidence, stat, verdict, values, tests)


def late_curiosity(sweep: Sweep, fraction: float = 0.25) -> np.ndarray:
    """[runs]: mean curiosity over the last `fraction` of the windows, averaged over agents."""
    k = max(1, int(math.ceil(fraction * sweep.n_windows)))
    return _nanmean(sweep.metrics["curiosity"][:, -k:].astype(float), axis=(1, 2))


def seed_coupling(sweep: Sweep, a: Group, b: Group) -> dict:
    """How alike two groups' runs are when they share a seed, against when they do not.

    Runs of one seed draw the same random numbers, so where a policy barely depends on its setting
    (a near-uniform Boltzmann policy at any T) they repeat much of each other's actions. For each
    pair of runs, one from `a` and one from `b`: `identical`, the share of metrics windows in which
    an agent's action counts are identical (mean over agents), and `r`, the Pearson correlation
    of the two runs' curiosity curves (window means, mean over agents). Returns {"same": ...,
    "other": ...}, each {"identical": [...], "r": [...]}, one value per pair: pairs of the same
    seed, in seed order, and pairs of different seeds."""
    counts = sweep.metrics["action_counts"]
    curiosity = _nanmean(sweep.metrics["curiosity"].astype(float), axis=2)
    out = {kind: {"identical": [], "r": []} for kind in ("same", "other")}
    pairs = sorted(((sweep.runs[i].seed, i, j) for i in a.indices for j in b.indices),
                   key=lambda p: (sweep.runs[p[1]].seed != sweep.runs[p[2]].seed, p))
    for seed, i, j in pairs:
        kind = out["same" if seed == sweep.runs[j].seed else "other"]
        kind["identical"].append(float((counts[i] == counts[j]).all(axis=-1).mean()))
        kind["r"].append(pearson_r(curiosity[i], curiosity[j]))
    return out


def claim_boltzmann_least_curious(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 10: Boltzmann records the lowest curiosity of the three policies, throughout the run;
    ε-greedy and UCB follow similar curves (fig. 11, section 4.1).

    Measured on single_agent (the paper's section 4.1, one agent), per run: the mean curiosity
    over the whole run (`run_curiosity`). Two Welch t-tests across runs: ε-greedy > Boltzmann and
    UCB > Boltzmann. Verdict: holds if both have p < 0.05 in the paper's direction. Context, not
    the verdict: ε-greedy against UCB (Welch, with the bound two one-sided tests put on their
    difference: the paper's "very similar"), and the same three policies with two agents
    (multi_agent), where loaded. Scale: runs of >= 40,000 steps (the paper's "throughout" is an
    80,000-step run), >= MIN_SEEDS seeds a policy.
    """
    key, claim = "10", "Boltzmann records the lowest curiosity; ε-greedy and UCB alike"
    evidence = "fig. 11, section 4.1 (one agent; one run per policy)"
    return _policy_curiosity_claim(presets, key, claim, evidence, "single_agent", "multi_agent",
                                   (("eps", "boltzmann"), ("ucb", "boltzmann")), similar=("eps", "ucb"))


def claim_ucb_more_curious(presets: Mapping[str, Sweep]) -> ClaimResult:
    """Claim 11: UCB's curiosity is higher than ε-greedy's (section 4.2, figs. 17 and 18 against
    fig. 8: "the UCB runs ... show a significantly higher and more distinct curiosity reward").

    Measured on multi_agent (figs. 17 and 18 are two-agent runs), per run: the mean curiosity over
    the whole run (`run_curiosity`). Welch t-test UCB > ε-greedy across runs. Verdict: holds if
    p < 0.05 in the paper's direction. Context, not the verdict: the same with one agent
    (single_agent), where loaded. Scale: runs of >= 40,000 steps, >= MIN_SEEDS seeds a policy.
    """
    key, claim = "11", "UCB's curiosity is higher than ε-greedy's"
    evidence = "section 4.2 (figs. 17, 18 against fig. 8; one run each)"
    return _policy_curiosity_claim(presets, key, claim, evidence, "multi_agent", "single_agent", (("ucb", "eps"),))


def run_curiosity(sweep: Sweep) -> np.ndarray:
    """[runs]: the mean curiosity over the whole run, averaged over the agents."""
    return _nanmean(sweep.metrics["curiosity"].astype(float), axis=(1, 2))


def _policy_curiosity_claim(presets, key, claim, evidence, preset, context, pairs, similar=None) -> ClaimResult:
    """Claims 10 and 11: Welch tests of `run_curiosity` between the policies of `preset`, each pair
    (higher in the paper, lower); the same numbers for the `context` preset, and the `similar`
    pair with the bound two one-sided tests put on its difference, as context."""
    s = presets.get(preset)
    if s is None:
        return ClaimResult(key, claim, evidence, "n/a", _missing((preset,), presets))
    values: dict = {}
    found = _compare_policy_curiosity(s, f"{preset} ", pairs, similar, values)
    if isinstance(found, str):
        return ClaimResult(key, claim, evidence, "n/a", f"not testable: {found}")
    stat, fails, gs, tests = found
    stat = f"{s.name}: {stat}"
    other = presets.get(context)
    more = None if other is None else _compare_policy_curiosity(other, f"{context} ", pairs, similar, values)
    if more is not None and not isinstance(more, str):
        agents = f"{other.n_agents} agent{'s' * (other.n_agents > 1)}"
        stat += f". Context, not the verdict: {other.name} ({agents}): {more[0]}"
    gap = _scale_gap(s, 40_000, {g.label: g.n for g in gs.values()})
    return ClaimResult(key, claim, evidence, stat,
                       _decide([gap] if gap else [], fails, "every Welch test p < 0.05 in the paper's direction"),
                       values, tests)


def _compare_policy_curiosity(sweep: Sweep, prefix: str, pairs, similar, values: dict):
    """(statistic, fails, groups, tests) of `_policy_curiosity_claim` on one sweep, its numbers
    added to `values` under `prefix`; a message where the sweep lacks a policy."""
    needed = sorted({p for pair in pairs for p in pair} | set(similar or ()), key=("eps", "boltzmann", "ucb").index)
    gs = {p: paper_group(sweep, p) for p in needed}
    if any(g is None for g in gs.values()):
        return f"{sweep.name} has no runs of {', '.join(p for p, g in gs.items() if g is None)}"
    c = run_curiosity(sweep)
    cells = []
    for p, g in gs.items():
        m = mean_ci(c[g.indices])
        values[f"{prefix}{p}"] = _num(m[0])
        cells.append(f"{_short(p)} {_ci(m)}")
    parts, fails, tests = [f"mean curiosity over the run: {', '.join(cells)}"], [], {}
    for hi, lo in pairs:
        label = f"{_short(hi)} > {_short(lo)}"
        x, y = c[gs[hi].indices], c[gs[lo].indices]
        w = welch_t(x, y)
        values[f"{prefix}{label} t"], values[f"{prefix}{label} p"] = _num(w["t"]), _num(w["p"])
        parts.append(f"{label}: Welch t={_f(w['t'])}, p={_p(w['p'])}")
        tests[label] = Tested(x, y)
        if not (w["p"] < ALPHA and w["diff"] > 0):
            fails.append(f"{label} {'significantly the other way' if w['p'] < ALPHA else 'not significant'}")
    if similar:
        a, b = similar
        w = welch_t(c[gs[a].indices], c[gs[b].indices])
        bound = tost_bound(w["diff"], w["se"], w["df"], ALPHA)
        values.update({f"{prefix}{a} - {b}": _num(w["diff"]), f"{prefix}{a} - {b} p": _num(w["p"]),
                       f"{prefix}{a} - {b} bound": _num(bound)})
        parts.append(f"{_short(a)} - {_short(b)} {_f(w['diff'])}, p={_p(w['p'])}, within ±{_f(bound)} (two one-sided "
                     "tests at 5 %)")
    return "; ".join(parts), fails, gs, tests
