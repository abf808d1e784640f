"""The paper's experiments at their full length: 80,000 steps, where the committed runs stop at 40,000.

    python experiments/full_length_evidence.py runs/h200/main [runs/paper/single_agent.full_length ...]

The main job (`python -m mjx_curio.sweep policies=eps,boltzmann,ucb seeds=8`: two agents, the
three policies, 8 seeds a policy, the paper's 80,000 steps) takes about a day on a 2-core CPU, so
the committed runs (experiments/results/) stop at 40,000 steps. A GPU runs the whole job in
minutes (docs/cost_model.md). Such sweeps' metrics (the main job's about 25 MB) are not
committed; this script reduces them to what the results page shows and writes
docs/results/full_length.json. Each sweep given stands for the preset whose settings it has
(`analysis.assign_presets`: the main job is `multi_agent`; a sweep named `<preset>.<label>` stands
for <preset>) on the platform it ran on, a CPU or a GPU (`platform_of`), and is compared with that
preset's committed runs of the same settings, all their seeds (a full-length sweep may run some of
the preset's policies and seeds: on a CPU, one agent's ε-greedy runs, fig. 8's setting, take hours
where all of its runs take a day; sweeps of one preset's different policies on one platform stand
for it together, `stands_for`). An entry of the file is a preset on a platform: the main job on a
GPU and a few of its runs on a CPU are two entries. The file keeps what it holds of entries not
given this time, so that sweeps measured on different machines, or in different sessions, stand
side by side:

- `claims`: the paper's claims that each given sweep can test by itself (`analysis.claims_table`
  on it alone), at its full length, and claim 14 of a one-agent and a two-agent sweep given
  together on one platform, each row with the presets it was computed from (`presets`) and the
  platform of each (`on`);
- `platforms`: the sweep against the committed CPU runs over the steps both ran, policy by policy
  (`analysis.walls_measures`: late curiosity, the VAE loss per image and its reconstruction term
  over the last 10,000 of those steps, object contacts per 1,000 agent-steps over all of them);
  Welch's t-test across seeds, then Holm's correction over the table's tests. Another device
  rounds differently (and a recent NVIDIA GPU, at JAX's default precision, runs float32 matrix
  products and convolutions on TF32 tensor cores), so no run is reproduced bit for bit; the
  question is whether the results move beyond seed noise;
- `halves`: the same measures (object contacts too) over the sweep's last 10,000 steps against the
  10,000 before the committed runs' end, run by run (a paired t-test): what the second half of the
  paper's run length changes;
- `curves`: each run's curiosity (the mean of its agents) in bins of 1,000 steps, and its contacts
  with objects and between the agents summed from the start, for both sets of runs, from which
  `results.py page` draws the figures;
- `one_against_two`: for each one-agent and two-agent entry of the same length, the two set
  against each other over their last 10,000 steps (`one_against_two`), claim 3 at the full
  length, whose row joins the claims (pairs on one platform first); each run's change in those
  measures from the committed runs' last 10,000 steps to its own last 10,000, two agents against
  one; and the same over their committed runs' last 10,000 steps, where the two sides may share
  their machines when the full-length sweeps do not;
- `across_platforms`: for each preset the file holds on a CPU and on a GPU at one length, the two
  entries' runs over their last 10,000 steps, the GPU's against the CPU's (`across_platforms`):
  how far the machine alone moves the measures at the full length.

Per sweep (`sweeps`), `platforms`, `halves` and `curves`. It refuses a sweep that fits no
preset, whose runs were set up differently (`analysis.run_config`; how the runs are looped over
may differ) from the committed runs, that has a policy or seed they lack, or that is not longer
than them; and sweeps that would stand for an entry with fewer runs of a policy than the file
holds of it (`lost_runs`: measuring an entry anew replaces it whole, and the metrics behind it
may not be on this machine), before reducing anything.
"""

from __future__ import annotations

import dataclasses
import json
import math
import pathlib
import sys

import mjx_curio  # noqa: F401  (XLA flags before JAX initialises)

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "results" / "full_length.json"
LATE_STEPS = 10_000
BIN_STEPS = 1_000


def holm(p: list) -> list:
    """Holm's step-down adjusted p-values; None (no test) stays None and is not counted."""
    idx = sorted((i for i, v in enumerate(p) if v is not None), key=lambda i: p[i])
    out, running = [None] * len(p), 0.0
    for rank, i in enumerate(idx):
        running = max(running, min(1.0, (len(idx) - rank) * p[i]))
        out[i] = running
    return out


