"""The results page's block of the paper's full length, from docs/results/full_length.json
(which `full_length_evidence.py` writes): the claims each full-length sweep can test, per sweep
its runs beside the committed ones and its second half against its first, a preset on both
platforms, one agent against two (claim 3), and their figures. `results.py` puts the block and
the figures on the page; `full_length_curves` also gives its table of the paper's numbers a
column for these runs.
"""

from __future__ import annotations

import json
import pathlib
import textwrap

import numpy as np

FULL_LENGTH = pathlib.Path(__file__).resolve().parents[1] / "docs" / "results" / "full_length.json"
ONE_AGAINST_TWO = "full_length_one_against_two"  # the figure of one agent against two
STYLE_WORDS = {"-": "solid", "--": "dashed", ":": "dotted", "-.": "dash-dotted"}  # its captions name line styles


def _device(d: dict | list) -> str:
    """'one NVIDIA H200', 'a CPU (AMD EPYC)' or, for a sweep merged from parts, 'CPUs (AMD EPYC, ...)'."""
    ds = d if isinstance(d, list) else [d]
    if all(x.get("platform") == "gpu" for x in ds) and len({x.get("kind") for x in ds}) == 1:
        return f"one {ds[0]['kind']}" if len(ds) == 1 else f"{ds[0]['kind']}s"
    names = list(dict.fromkeys(x.get("cpu", "?") for x in ds))
    return f"a CPU ({names[0]})" if len(names) == 1 and len(ds) == 1 else f"CPUs ({', '.join(names)})"


def _mean(xs) -> float:
    v = [x for x in xs if x is not None]
    return sum(v) / len(v) if v else float("nan")


def _p(v) -> str:
    return f"{v:.2g}" if v is not None else "—"


def full_length_block(path: pathlib.Path = FULL_LENGTH) -> str:
    """Markdown of full_length.json (`full_length_evidence.py`): the claims at the full run length,
    then per sweep the same runs on two platforms, the second half against the first, and its
    figures."""
    if not path.exists():
        return "No sweep of the paper's full length has been measured yet (`experiments/full_length_evidence.py`).\n"
    e = json.loads(path.read_text())
    names = ", ".join(f"`{x['sweep']}` ({x['preset']}, {x['steps']:,} steps on {_device(x['device'])})"
                      for x in e["sweeps"])
    several = len(e["sweeps"]) > 1
    joint = {r["claim"] for r in e["claims"] if len(r.get("presets", [])) > 1}
    together = (", and claim 3 each one-agent and two-agent sweep of one length together" if joint else "") + (
        " (claim 14 those that ran on one platform, from their VAE losses' course)" if "14" in joint else "")
    lines = [f"The claims that {'each of ' if several else ''}the full-length sweep{'s' if several else ''} {names} "
             f"can test by itself{together} (the claims table above has them at the committed runs' length):", "",
             "| # | claim | our statistic | verdict |", "|---|---|---|---|"]
    lines += [f"| {r['claim']} | {r['text']} | {r['statistic']} | {r['verdict']} |" for r in e["claims"]]
    if not any(r["claim"] == "15" for r in e["claims"]):
        lines += [row for x in e["sweeps"] for row in _agent_contact_order_row(x)]
    for x in e["sweeps"]:
        lines += ["", *_full_length_sweep(x)]
    for t in e.get("across_platforms", []):
        lines += ["", *_across_platforms(t, {x["sweep"]: x for x in e["sweeps"]})]
    pairs = e.get("one_against_two", [])
    for a, show in zip(pairs, _committed_shown(pairs)):
        lines += ["", *_one_against_two(a, {x["sweep"]: x for x in e["sweeps"]}, committed=show)]
    if e.get("one_against_two"):
        ones, twos = _one_against_two_styles(e["one_against_two"])
        said = lambda sides: "; ".join(f"`{name}`, {STYLE_WORDS[style]}" for name, style in sides)  # noqa: E731
        lines += ["", f"![{ONE_AGAINST_TWO}](figures/results/{ONE_AGAINST_TWO}.png)", "",
                  f"*Curiosity in bins of {e['sweeps'][0]['curves']['bin_steps']:,} steps, mean over seeds with its "
                  f"95 % CI: one agent ({said(ones)}) and two (the mean of the agents; {said(twos)}), the paper's "
                  "fig. 23 at its full length; shaded, the steps the table"
                  f"{'s' if len(e['one_against_two']) > 1 else ''} compare{'' if len(e['one_against_two']) > 1 else 's'}.*"]
    return "\n".join(lines) + "\n"


