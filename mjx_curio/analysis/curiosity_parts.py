"""What claim 1's fall and rise are made of: the world model's error, or the posterior's spread.

The curiosity of a step is r = ||z_{t+1} - E[z_hat_{t+1}]||^2 (mean over the latent dimensions),
with z_{t+1} = mu + sigma * eps drawn from the VAE's posterior. Over the draw eps its expectation
is ||mu - E[z_hat_{t+1}]||^2 + mean(sigma^2): the MDN-RNN's error against the posterior mean,
which learning can reduce, plus the posterior's own variance, which no prediction removes. A
sweep that records `curiosity_spread` (the second term, a window mean per agent) gives the first
window by window as curiosity minus spread: unbiased, its noise averaged over a window's steps,
and over claim 1's blocks of thousands of steps. If the rise of curiosity late in a run is the
spread's, the world model is not growing more surprised; its VAE is growing less sure.

The same split reads claim 3 (two agents more curious than one) part by part: a second agent may
raise the world model's error, which its moves make harder to foresee, while the curiosity as a
whole does not move (`agents_parts_table`); claims 10 and 11, the policies' curiosity, part
by part (`policies_parts_table`); and claims 9 and 12, the curiosity of an agent watching something
move and of one touching an object (`situation_parts_table`).
"""

from __future__ import annotations

import warnings
from typing import Mapping

import numpy as np

from mjx_curio.analysis.claims import block_mean, contact_excess, fall_rise, watching_excess
from mjx_curio.analysis.significance import welch_t
from mjx_curio.analysis.stats import mean_ci
from mjx_curio.analysis.sweeps import Group, Sweep
from mjx_curio.analysis.tables import Table

SPREAD = "curiosity_spread"
# The parts, in the order tables and figures show them: the whole, the part learning cannot
# remove, and the part it can.
PARTS = {"curiosity": "curiosity obtained", "spread": "posterior spread", "error": "error against the posterior mean"}
# Under z=mean the latent is the posterior mean: no spread, the curiosity is the error itself.
MEAN_LATENT_PART = {"curiosity": "curiosity obtained = error (z=mean, no spread)"}


def records_spread(sweep: Sweep) -> bool:
    """Whether `sweep` recorded each window's posterior spread (sweeps made before it did not)."""
    return SPREAD in sweep.metrics


def samples_latent(sweep: Sweep) -> bool:
    """Whether `sweep`'s latents were posterior samples (z=sample, the paper's), so that its
    curiosity holds the spread; under z=mean (the posterior mean as the latent) it is all error."""
    return sweep.learner_config().z == "sample"


def default_vae(sweep: Sweep) -> bool:
    """Whether `sweep`'s VAE has the default layers: the tables that set one sweep against another
    compare like with like (a side experiment with the authors' layers is read on its own)."""
    return sweep.learner_config().vae_layers == "hs"


def curiosity_parts(sweep: Sweep, group: Group) -> dict[str, np.ndarray]:
    """Per run of `group` and window, the agents' mean of each part of `PARTS`: {part: [runs, windows]}."""
    if not records_spread(sweep):
        raise ValueError(f"{sweep.name} does not record {SPREAD} (made before sweeps recorded it)")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        c = np.nanmean(sweep.metrics["curiosity"][group.indices].astype(float), axis=2)
        s = np.nanmean(sweep.metrics[SPREAD][group.indices].astype(float), axis=2)
    return {"curiosity": c, "spread": s, "error": c - s}


def parts_fall_rise(sweep: Sweep, group: Group) -> dict[str, dict]:
    """Claim 1's blocks of each part (`claims.fall_rise`): {part: {"early", "trough", "late",
    "fall", "rise"}}, arrays over the group's runs. The error's fall and rise are the curiosity's
    minus the spread's, run by run."""
    return {part: fall_rise(sweep, x) for part, x in curiosity_parts(sweep, group).items()}