def paired_t(x, y) -> dict:
    """Mean of x - y over runs with both finite, and the two-sided paired t-test's p."""
    from mjx_curio import analysis as an

    d = np.asarray(x, float) - np.asarray(y, float)
    d = d[np.isfinite(d)]
    out = {"diff": float(d.mean()) if len(d) else None, "n": int(len(d)), "p": None}
    if len(d) >= 2 and d.std(ddof=1) > 0:
        out["p"] = an.t_pvalue(float(d.mean() / (d.std(ddof=1) / math.sqrt(len(d)))), len(d) - 1)
    return out


def _num(v) -> float | None:
    """A number for JSON: None where it is not finite (JSON has no NaN)."""
    return float(v) if v is not None and math.isfinite(v) else None


def _floats(x, digits: int | None = None) -> list:
    """Per-run numbers for JSON: at full precision, so that a test recomputes the p-values from
    them exactly; the curves' many numbers rounded to `digits`."""
    return [_num(float(v) if digits is None else round(float(v), digits)) for v in np.asarray(x, float)]


def _same_setup(long, short) -> None:
    from mjx_curio import analysis as an

    # How the runs are looped over (vmap on a GPU, map on a CPU) is execution, not a setting of the runs.
    long_cfg, short_cfg = an.run_config(long.manifest), an.run_config(short.manifest)
    if dataclasses.replace(long_cfg, runs_loop=short_cfg.runs_loop) != short_cfg:
        raise ValueError(f"{long.path} ran other settings than the committed runs {short.name}; "
                         "compare it with runs of its own settings")
    key = lambda s: {(r.policy, r.seed, r.eps, r.temperature, r.ucb_c) for r in s.runs}  # noqa: E731
    extra = sorted(key(long) - key(short))
    if extra:
        runs = ", ".join(f"{policy} seed {seed}" for policy, seed, *_ in extra)
        raise ValueError(f"{long.path} has runs the committed runs {short.name} lack ({runs}); compare runs "
                         "of the committed policies and seeds")
    if long.steps_done <= short.steps_done:
        raise ValueError(f"{long.path} has {long.steps_done:,} steps done, no more than the committed runs' "
                         f"{short.steps_done:,}")


def _curves(sweep) -> dict:
    """Per run, in bins of BIN_STEPS (`analysis.run_curves`), as JSON lists: the curiosity (mean of
    the agents, rounded), and the contact steps with objects and between the agents summed from
    the start (figs. 21 and 22, not normalised)."""
    from mjx_curio import analysis as an

    cv = an.run_curves(sweep, BIN_STEPS)
    out = {"steps": [int(s) for s in cv["steps"]], "runs": [_floats(r, digits=6) for r in cv["runs"]]}
    for key in ("object_contacts", "agent_contacts"):
        out[key] = [[int(v) for v in r] for r in cv[key]]
    return out