def _measure_formats() -> dict:
    """{measure: its number format} of the full-length tables' measures (`analysis.walls.MEASURES`)."""
    from mjx_curio.analysis.walls import MEASURES

    return {key: fmt for key, _, fmt in MEASURES}


def _committed_shown(pairs: list) -> list[bool]:
    """Whether each one-against-two pair sets out its table of the committed runs: once for pairs
    that share it (the same two presets, length, policies and measures), again for a pair whose
    full-length sweeps ran other policies, as its committed runs' rows differ."""
    shown, out = set(), []
    for a in pairs:
        c = a.get("committed")
        key = c and (c["one"], c["two"], c["steps"], tuple((r["group"], r["measure"]) for r in c["rows"]))
        out.append(key not in shown)
        shown.add(key)
    return out


def _one_against_two(a: dict, sweeps: dict, committed: bool = True) -> list[str]:
    """A one-agent sweep against a two-agent one at the full length (a table of `one_against_two` in
    full_length_evidence.py): claim 3's measures over the last steps, per policy both ran; each
    run's change in them over the second half, where the file has it; then, where `committed`,
    the same over the committed runs."""
    one, two = sweeps[a["one"]], sweeps[a["two"]]
    lo, hi = a["steps"] - a["late_steps"], a["steps"]
    n = sum(r["p"] is not None for r in a["rows"])

    def table(entries) -> list[str]:
        return ["| policy | measure | one agent | two agents | difference | p | p (Holm) |", "|---|---|---|---|---|---|---|",
                *_measure_rows(entries, "one", "two", counts=True)]

    same = _device(one["device"]) == _device(two["device"])  # the machines as the reader sees them named
    c = a.get("committed") if committed else None
    below = [] if not c else [
        f"The same over the committed runs' last {a['late_steps']:,} steps (steps {c['steps'] - a['late_steps']:,}-"
        f"{c['steps']:,}): `{c['one']}` on {_device(one['committed']['devices'])} against `{c['two']}` on "
        f"{_device(two['committed']['devices'])}, all their seeds, Holm's correction over the table's "
        f"{sum(r['p'] is not None for r in c['rows'])} tests:", "", *table(c["rows"])]
    ch = a.get("changes")
    changes = [] if not ch else [
        f"What the second half changes, two agents against one: each run's change in the same measures from steps "
        f"{ch['steps'][0]:,}-{ch['steps'][1]:,} to {lo:,}-{hi:,} (the table of each sweep's halves above, run by "
        "run), means over seeds (how many in brackets), the difference two agents minus one, Welch's two-sided "
        f"t-test, and Holm's correction over the table's {sum(r['p'] is not None for r in ch['rows'])} tests; fig. "
        "24's two-agent VAE loss \"fails to converge\", which would read here as a smaller fall (context, not the "
        "claim's verdict):", "", *table(ch["rows"])]
    return [f"One agent against two at the full length (claim 3, figs. 23 and 24): `{a['one']}` on "
            f"{_device(one['device'])} against `{a['two']}` on {_device(two['device'])}, the curiosity, the VAE "
            f"loss per image and its reconstruction term over steps {lo:,}-{hi:,}, per policy both ran (the claim's "
            "verdict is on UCB's, the paper's choice); means over seeds (how many in brackets), the difference two "
            f"agents minus one, Welch's two-sided t-test, and Holm's correction over the table's {n} tests"
            + ("" if same else "; the two ran on different machines, and each sweep's first table above (and, "
               "where a preset ran on both, its table on both platforms) says how far the machine alone moves "
               "these measures") + ":", "",
            *table(a["rows"]), *([""] + changes if changes else []), *([""] + below if below else [])]