def curiosity_parts_table(presets: Mapping[str, Sweep]) -> Table:
    """Per sweep that records the spread and per group of it: each part's means over claim 1's
    blocks (steps 0-2,000, 10,000-30,000, the last 10,000), its fall and rise with their 95 % CIs
    over runs, and its share of the curiosity's mean fall and rise. A z=mean sweep has one row a
    group: its curiosity, all of it error (`MEAN_LATENT_PART`)."""
    cols = ["sweep", "group", "runs", "part", "steps 0-2k", "steps 10k-30k", "last 10k steps", "fall [95 % CI]",
            "rise [95 % CI]", "share of the fall", "share of the rise"]
    rows, values = [], []
    for name, s in presets.items():
        if not records_spread(s):
            continue
        for g in s.groups():
            d = parts_fall_rise(s, g)
            whole = {k: _mean(d["curiosity"][k]) for k in ("fall", "rise")}
            for part, what in (PARTS if samples_latent(s) else MEAN_LATENT_PART).items():
                x = d[part]
                block = {k: _mean(x[k]) for k in ("early", "trough", "late")}
                fall, rise = mean_ci(x["fall"]), mean_ci(x["rise"])
                share = {k: _mean(x[k]) / whole[k] if np.isfinite(whole[k]) and whole[k] != 0 else float("nan")
                         for k in ("fall", "rise")}
                rows.append([f"`{name}`", g.label, str(g.n), what, *(_f(block[k]) for k in ("early", "trough", "late")),
                             _ci(fall), _ci(rise), _pct(share["fall"]), _pct(share["rise"])])
                values.append({"sweep": name, "group": g.label, "runs": g.n, "part": part, **block,
                               "fall": float(fall[0]), "fall_low": float(fall[1]), "fall_high": float(fall[2]),
                               "rise": float(rise[0]), "rise_low": float(rise[1]), "rise_high": float(rise[2]),
                               "fall_share": share["fall"], "rise_share": share["rise"]})
    note = ("Curiosity (mean of the agents) = error against the posterior mean + posterior spread, in expectation "
            "over the latent's sampling noise; the spread is recorded, the error is curiosity minus spread. "
            "fall = steps 0-2k minus 10k-30k, rise = last 10k minus 10k-30k (claim 1's blocks), per run; "
            "mean over runs [95 % CI]. Share: the part's mean over the curiosity's.")
    if any(not samples_latent(s) for s in presets.values() if records_spread(s)):
        note += " Under z=mean (the posterior mean as the latent) there is no spread: the curiosity is all error."
    return Table(cols, rows, values, note if rows else "")


def agents_parts_table(presets: Mapping[str, Sweep]) -> Table:
    """Claim 3 part by part: one agent against two, from the sweeps that record the spread with
    sampled latents (z=sample), for every policy and setting both a one-agent and a two-agent
    such sweep ran. Per part (`PARTS`): each run's mean over the second half of the steps both
    sweeps ran (claim 3's window), mean over runs [95 % CI] for one agent and for two (the mean of
    both agents), and Welch's t-test of two minus one."""
    sampled = [(n, s) for n, s in presets.items() if records_spread(s) and samples_latent(s) and default_vae(s)]
    cols = ["sweeps (one agent / two)", "policy", "part", "one agent", "runs", "two agents", "runs", "two minus one",
            "Welch p"]
    rows, values, steps = [], [], set()
    for one_name, one in (x for x in sampled if x[1].n_agents == 1):
        for two_name, two in (x for x in sampled if x[1].n_agents == 2):
            common = min(one.steps_done, two.steps_done)
            lo, hi = common // 2, common
            for g1 in one.groups():
                g2 = next((g for g in two.groups() if g.label == g1.label), None)
                if g2 is None:
                    continue
                steps.add((lo, hi))
                p1, p2 = curiosity_parts(one, g1), curiosity_parts(two, g2)
                for part, what in PARTS.items():
                    x1, x2 = block_mean(one, p1[part], lo, hi), block_mean(two, p2[part], lo, hi)
                    m1, m2, w = mean_ci(x1), mean_ci(x2), welch_t(x2, x1)
                    rows.append([f"`{one_name}` / `{two_name}`", g1.label, what, _ci(m1), str(g1.n), _ci(m2),
                                 str(g2.n), _f(w["diff"]), f"{w['p']:.3g}" if np.isfinite(w["p"]) else "n/a"])
                    values.append({"one": one_name, "two": two_name, "group": g1.label, "part": part,
                                   "from": lo, "to": hi, "one_mean": float(m1[0]), "two_mean": float(m2[0]),
                                   "diff": w["diff"], "t": w["t"], "p": w["p"]})
    window = ", ".join(f"{lo:,}-{hi:,}" for lo, hi in sorted(steps))
    note = (f"Claim 3 part by part: each run's mean over steps {window} (the second half of the steps both sweeps "
            "ran, claim 3's window) of the curiosity (mean of the agents) and its parts, from the sweeps that record "
            "the spread with sampled latents; mean over runs [95 % CI]; Welch's t-test of two agents minus one.")
    return Table(cols, rows, values, note if rows else "")