def late_measures(sweep, end: int) -> dict:
    """`walls_measures` over the sweep's first `end` steps, with object contacts counted over the
    same last LATE_STEPS as the other measures (not over all `end` steps)."""
    from mjx_curio import analysis as an
    from mjx_curio.analysis.walls import walls_measures

    out = walls_measures(sweep, end, LATE_STEPS)
    late = slice((end - LATE_STEPS) // sweep.metrics_every, end // sweep.metrics_every)
    steps = sweep.metrics["steps_taken"][:, late].astype(float).sum(axis=1) * sweep.n_agents
    contacts = an.object_contacts(sweep)[:, late].astype(float).sum(axis=1)
    out["object_contacts"] = np.where(steps > 0, 1000 * contacts / np.maximum(steps, 1), np.nan)
    return out


def sweep_evidence(preset: str, long, short) -> dict:
    """The JSON entry of one sweep (module docstring): `long` against the committed sweep `short`
    of the same preset."""
    from mjx_curio import analysis as an
    from mjx_curio.analysis.walls import MEASURES, walls_measures

    _same_setup(long, short)
    end, full = short.steps_done, long.steps_done
    parts = long.parts or (long,)
    devices = list({json.dumps(p.manifest.get("device", {}), sort_keys=True): p.manifest.get("device", {})
                    for p in parts}.values())
    at_end = walls_measures(long, end, LATE_STEPS)
    committed = walls_measures(short, end, LATE_STEPS)
    first, second = late_measures(long, end), late_measures(long, full)
    platforms, halves = [], []
    for g in long.groups():
        h = next(x for x in short.groups(g.policy) if np.isclose(x.value, g.value))
        for key, what, _ in MEASURES:
            t = an.welch_t(at_end[key][g.indices], committed[key][h.indices])
            platforms.append({"group": g.label, "measure": key, "what": what,
                              "long": _floats(at_end[key][g.indices]), "short": _floats(committed[key][h.indices]),
                              "diff": _num(t["diff"]), "p": _num(t["p"])})
            halves.append({"group": g.label, "measure": key, "what": what,
                           "first": _floats(first[key][g.indices]), "second": _floats(second[key][g.indices]),
                           **paired_t(second[key][g.indices], first[key][g.indices])})
    for rows in (platforms, halves):
        for row, q in zip(rows, holm([r["p"] for r in rows])):
            row["p_holm"] = q
    return {
        # a sweep merged from parts (`stands_for`): each part's command, and its machines, once each
        "preset": preset, "platform": platform_of(devices), "sweep": long.name, "command": " && ".join(p.manifest.get("command", "") for p in parts),
        "device": devices[0] if len(devices) == 1 else devices, "versions": long.manifest.get("versions", {}),
        "steps": full, "runs": len(long.runs), "agents": long.n_agents,
        # a merged sweep's parts may have run on different machines
        "committed": {"sweep": short.name, "steps": end, "runs": len(short.runs),
                      "devices": [p.manifest.get("device", {}) for p in (short.parts or [short])]},
        "late_steps": LATE_STEPS,
        "platforms": platforms, "halves": halves,
        "curves": {"bin_steps": BIN_STEPS, "groups": {g.label: [int(i) for i in g.indices] for g in long.groups()},
                   "long": _curves(long),
                   "short": {**_curves(short), "groups": {g.label: [int(i) for i in g.indices]
                                                          for g in short.groups()}}},
    }


def platform_of(device: dict | list) -> str:
    """"cpu" or "gpu": the platform of a sweep's machine (its manifest's `device`), or of a merged
    sweep's machines (a list of them), which `stands_for` gives one platform; "cpu+gpu" where they
    differ."""
    ds = device if isinstance(device, list) else [device]
    return "+".join(sorted({d.get("platform", "cpu") for d in ds}))


def entry_key(e: dict) -> tuple[str, str]:
    """(preset, platform): what an entry of the file stands for. An entry written before entries
    recorded their platform has its machines' (`platform_of`)."""
    return e["preset"], e.get("platform") or platform_of(e["device"])


AGENT_MEASURES = ("curiosity", "vae_loss", "recon")  # claim 3's two, and the loss's reconstruction term
ONE, TWO = "single_agent", "multi_agent"


def evidence(longs: dict, committed: dict) -> dict:
    """{"claims": the claims each sweep of `longs` ({(preset, platform): sweep}) can test by itself,
    and claim 14 of each one-agent and two-agent sweep of one length on one platform (`vae_unsettled`),
    "sweeps": `sweep_evidence` of each against `committed`'s ({preset: sweep}) sweep of its preset}."""
    from mjx_curio import analysis as an

    missing = sorted({p for p, _ in longs} - set(committed))
    if missing:
        raise ValueError(f"no committed runs of {', '.join(missing)} to compare with")
    keys = sorted(longs)
    return {"claims": [{"claim": r[0], "text": r[1], "statistic": r[3], "verdict": r[4], "presets": [preset],
                        "on": [platform]}
                       for preset, platform in keys for r in an.claims_table({preset: longs[preset, platform]}).rows
                       if not r[4].startswith("not testable")] + vae_unsettled(longs),
            "sweeps": [sweep_evidence(p, longs[p, pl], committed[p]) for p, pl in keys]}


def vae_unsettled(longs: dict) -> list[dict]:
    """Claim 14 (the two-agent VAE's loss stays volatile where one agent's settles, fig. 24) of each
    one-agent and two-agent sweep of `longs` ({(preset, platform): sweep}) of one length on one
    platform, over the second half of their steps: the claims table's test, which needs each run's
    VAE loss over those steps, so only sweeps reduced together (the file keeps their last steps'
    means, not the losses' course). Rows as `evidence`'s, with both presets and platforms."""
    from mjx_curio.analysis.claims import claim_two_agent_vae_unsettled

    rows = []
    for platform in sorted({pl for _, pl in longs}):
        one, two = longs.get((ONE, platform)), longs.get((TWO, platform))
        if one is None or two is None or one.steps_done != two.steps_done:
            continue
        r = claim_two_agent_vae_unsettled({ONE: one, TWO: two})
        if not r.verdict.startswith("not testable"):
            rows.append({"claim": r.key, "text": r.claim, "statistic": r.statistic, "verdict": r.verdict,
                         "presets": [TWO, ONE], "on": [platform, platform]})
    return rows


def _claim_order(claim: str) -> tuple[int, str]:
    """"6a" -> (6, "a"): the claims table's order."""
    digits = claim[:len(claim) - len(claim.lstrip("0123456789"))]
    return int(digits or 0), claim[len(digits):]


def merged(old: dict | None, new: dict) -> dict:
    """`new` (`evidence`) with what `old` (the file as it was) holds of other entries (`entry_key`):
    its sweeps of presets on platforms `new` does not measure, and its claims computed from none of
    `new`'s entries (a claim computed from an entry measured anew is computed anew, or dropped with
    its sweep). Rows of a file written before they recorded their presets came from all of that
    file's sweeps, and rows written before they recorded their platforms (`on`) from the one entry that
    file held of each preset. Claims in the claims table's order, a claim's rows in the order of
    their entries; sweeps by entry."""
    if not old:
        return new
    fresh = {entry_key(x) for x in new["sweeps"]}
    before = sorted(x["preset"] for x in old["sweeps"])
    on = {x["preset"]: entry_key(x)[1] for x in old["sweeps"]}
    kept = []
    for r in old["claims"]:
        presets = r.get("presets", before)
        kept.append({**r, "presets": presets, "on": r.get("on", [on.get(p, "") for p in presets])})
    claims = [r for r in kept if not fresh & set(zip(r["presets"], r["on"]))] + new["claims"]
    sweeps = [{**x, "platform": entry_key(x)[1]} for x in old["sweeps"] if entry_key(x) not in fresh] + new["sweeps"]
    return {"claims": _in_order(claims), "sweeps": sorted(sweeps, key=entry_key)}


def _in_order(claims: list) -> list:
    """Claims rows in the claims table's order, a claim's rows in the order of their entries."""
    return sorted(claims, key=lambda r: (_claim_order(r["claim"]), r["presets"], r.get("on", [])))


def one_against_two(sweeps: list) -> list[dict]:
    """Claim 3 at the full length for each pair of the file's entries of single_agent and
    multi_agent (`pair_against`) of one length: pairs whose two sides ran on one platform first,
    then by their platforms. Empty where there is no such pair."""
    ones = [x for x in sweeps if x["preset"] == ONE]
    twos = [x for x in sweeps if x["preset"] == TWO]
    pairs = [(one, two) for one in ones for two in twos
             if one["steps"] == two["steps"] and one["late_steps"] == two["late_steps"]]
    pairs.sort(key=lambda p: (entry_key(p[0])[1] != entry_key(p[1])[1], entry_key(p[0])[1], entry_key(p[1])[1]))
    return [pair_against(one, two) for one, two in pairs]


def pair_against(one: dict, two: dict) -> dict:
    """Claim 3 (two agents have higher curiosity and a higher VAE loss than one) at the full length,
    from the file's entry (`sweep_evidence`) `one` of single_agent and `two` of multi_agent, of one
    length. The committed claim compares the second half of the steps both sweeps ran; the file
    keeps, per run, the measures over the last LATE_STEPS (`halves`, a sweep's own numbers
    whatever else the file holds), so the comparison is over those: per policy both ran, the late
    curiosity, the VAE loss per image and its reconstruction term, two agents against one, Welch's
    two-sided t-test and Holm's correction over the table's tests. The verdict, as claim 3's: the
    UCB runs (the paper's choice), both curiosity and the VAE loss higher with two agents at
    p < 0.05 (no claim row where either side lacks UCB runs). The two entries may come from
    different machines: their `platforms` tables say how far that alone moves the same measures,
    and `committed` sets one agent against two on the committed runs.

    {"one", "two": the sweeps' names, "on": their platforms (one's, two's), "steps", "late_steps",
    "rows": [{"group", "measure", "what", "one", "two" (per run), "diff" (two - one), "t", "p",
    "p_holm"}], "committed": where both entries have their committed runs' measures at one length,
    {"one", "two": those sweeps' names, "steps", "rows": the same rows over the last LATE_STEPS of
    those runs}, "changes": where both entries' `halves` start at one step (`_changes_against`),
    {"steps": [first, last] of the earlier steps, "rows": each run's change in the measures from
    those steps to the last LATE_STEPS, two agents against one}, "claim": the claims-table row, or
    None}."""
    from mjx_curio import analysis as an
    from mjx_curio.analysis.claims import claim_two_agents_higher
    from mjx_curio.analysis.claims.common import ALPHA, _ci, _decide, _f, _p

    late = lambda e: {(h["group"], h["measure"]): h for h in e["halves"]}  # noqa: E731
    rows = _two_against_one(late(one), late(two), "second")
    lo, hi = one["steps"] - one["late_steps"], one["steps"]
    ucb = [r for r in rows if r["group"].startswith(an.POLICY_LABELS["ucb"]) and r["measure"] != "recon"]
    result = claim_two_agents_higher({})  # its wording; with no sweep it tests nothing
    parts, fails = [], []
    for r in ucb:
        what = "curiosity" if r["measure"] == "curiosity" else "VAE loss per image"
        ms, mm = (an.mean_ci(np.asarray(v, float)) for v in (r["one"], r["two"]))
        parts.append(f"{what}: one agent {_ci(ms)}, two agents {_ci(mm)}, Welch t={_f(_nan(r['t']))}, "
                     f"p={_p(_nan(r['p']))}")
        if not (r["p"] is not None and r["p"] < ALPHA and r["diff"] > 0):
            fails.append(f"{what} not significantly higher with two agents")
    on = [entry_key(one)[1], entry_key(two)[1]]
    stat = (f"mean over steps {lo:,}-{hi:,} of each run (the last {one['late_steps']:,} steps, which "
            f"full_length.json keeps of every run), {one['sweep']} ({on[0].upper()}) vs {two['sweep']} "
            f"({on[1].upper()}): " + "; ".join(parts))
    claim = {"claim": result.key, "text": result.claim, "statistic": stat, "presets": [TWO, ONE],
             "on": on[::-1], "verdict": _decide([], fails, "both Welch tests p < 0.05, multi > single")}
    out = {"one": one["sweep"], "two": two["sweep"], "on": on, "steps": hi,
           "late_steps": one["late_steps"], "rows": rows,
           "claim": claim if ucb else None}  # without UCB runs on both sides, the claim is not tested
    committed = _committed_one_against_two(one, two)
    changes = _changes_against(one, two)
    return {**out, **({"committed": committed} if committed else {}), **({"changes": changes} if changes else {})}


def _changes_against(one: dict, two: dict) -> dict | None:
    """What the second half changes, two agents against one: each run's change in claim 3's
    measures from the LATE_STEPS before the committed runs' end to the sweep's last LATE_STEPS
    (`halves`' "second" minus its "first", run by run), Welch's two-sided t-test of two agents'
    changes against one agent's and Holm's correction over the table's tests. Fig. 24 has two
    agents' VAE loss failing to converge: here, a smaller fall. None where an entry's `halves` keep
    no earlier steps or the two entries' earlier steps differ."""
    if not all("committed" in e and all("first" in h for h in e["halves"]) for e in (one, two)):
        return None
    if one["committed"]["steps"] != two["committed"]["steps"]:
        return None

    def change(e: dict) -> dict:
        return {(h["group"], h["measure"]): {"what": h["what"], "change": _floats(
            np.asarray(h["second"], float) - np.asarray(h["first"], float))} for h in e["halves"]}

    end = one["committed"]["steps"]
    return {"steps": [end - one["late_steps"], end], "rows": _two_against_one(change(one), change(two), "change")}


def _two_against_one(one: dict, two: dict, side: str) -> list:
    """Rows of `one_against_two`: for each policy both {(group, measure): row} dicts hold (in
    `one`'s order) and each of AGENT_MEASURES, the per-run numbers `row[side]` of two agents
    against one, Welch's two-sided t-test, and Holm's correction over the rows' tests."""
    return _against(one, two, side, ("one", "two"), AGENT_MEASURES)


def _against(left: dict, right: dict, side: str, names: tuple[str, str], measures) -> list:
    """For each policy both {(group, measure): row} dicts hold (in `left`'s order) and each of
    `measures` both hold, the per-run numbers `row[side]` of each as `names`, the difference
    right minus left with Welch's two-sided t-test, and Holm's correction over the rows' tests."""
    from mjx_curio import analysis as an

    groups = [g for g in dict.fromkeys(k[0] for k in left) if any(k[0] == g for k in right)]
    rows = []
    for g in groups:
        for key in measures:
            if (g, key) not in left or (g, key) not in right:
                continue
            x, y = left[(g, key)], right[(g, key)]
            t = an.welch_t(np.asarray(y[side], float), np.asarray(x[side], float))
            rows.append({"group": g, "measure": key, "what": x["what"], names[0]: x[side], names[1]: y[side],
                         "diff": _num(t["diff"]), "p": _num(t["p"]), "t": _num(t["t"])})
    for row, q in zip(rows, holm([r["p"] for r in rows])):
        row["p_holm"] = q
    return rows


def across_platforms(sweeps: list) -> list[dict]:
    """Each preset the file holds on a CPU and on a GPU at one length: the two entries' runs over
    their last LATE_STEPS (`halves`, each entry's own numbers), per policy both ran and measure
    (the late curiosity, the VAE loss per image, its reconstruction term and object contacts),
    the GPU's against the CPU's, Welch's two-sided t-test and Holm's correction over the table's
    tests: how far the machine alone moves the measures at the full length, where each entry's
    `platforms` table answers it over the committed runs' steps.

    [{"preset", "cpu", "gpu": the sweeps' names, "steps", "late_steps", "rows": [{"group",
    "measure", "what", "cpu", "gpu" (per run), "diff" (GPU - CPU), "t", "p", "p_holm"}]}]."""
    from mjx_curio.analysis.walls import MEASURES

    late = lambda e: {(h["group"], h["measure"]): h for h in e["halves"]}  # noqa: E731
    on = {entry_key(x): x for x in sweeps}
    out = []
    for (preset, platform), cpu in sorted(on.items()):
        gpu = on.get((preset, "gpu"))
        if platform != "cpu" or gpu is None or (cpu["steps"], cpu["late_steps"]) != (gpu["steps"], gpu["late_steps"]):
            continue
        rows = _against(late(cpu), late(gpu), "second", ("cpu", "gpu"), [key for key, _, _ in MEASURES])
        out.append({"preset": preset, "cpu": cpu["sweep"], "gpu": gpu["sweep"], "steps": cpu["steps"],
                    "late_steps": cpu["late_steps"], "rows": rows})
    return out


def _committed_one_against_two(one: dict, two: dict) -> dict | None:
    """One agent against two over the committed runs' last LATE_STEPS (each entry's `platforms`
    keeps those runs' measures, all their seeds): the same question where both sides ran on the
    committed runs' machines, so that the full length's difference of machine can be read against
    it. None where an entry lacks them or the two committed lengths differ."""
    if not all("platforms" in e and "committed" in e for e in (one, two)):
        return None
    if one["committed"]["steps"] != two["committed"]["steps"]:
        return None
    short = lambda e: {(r["group"], r["measure"]): r for r in e["platforms"]}  # noqa: E731
    return {"one": one["committed"]["sweep"], "two": two["committed"]["sweep"], "steps": one["committed"]["steps"],
            "rows": _two_against_one(short(one), short(two), "short")}


def _nan(v) -> float:
    """A JSON number back as a float, NaN for None."""
    return math.nan if v is None else float(v)


def with_one_against_two(doc: dict) -> dict:
    """`doc` (`merged`) with `one_against_two` of its sweeps: the `one_against_two` tables, and
    their claim 3 rows among the claims in place of those computed before from the two presets (a
    file written before it kept several pairs had one table, as `agents`); and the
    `across_platforms` tables of its presets on two platforms."""
    both = sorted([ONE, TWO])
    claims = [r for r in doc["claims"] if not (r["claim"] == "3" and sorted(r.get("presets", [])) == both)]
    out = {k: v for k, v in doc.items() if k not in ("agents", "one_against_two", "across_platforms")}
    tables = one_against_two(doc["sweeps"])
    claims += [t["claim"] for t in tables if t["claim"]]
    if tables:
        out["one_against_two"] = [{k: v for k, v in t.items() if k != "claim"} for t in tables]
    out["claims"] = _in_order(claims)
    platforms = across_platforms(doc["sweeps"])
    if platforms:
        out["across_platforms"] = platforms
    return out


def stands_for(assigned: dict) -> dict:
    """{(preset, platform): sweep} from `analysis.assign_presets`'s answer: a sweep named
    `<preset>.<label>` (`runs/paper/single_agent.full_length`), which the page keeps apart from its
    preset, is here the preset at its full length on the platform it ran on (`platform_of`).
    Several such sweeps of one preset on one platform, each of some of its policies
    (`single_agent.full_length` of ε-greedy, `single_agent.full_length_ucb` of UCB, each perhaps
    its seeds in parts that `assign_presets` has joined), stand for it as one
    (`analysis.merge_sweeps`; SweepError where they differ in more than their policies or repeat a
    run); on different platforms they are different entries (the main job on a GPU, a few of its
    runs again on a CPU)."""
    from mjx_curio import analysis as an

    parts: dict[tuple[str, str], list] = {}
    for key, sweep in assigned.items():
        platform = platform_of(sweep.manifest.get("device", {}))
        parts.setdefault((key.partition(".")[0], platform), []).append(sweep)
    return {key: ps[0] if len(ps) == 1 else an.merge_sweeps(ps, differ=("policies",))
            for key, ps in parts.items()}


def lost_runs(old: dict | None, longs: dict) -> list[str]:
    """What measuring `longs` ({(preset, platform): sweep}) anew would drop from the file `old`: per
    entry it holds (`entry_key`), each policy whose runs there outnumber the new sweep's (`merged`
    replaces an entry whole, and the metrics behind an entry, the main job's on a GPU, may not be
    on this machine to reduce again). Empty where nothing would be lost."""
    lost = []
    for e in (old or {}).get("sweeps", []):
        key = entry_key(e)
        if key not in longs:
            continue
        new = {g.label: len(g.indices) for g in longs[key].groups()}
        short = [f"{label}: {len(idx)} runs against {new.get(label, 0)}"
                 for label, idx in e["curves"]["groups"].items() if len(idx) > new.get(label, 0)]
        if short:
            lost.append(f"{key[0]} on {key[1].upper()} (`{e['sweep']}`; {', '.join(short)})")
    return lost


def _read(path: pathlib.Path) -> dict | None:
    """The full-length JSON as it is, to add to (`merged`); None where there is none yet."""
    if not path.exists():
        return None
    try:
        old = json.loads(path.read_text())
    except ValueError as err:
        raise ValueError(f"{path} is not JSON ({err}); move it aside to write a new one") from err
    if not isinstance(old, dict) or not {"claims", "sweeps"} <= set(old):
        raise ValueError(f"{path} has no claims and sweeps; move it aside to write a new one")
    return old


def main(argv: list[str]) -> int:
    sys.path.insert(0, str(ROOT / "experiments"))
    import results

    from mjx_curio import analysis as an
    from mjx_curio.cli import wants_help

    usage = __doc__.splitlines()[2].strip()
    if wants_help(argv):
        print(usage)
        return 0
    if not argv:
        print(f"full_length_evidence.py: want at least one sweep directory\n{usage}", file=sys.stderr)
        return 2
    try:
        sweeps = [an.load(a) for a in argv]
        longs = stands_for(an.assign_presets(sweeps))
        lost = [s.name for s in sweeps if not any(s is x or s in getattr(x, "parts", ()) for x in longs.values())]
        if lost:
            raise ValueError(f"{', '.join(lost)}: fits no preset, or one another sweep given already stands for")
        old = _read(OUT)  # a damaged file stops the script before the sweeps are reduced
        dropped = lost_runs(old, longs)
        if dropped:
            raise ValueError(f"{OUT} holds runs the sweeps given lack, which measuring them would drop: "
                             f"{'; '.join(dropped)}; give those runs' sweeps too, or move the file aside")
        entry = evidence(longs, results.load_presets())
    except (an.SweepError, ValueError) as err:
        print(f"full_length_evidence.py: {err}", file=sys.stderr)
        return 2
    entry = with_one_against_two(merged(old, entry))
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(entry, indent=1, allow_nan=False) + "\n")
    kept = [f"`{x['sweep']}` ({x['preset']} on {entry_key(x)[1].upper()})" for x in entry["sweeps"]
            if entry_key(x) not in longs]
    print(f"wrote {OUT}" + (f", keeping {', '.join(kept)}" if kept else "") + "\n")
    print(results.full_length_block(OUT))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