def _across_platforms(t: dict, sweeps: dict) -> list[str]:
    """A preset on a CPU and on a GPU at the full length (a table of `across_platforms` in
    full_length_evidence.py): the measures over the last steps, per policy both ran."""
    cpu, gpu = _device(sweeps[t["cpu"]]["device"]), _device(sweeps[t["gpu"]]["device"])
    n = sum(r["p"] is not None for r in t["rows"])
    return [f"{t['preset']} on both platforms at the full length: `{t['gpu']}` on {gpu} against `{t['cpu']}` on "
            f"{cpu}, the curiosity, the VAE loss per image, its reconstruction term and object contacts per 1,000 "
            f"agent-steps over steps {t['steps'] - t['late_steps']:,}-{t['steps']:,}, per policy both ran; means "
            "over seeds (how many in brackets), the difference GPU minus CPU, Welch's two-sided t-test, and Holm's "
            f"correction over the table's {n} tests:", "",
            f"| policy | measure | {cpu} | {gpu} | difference | p | p (Holm) |", "|---|---|---|---|---|---|---|",
            *_measure_rows(t["rows"], "cpu", "gpu", counts=True)]


def _measure_rows(entries: list, left: str, right: str, counts: bool = False) -> list[str]:
    """Table rows of the full-length file's per-run measures (`platforms`, `halves`, `agents`):
    policy, measure, each side's mean over runs (and how many, where `counts`), the difference,
    p and Holm's p."""
    fmt = _measure_formats()
    out = []
    for r in entries:
        f = fmt.get(r["measure"], ".3g")
        d = f"{r['diff']:+{f}}" if r["diff"] is not None else "—"
        n = {side: f" ({len(r[side])})" if counts else "" for side in (left, right)}
        out.append(f"| {r['group']} | {r['what']} | {_mean(r[left]):{f}}{n[left]} | {_mean(r[right]):{f}}{n[right]} "
                   f"| {d} | {_p(r['p'])} | {_p(r['p_holm'])} |")
    return out


def _full_length_sweep(e: dict) -> list[str]:
    c = e["committed"]
    late = e["late_steps"]
    a, b = c["steps"] - late, c["steps"]
    n = sum(r["p"] is not None for r in e["platforms"])
    m = sum(r["p"] is not None for r in e["halves"])
    name = _figure_name(e)
    lines = [f"`{e['sweep']}` ({e['preset']}): {e['runs']} runs × {e['steps']:,} steps on {_device(e['device'])}, beside the "
             f"committed runs `{c['sweep']}` ({c['runs']} runs × {c['steps']:,} steps on {_device(c['devices'])}).", "",
             f"{_same_runs(e)} in the two sets of runs, over the steps both ran: curiosity, the VAE loss "
             f"per image and its reconstruction term over steps {a:,}-{b:,}, object contacts per 1,000 agent-steps "
             f"over 0-{b:,}; means over seeds, Welch's two-sided t-test, and Holm's correction over the table's "
             f"{n} tests:", "",
             f"| policy | measure | {_device(e['device'])} | {_device(c['devices'])} | difference | p | p (Holm) |",
             "|---|---|---|---|---|---|---|", *_measure_rows(e["platforms"], "long", "short"), "",
             f"What the second half of the run changes: the same measures, object contacts too, over steps "
             f"{e['steps'] - late:,}-{e['steps']:,} against {a:,}-{b:,}, run by run; the paired two-sided t-test, "
             f"Holm over {m} tests:", "",
             f"| policy | measure | steps {a:,}-{b:,} | steps {e['steps'] - late:,}-{e['steps']:,} | difference | p "
             "| p (Holm) |", "|---|---|---|---|---|---|---|", *_measure_rows(e["halves"], "first", "second"), "",
             *_contact_timing(e),
             f"![{name}_curiosity](figures/results/{name}_curiosity.png)", "",
             f"*Curiosity{' (the mean of the agents)' if e['agents'] > 1 else ''} in bins of "
             f"{e['curves']['bin_steps']:,} steps, mean over seeds "
             f"with its 95 % CI: the {e['runs']} runs of {e['steps']:,} steps (solid) and the committed runs of "
             f"{c['steps']:,} (dashed).*", "",
             f"![{name}_interactions](figures/results/{name}_interactions.png)", "",
             "*Contact steps summed from the start, "
             + ("agent-object (both agents) and agent-agent, mean over seeds with its 95 % CI, per policy: the "
                "paper's figs. 21 and 22 at their full length, in contact steps rather than normalised"
                if e["agents"] > 1 else
                "agent-object (all four objects), mean over seeds with its 95 % CI, per policy: the paper's fig. 9 "
                "at its full length, summed over the objects")
             + f"; the {e['runs']} runs of {e['steps']:,} steps (solid) and the committed runs of {c['steps']:,} "
             "(dashed).*"]
    return lines