# Claims 10 and 11, part by part: (policy, against policy), the first the one the claims single out.
POLICY_PAIRS = (("boltzmann", "eps"), ("boltzmann", "ucb"), ("ucb", "eps"))


def policies_parts_table(presets: Mapping[str, Sweep]) -> Table:
    """Claims 10 and 11 part by part: one policy against another with the same number of agents,
    each from a sweep that records the spread with sampled latents (z=sample), for the pairs of
    `POLICY_PAIRS` such sweeps ran (the paper's setting of each policy; the first made of the sweeps
    that ran a policy where several did, so that a later rerun adds no silent change of sweep).
    Per part (`PARTS`): each run's mean over the whole run (claims 10 and
    11's measure; over the steps both sweeps ran), mean over runs [95 % CI] for each policy, and
    Welch's t-test of the first minus the second."""
    from mjx_curio.analysis.claims import PAPER_SETTING

    found: dict[tuple[int, str], tuple[str, Sweep, Group]] = {}
    for name, s in sorted(presets.items(), key=lambda item: item[1].manifest.get("created", "")):
        if not (records_spread(s) and samples_latent(s) and default_vae(s)):
            continue
        for g in s.groups():
            if np.isclose(g.value, PAPER_SETTING[g.policy]):
                found.setdefault((s.n_agents, g.policy), (name, s, g))
    cols = ["agents", "policy (sweep)", "against (sweep)", "part", "policy", "runs", "against", "runs", "difference",
            "Welch p"]
    rows, values = [], []
    for agents in sorted({a for a, _ in found}):
        for first, second in POLICY_PAIRS:
            if (agents, first) not in found or (agents, second) not in found:
                continue
            (n1, s1, g1), (n2, s2, g2) = found[agents, first], found[agents, second]
            hi = min(s1.steps_done, s2.steps_done)
            p1, p2 = curiosity_parts(s1, g1), curiosity_parts(s2, g2)
            for part, what in PARTS.items():
                x1, x2 = block_mean(s1, p1[part], 0, hi), block_mean(s2, p2[part], 0, hi)
                m1, m2, w = mean_ci(x1), mean_ci(x2), welch_t(x1, x2)
                rows.append([str(agents), f"{g1.label} (`{n1}`)", f"{g2.label} (`{n2}`)", what, _ci(m1), str(g1.n),
                             _ci(m2), str(g2.n), _f(w["diff"]), f"{w['p']:.3g}" if np.isfinite(w["p"]) else "n/a"])
                values.append({"agents": agents, "policy": first, "against": second, "sweep": n1, "against_sweep": n2,
                               "part": part, "to": hi, "mean": float(m1[0]), "against_mean": float(m2[0]),
                               "diff": w["diff"], "t": w["t"], "p": w["p"]})
    note = ("Claims 10 and 11 part by part: each run's mean over the whole run (over the steps both sweeps ran) of the "
            "curiosity (mean of the agents) and its parts, from the sweeps that record the spread with sampled "
            "latents, the paper's setting of each policy; mean over runs [95 % CI]; Welch's t-test of the policy "
            "minus the one it is set against.")
    return Table(cols, rows, values, note if rows else "")