def _figure_name(e: dict) -> str:
    """The stem of a full-length entry's figures: its preset and platform (`full_length_multi_agent_gpu`),
    as the file may hold a preset on a CPU and on a GPU."""
    return f"full_length_{e['preset']}_{e['platform']}"


def _same_runs(e: dict) -> str:
    """What a full-length sweep's runs have in common with the committed ones they are set beside:
    the same seeds, or (a sweep of fewer) the same settings, with the seeds each side has."""
    cv = e["curves"]
    long = {label: len(idx) for label, idx in cv["groups"].items()}
    short = {label: len(cv["short"]["groups"][label]) for label in long}
    if long == short:
        return "The same settings and seeds"
    return "The same settings (" + "; ".join(f"{label}: {long[label]} against {short[label]} seeds"
                                              for label in long) + ")"


def _agent_contact_order_row(e: dict) -> list[str]:
    """Claim 15's row of the full-length claims table, from a two-agent sweep's cumulative
    agent-agent contact curves (their last point is each run's total, what the claim counts), for
    a full_length.json written before the claim existed; empty where the sweep is too short."""
    from mjx_curio.analysis.claims import AGENT_PHASE_STEPS, agent_contact_order, claim_boltzmann_agents_meet

    cv = e["curves"]
    policies = _policy_groups(cv["groups"])
    if e["agents"] < 2 or cv["long"]["steps"][-1] < AGENT_PHASE_STEPS or not {"eps", "boltzmann", "ucb"} <= set(policies):
        return []  # the claim sets Boltzmann against ε-greedy, each as a share of UCB: a sweep of all three
    totals = np.asarray([r[-1] for r in cv["long"]["agent_contacts"]], float)
    d = agent_contact_order({p: totals[idx] for p, idx in policies.items()})
    claim = claim_boltzmann_agents_meet({}).claim  # its wording; with no sweep it tests nothing
    return [f"| 15 | {claim} | {e['sweep']} (from its cumulative contact curves): {d['text']} | {d['verdict']} |"]


def _policy_groups(groups: dict) -> dict:
    """A full-length JSON's groups ({label: run indices}, one group a policy) as {policy: run
    indices}."""
    from mjx_curio.analysis import POLICY_LABELS

    policy = {label: p for p, label in POLICY_LABELS.items()}
    return {policy[label.split(" (")[0]]: idx for label, idx in groups.items()}


def full_length_curves(path: pathlib.Path = FULL_LENGTH) -> tuple[dict, str]:
    """full_length.json's runs as `analysis.paper_numbers_table` takes them, {preset: (curves,
    {policy: run indices})}, and a label naming them; ({}, "") where there is none. Of a preset
    the file holds on two platforms, the entry of more runs (the main job on a GPU, not a few of
    its runs on a CPU)."""
    if not path.exists():
        return {}, ""
    most = {}
    for e in json.loads(path.read_text())["sweeps"]:
        if e["runs"] > most.get(e["preset"], {"runs": -1})["runs"]:
            most[e["preset"]] = e
    sweeps = list(most.values())
    long = {e["preset"]: (e["curves"]["long"], _policy_groups(e["curves"]["groups"])) for e in sweeps}
    return long, " and ".join(f"`{e['sweep']}`, {e['steps']:,} steps on {_device(e['device'])}" for e in sweeps)

def _contact_timing(e: dict) -> list[str]:
    """When a full-length sweep's agent-object contacts come, per policy, from its cumulative
    curves: contact steps (all agents) per 1,000 steps before and after claim 13's onset (fig. 9),
    the rise with its one-sample t-test, the share of the run's contacts made by 40,000 steps and
    the runs still touching after 30,000 (fig. 21). Empty where the run is too short for them."""
    from mjx_curio import analysis as an
    from mjx_curio.analysis.claims import CONTACT_ONSET

    cv = e["curves"]
    steps = list(cv["long"]["steps"])
    marks = (CONTACT_ONSET, 30_000, 40_000)
    if not all(m in steps for m in marks) or steps[-1] <= 40_000:
        return []
    onset, thirty, forty = (steps.index(m) for m in marks)
    cum = np.asarray(cv["long"]["object_contacts"], float)
    lines = [f"When the agent-object contacts come (figs. 9 and 21 at the full length): contact steps of all agents "
             f"per 1,000 agent-steps before step {CONTACT_ONSET:,} and after it, the rise (claim 13's measure; "
             "mean over runs [95 % CI], one-sample two-sided t-test), the share of a run's contacts made by step "
             "40,000, and the runs that still touch an object after step 30,000:", "",
             f"| policy | before {CONTACT_ONSET:,} | after | rise | p | share by 40,000 | runs touching after 30,000 |",
             "|---|---|---|---|---|---|---|"]
    for label, idx in cv["groups"].items():
        x = cum[idx]
        before = x[:, onset] / (CONTACT_ONSET / 1000)
        after = (x[:, -1] - x[:, onset]) / ((steps[-1] - CONTACT_ONSET) / 1000)
        rise, share = an.mean_ci(after - before), an.mean_ci(100 * x[:, forty] / x[:, -1])
        p = an.p_value(an.Tested(after - before))
        lines.append(f"| {label} | {before.mean():.1f} | {after.mean():.1f} | {rise[0]:.1f} [{rise[1]:.1f}, "
                     f"{rise[2]:.1f}] | {_p(p)} | {share[0]:.0f} % [{share[1]:.0f}, {share[2]:.0f}] | "
                     f"{int((x[:, -1] - x[:, thirty] > 0).sum())} of {len(idx)} |")
    return lines + [""]


def full_length_figure(path: pathlib.Path, out: pathlib.Path, dpi: int) -> None:
    """Per sweep of full_length.json, `out`/full_length_<preset>_<platform>_curiosity.png at `dpi`
    (a panel a policy) and ..._interactions.png (object contacts, and agent contacts where there
    are two agents); where it sets one agent against two, their curiosity
    (`_one_against_two_figure`)."""
    if not path.exists():
        return
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mjx_curio import analysis as an

    doc = json.loads(path.read_text())
    for e in doc["sweeps"]:
        cv = e["curves"]
        groups = list(cv["groups"])
        sides = (("long", cv["groups"], "-", _device(e["device"])),
                 ("short", cv["short"]["groups"], "--", _device(e["committed"]["devices"])))
        # at least 7 inches: the legend names the committed runs' CPUs
        fig, axes = plt.subplots(1, len(groups), figsize=(max(4.0 * len(groups), 7.0), 3.2), sharey=True, squeeze=False)
        for ax, label in zip(axes[0], groups):
            for side, groups_of, style, dev in sides:
                _band(ax, cv[side], groups_of[label], "runs", style,
                      label=_legend_label(f"{dev}, {len(groups_of[label])} seeds"))
            ax.set_title(label, fontsize=9)
            ax.set_xlabel("agent step (thousands)")
            ax.legend(fontsize=7)
        axes[0][0].set_ylabel("curiosity")
        fig.tight_layout()
        an.save_figure(fig, out, f"{_figure_name(e)}_curiosity", dpi=dpi)
        plt.close(fig)
        kinds = [("object_contacts", "agent-object contacts")] + (
            [("agent_contacts", "agent-agent contacts")] if e["agents"] > 1 else [])
        fig, axes = plt.subplots(1, len(kinds), figsize=(4.5 * len(kinds), 3.4), squeeze=False)
        colours = dict(zip(groups, plt.rcParams["axes.prop_cycle"].by_key()["color"]))
        for ax, (key, title) in zip(axes[0], kinds):
            for label in groups:
                for side, groups_of, style, _ in sides:
                    _band(ax, cv[side], groups_of[label], key, style, colours[label], label if side == "long" else None)
            ax.set_title(title, fontsize=9)
            ax.set_xlabel("agent step (thousands)")
        axes[0][0].set_ylabel("contact steps since the start")
        axes[0][0].legend(fontsize=7)
        fig.tight_layout()
        an.save_figure(fig, out, f"{_figure_name(e)}_interactions", dpi=dpi)
        plt.close(fig)
    if doc.get("one_against_two"):
        _one_against_two_figure(doc, out, dpi)