# The situations of claims 12 and 9, as `situation_parts_table` names them.
SITUATIONS = {"12": "12: touching an object", "9": "9: watching something move"}


def situation_parts_table(presets: Mapping[str, Sweep]) -> Table:
    """Claims 9 and 12 part by part: per sweep that records the spread with sampled latents
    (z=sample) and per group of it, for each part (`PARTS`, per agent: the curiosity, the spread,
    and the curiosity minus the spread), the claim's own measure: its excess over the agent's
    moving average while it touches an object minus while it touches nothing (claim 12,
    `claims.contact_excess`), and, with two agents, while the other agent or a moving object is in
    view minus while neither is, with no contact of its own (claim 9, `claims.watching_excess`);
    mean over runs [95 % CI], raw and with the view's fill held fixed (`claims.beyond_view`)."""
    cols = ["sweep", "group", "claim", "runs", "part", "in the situation - out of it", "the view's fill held fixed"]
    rows, values = [], []
    for name, s in presets.items():
        if not (records_spread(s) and samples_latent(s)):
            continue
        c = s.metrics["curiosity"].astype(float)
        spread = s.metrics[SPREAD].astype(float)
        series = {"curiosity": c, "spread": spread, "error": c - spread}
        for g in s.groups():
            for claim in ("12", "9") if s.n_agents == 2 else ("12",):
                for part, x in series.items():
                    if claim == "12":
                        d = contact_excess(s, g, series=x[g.indices])
                        diff, fixed = d["diff"], d["beyond_view"]
                    else:
                        d = watching_excess(s, series=x)
                        diff, fixed = d["diff"][g.indices], d["beyond_view"][g.indices]
                    raw, held = mean_ci(diff), mean_ci(fixed)
                    runs = str(int(np.isfinite(diff).sum()))
                    rows.append([f"`{name}`", g.label, SITUATIONS[claim], runs, PARTS[part], _ci(raw), _ci(held)])
                    values.append({"sweep": name, "group": g.label, "claim": claim, "part": part,
                                   "diff": float(raw[0]), "diff_low": float(raw[1]), "diff_high": float(raw[2]),
                                   "beyond_view": float(held[0]), "beyond_view_low": float(held[1]),
                                   "beyond_view_high": float(held[2])})
    note = ("Claims 9 and 12 part by part: each part's excess over the agent's moving average of 50 windows in the "
            "claim's situation minus out of it (claim 12: touching an object against touching nothing, runs with at "
            "least 5 touching windows; claim 9: the other agent or a moving object in view against neither, no "
            "contact of its own), and the same with the share of the view that the objects and the other agent fill "
            "held fixed (per run, least squares on the situation, that share and its square); mean over runs "
            "[95 % CI].")
    return Table(cols, rows, values, note if rows else "")


def _mean(x: np.ndarray) -> float:
    """The mean over runs, NaN where no run has a value (a block the sweep has not reached)."""
    return float(np.nanmean(x)) if np.isfinite(x).any() else float("nan")


def _f(x: float) -> str:
    return f"{x:.3f}" if np.isfinite(x) else "n/a"


def _pct(x: float) -> str:
    return f"{100 * x:.0f} %" if np.isfinite(x) else "n/a"


def _ci(m) -> str:
    mean, lo, hi, _ = (float(v) for v in m)
    if not np.isfinite(mean):
        return "n/a"
    return f"{mean:.3f} [{lo:.3f}, {hi:.3f}]" if np.isfinite(lo) else f"{mean:.3f}"