def _band(ax, curve, indices, key, style, colour=None, label=None):
    """A full-length curve's runs `indices` (`curve[key]`, one list a run, at `curve["steps"]`)
    as their mean and its 95 % CI."""
    from mjx_curio import analysis as an

    y = np.asarray([curve[key][i] for i in indices], dtype=float)
    mean, lo, hi, _ = an.mean_ci(y)
    x = np.asarray(curve["steps"]) / 1000
    line, = ax.plot(x, mean, style, color=colour, lw=1.2, label=label)
    ax.fill_between(x, lo, hi, color=line.get_color(), alpha=0.2, lw=0)


def _legend_label(text: str) -> str:
    """A legend entry in lines of at most 45 characters: a list of CPU models in one line would
    widen the legend past its panel."""
    return textwrap.fill(text, 45)


def _one_against_two_styles(tables: list) -> tuple[list, list]:
    """The sweeps of full_length.json's `one_against_two` tables with their line styles in
    `ONE_AGAINST_TWO`'s figure: ([(one-agent sweep, style)], [(two-agent sweep, style)]); one
    agent solid, two dashed, a second two-agent sweep dotted."""
    ones = [(name, "-") for name in dict.fromkeys(a["one"] for a in tables)]
    twos = [(name, ("--", ":", "-.")[k % 3]) for k, name in enumerate(dict.fromkeys(a["two"] for a in tables))]
    return ones, twos


def _one_against_two_figure(doc: dict, out: pathlib.Path, dpi: int) -> None:
    """`out`/full_length_one_against_two.png: the curiosity of every full-length
    sweep that `one_against_two` sets one agent against two with (the mean of its agents), a
    panel a policy some pair ran: fig. 23 at the full length. One agent solid, two dashed, a
    second two-agent sweep dotted."""
    import matplotlib.pyplot as plt

    from mjx_curio import analysis as an

    tables = doc["one_against_two"]
    by = {x["sweep"]: x for x in doc["sweeps"]}
    groups = list(dict.fromkeys(r["group"] for a in tables for r in a["rows"]))
    ones, twos = _one_against_two_styles(tables)
    styles = ones + twos
    fig, axes = plt.subplots(1, len(groups), figsize=(max(4.0 * len(groups), 7.0), 3.2), sharey=True, squeeze=False)
    for ax, label in zip(axes[0], groups):
        for name, style in styles:
            e = by[name]
            idx = e["curves"]["groups"].get(label)
            if idx is None:  # a sweep of some of the policies
                continue
            _band(ax, e["curves"]["long"], idx, "runs", style,
                  label=_legend_label(f"{e['agents']} agent{'s' if e['agents'] > 1 else ''}, {len(idx)} seeds, "
                                      f"{_device(e['device'])}"))
        a = tables[0]
        ax.axvspan((a["steps"] - a["late_steps"]) / 1000, a["steps"] / 1000, color="0.9", lw=0)
        ax.set_title(label, fontsize=9)
        ax.set_xlabel("agent step (thousands)")
        ax.legend(fontsize=7)
    axes[0][0].set_ylabel("curiosity")
    fig.tight_layout()
    an.save_figure(fig, out, ONE_AGAINST_TWO, dpi=dpi)
    plt.close(fig)
