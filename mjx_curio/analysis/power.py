"""Power: how many seeds each claim's test needs, and the smallest effect it can detect.

A verdict of "does not hold" at 3 seeds can mean that there is no effect or that 3 seeds cannot
see one. Each claim records the per-run values its tests compared (`claims.Tested`, oriented so
the paper's effect is positive); from their spread across runs this module gives, per test:

  seeds for 80 % power   the fewest seeds at which the test, run as the claim runs it (95% t
                         interval above the null, or Welch's t with p < 0.05 in the paper's
                         direction), would find the effect observed here with probability 0.8,
                         were that effect and that spread the truth;
  detectable effect      the smallest true effect the test finds with probability 0.8, at the
                         seeds the sweeps ran and at `PLANNED_SEEDS` (the main job's seeds=8);
  largest not ruled out  the one-sided 95 % upper confidence bound of the effect: what the runs
                         themselves allow, the complement of a test that found nothing.

A claim that needs every one of its tests to pass needs the most seeds any of them needs. The
spread comes from the runs themselves: with 3 seeds a standard deviation is uncertain by a factor
of about 0.5 to 6 (95 %), so read "seeds for 80 % power" as an order of magnitude, not a plan.

The power of a t test is a tail of the noncentral t distribution (`noncentral_t_sf`), integrated
here with NumPy alone, as the claims' own tests are. Imports `claims`, `significance` and `tables`.
"""

from __future__ import annotations

import math

import numpy as np

from mjx_curio.analysis.claims import ALPHA, Tested, claim_results
from mjx_curio.analysis.claims.common import _num
from mjx_curio.analysis.significance import (
    block_anova,
    equivalence_bound,
    finite,
    holm,
    t_critical,
    t_pvalue,
    welch_t,
)
from mjx_curio.analysis.tables import Table

POWER = 0.8
PLANNED_SEEDS = 8  # the main job, `python -m mjx_curio.sweep policies=eps,boltzmann,ucb seeds=8`
MAX_SEEDS = 10_000  # beyond this, "seeds for 80 % power" reads "> 10,000"

# Gauss-Legendre nodes on [-1, 1] for the integral over the t statistic's denominator.
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(256)


def noncentral_t_sf(c: float, df: float, ncp: float) -> float:
    """P(T > c) for T = (Z + ncp) / sqrt(V / df), Z standard normal, V chi-square with `df`
    (real, > 0) degrees of freedom: the noncentral t's upper tail. It is E[Phi(ncp - c U)] over
    U = sqrt(V / df), integrated by Gauss-Legendre over the range where U's density is not
    negligible (its mean is ~1, its spread ~1 / sqrt(2 df))."""
    if not (math.isfinite(c) and math.isfinite(ncp) and df > 0):
        return math.nan
    spread = 1.0 / math.sqrt(2.0 * df)
    lo, hi = max(0.0, 1.0 - 14.0 * spread), 1.0 + 14.0 * spread + 2.0 / df
    u = lo + (hi - lo) * (_NODES + 1.0) / 2.0
    w = _WEIGHTS * (hi - lo) / 2.0
    half = df / 2.0
    log_pdf = math.log(2.0) + half * math.log(half) - math.lgamma(half) + (df - 1.0) * np.log(u) - half * u * u
    phi = np.array([0.5 * math.erfc(-(ncp - c * ui) / math.sqrt(2.0)) for ui in u])
    return float(np.clip((w * np.exp(log_pdf) * phi).sum(), 0.0, 1.0))


def t_power(ncp: float, df: float, alpha: float = ALPHA) -> float:
    """Probability that a two-sided t test at level `alpha` comes out significant in the effect's
    own direction, for a true standardised effect `ncp` (effect / its standard error)."""
    return noncentral_t_sf(t_critical(df, alpha), df, ncp)


def design(tested: Tested, seeds: float) -> tuple[float, float]:
    """(standard error of the effect, degrees of freedom) of `tested`'s test with `seeds` seeds a
    group, each group's spread as observed."""
    n = seeds * tested.runs_per_seed
    if tested.blocked:
        # One temperature against another within the blocked design: the error variance is the
        # residual mean square of `block_anova`, with its degrees of freedom.
        a = block_anova(tested.x)
        return math.sqrt(2.0 * a["ms_error"] / seeds), (a["k"] - 1) * (seeds - 1)
    vx = _var(tested.x)
    if tested.y is None:
        return math.sqrt(vx / n), n - 1
    vy = _var(tested.y)
    df = (vx + vy) ** 2 * (n - 1) / (vx * vx + vy * vy) if vx + vy > 0 else math.nan
    return math.sqrt((vx + vy) / n), df


def effect(tested: Tested) -> float:
    """The observed effect in the paper's direction; for a blocked table, the largest difference
    between two treatments' means."""
    if tested.blocked:
        y = _complete_blocks(tested.x)
        means = y.mean(axis=1) if y.size else np.array([math.nan])
        return float(means.max() - means.min())
    x = finite(tested.x)
    if tested.y is None:
        return float(x.mean() - tested.null) if len(x) else math.nan
    y = finite(tested.y)
    return float(x.mean() - y.mean()) if len(x) and len(y) else math.nan


def seeds_now(tested: Tested) -> int:
    """The seeds a group ran: complete blocks, or finite runs (the smaller side) per seed."""
    if tested.blocked:
        return block_anova(tested.x)["b"]
    n = len(finite(tested.x)) if tested.y is None else min(len(finite(tested.x)), len(finite(tested.y)))
    return n // tested.runs_per_seed


def seeds_needed(tested: Tested, target: float = POWER) -> float:
    """The fewest seeds a group at which the test finds the observed effect with probability
    `target`, the observed spread taken as the truth: NaN for an effect <= 0 (the other way from
    the paper's) or a claim of no difference, inf beyond `MAX_SEEDS`."""
    d = effect(tested)
    if tested.blocked or not d > 0:
        return math.nan

    def enough(seeds: int) -> bool:
        se, df = design(tested, seeds)
        return se == 0 or t_power(d / se, df) >= target

    lo = 2 if tested.runs_per_seed == 1 else 1  # the fewest seeds that give a test at all
    if enough(lo):
        return float(lo)
    hi = lo
    while not enough(hi):  # power grows with the seeds: double, then halve the bracket
        lo, hi = hi, 2 * hi
        if hi > MAX_SEEDS:
            return math.inf
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (lo, mid) if enough(mid) else (mid, hi)
    return float(hi)


def detectable(tested: Tested, seeds: float, target: float = POWER) -> float:
    """The smallest true effect the test finds with probability `target` at `seeds` seeds a group
    (the observed spread taken as the truth): the standardised effect that gives that power, times
    the effect's standard error."""
    se, df = design(tested, seeds)
    if se == 0:
        return 0.0  # no spread: any effect is found
    if not (math.isfinite(se) and df > 0):
        return math.nan
    lo, hi = 0.0, 1.0
    while t_power(hi, df) < target:
        lo, hi = hi, 2.0 * hi
    for _ in range(60):
        mid = (lo + hi) / 2.0
        lo, hi = (mid, hi) if t_power(mid, df) < target else (lo, mid)
    return se * (lo + hi) / 2.0


def largest_allowed(tested: Tested, alpha: float = ALPHA) -> float:
    """The largest effect in the paper's direction that the runs do not rule out: the one-sided
    (1 - `alpha`) upper confidence bound of the effect, effect + t(1 - alpha, df) x its standard
    error (one sample: sd / sqrt(n) on n - 1 degrees of freedom; two: Welch's). Below 0 the
    paper's direction itself is ruled out. For a blocked claim of no difference, the
    `significance.equivalence_bound`: the largest difference between two treatments not ruled
    out. Where a test finds nothing, this says how much it could have missed, from the data
    alone; `detectable` says it from the spread, before looking at the effect."""
    if tested.blocked:
        return equivalence_bound(tested.x, alpha)["bound"]
    if tested.y is None:
        se, df = _one_sample(tested)
    else:
        w = welch_t(tested.x, tested.y)
        if w["nx"] >= 2 and w["ny"] >= 2 and not math.isfinite(w["se"]):
            return effect(tested)  # no spread on either side: the effect is known exactly
        se, df = w["se"], w["df"]
    if not (math.isfinite(se) and math.isfinite(df)):
        return math.nan
    return effect(tested) + t_critical(df, 2.0 * alpha) * se


def p_value(tested: Tested) -> float:
    """The two-sided p-value of `tested`'s own test: one sample, Student's t of mean(x) - null;
    two, Welch's t. NaN for a blocked claim of no difference, whose verdict a small p would turn
    against the paper, so that a correction for many tests would favour it."""
    if tested.blocked:
        return math.nan
    if tested.y is not None:
        return welch_t(tested.x, tested.y)["p"]
    se, df = _one_sample(tested)
    d = effect(tested)
    if se == 0:
        return 0.0 if d != 0 else math.nan
    return t_pvalue(d / se, df)


def standardised_effect(tested: Tested, alpha: float = ALPHA) -> tuple[float, float, float]:
    """(d, low, high): the effect in units of the spread across runs (Cohen's d, the paper's
    direction positive) and its two-sided (1 - `alpha`) interval, (effect -+ t x se) / sd, where sd
    is the runs' standard deviation (two samples: the root of the mean of the two variances) and
    se and t the test's own (Student's t of one sample, Welch's of two). A common axis for tests
    of different measures; NaN for a blocked claim of no difference and where there is no spread."""
    if tested.blocked:
        return math.nan, math.nan, math.nan
    if tested.y is None:
        se, df = _one_sample(tested)
        sd = math.sqrt(_var(tested.x))
    else:
        w = welch_t(tested.x, tested.y)
        se, df = w["se"], w["df"]
        sd = math.sqrt((_var(tested.x) + _var(tested.y)) / 2.0)
    if not (math.isfinite(se) and math.isfinite(df) and sd > 0):
        return math.nan, math.nan, math.nan
    d, half = effect(tested), t_critical(df, alpha) * se
    return d / sd, (d - half) / sd, (d + half) / sd


def _one_sample(tested: Tested) -> tuple[float, float]:
    """(standard error, degrees of freedom) of a one-sample test's mean over the runs it has;
    NaN below 2 runs."""
    x = finite(tested.x)
    if len(x) < 2:
        return math.nan, math.nan
    return float(x.std(ddof=1)) / math.sqrt(len(x)), len(x) - 1


def power_table(sweeps) -> Table:
    """One row per test a claim's verdict rests on: the observed effect (the paper's direction
    positive) and the spread across runs, the largest effect the runs do not rule out
    (`largest_allowed`), the seeds the sweeps ran, the seeds for 80 % power at the observed
    effect, and the smallest effect detectable with 80 % power now and at `PLANNED_SEEDS`; and each
    test's two-sided p (`p_value`) with Holm's adjustment over every test of the table (`holm`)."""
    cols = ["#", "verdict", "test", "observed effect", "sd across runs", "largest not ruled out (95 %)",
            "p (Holm)", "seeds", "seeds for 80 % power", "detectable now", f"detectable at {PLANNED_SEEDS} seeds"]
    rows, values = [], []
    for r in claim_results(sweeps):
        for label, t in r.tests.items():
            d, now, need = effect(t), seeds_now(t), seeds_needed(t)
            if now < 2:
                continue
            mde_now, mde_planned = detectable(t, now), detectable(t, PLANNED_SEEDS)
            sd = _spread(t)
            bound = largest_allowed(t)
            rows.append([r.key, r.verdict.split(":")[0].split(" (")[0], label, _g(d), sd, _g(bound), "", str(now),
                         _seeds(t, d, need), _g(mde_now), _g(mde_planned)])
            std = standardised_effect(t)
            values.append({"key": r.key, "verdict": rows[-1][1], "test": label, "effect": _num(d),
                           "d": _num(std[0]), "d_low": _num(std[1]), "d_high": _num(std[2]),
                           "largest_allowed": _num(bound),
                           "p": _num(p_value(t)), "seeds": now, "seeds_needed": _num(need),
                           "detectable_now": _num(mde_now), "detectable_planned": _num(mde_planned)})
    adjusted = holm([math.nan if v["p"] is None else v["p"] for v in values])
    for row, v, q in zip(rows, values, adjusted):
        v["p_holm"] = _num(q)
        row[6] = "n/a" if v["p"] is None else f"{_pv(v['p'])} ({_pv(q)})"
    note = ("Seeds are per group (a policy or setting; the tests that pool every policy of a sweep count a "
            "seed once, its runs of every policy together). Observed effect: in the paper's direction (negative: "
            "the other way); claim 7's is the largest difference between two temperatures, and its detectable "
            "effect a difference between two temperatures in the blocked design. Largest not ruled out: the "
            "one-sided 95 % upper confidence bound of the effect (below 0: the paper's direction is ruled out; "
            "claim 7: the equivalence bound, the largest difference between two temperatures two one-sided tests "
            "at 5 % do not rule out). p (Holm): the test's two-sided p, and in brackets adjusted by Holm's method "
            "over every test of the table (claim 7's excepted: a correction would favour its claim of no "
            "difference). Power: the chance that the "
            "claim's own test (95 % interval above the null, or Welch's t, p < 0.05, in the paper's direction) "
            "finds an effect, the spread across runs taken as the truth; with 3 seeds that spread is itself "
            "uncertain by a factor of about 0.5 to 6.")
    return Table(cols, rows, values, note)


# ---------------------------------------------------------------------------------- helpers


def _var(x) -> float:
    x = finite(x)
    return float(x.var(ddof=1)) if len(x) >= 2 else math.nan


def _complete_blocks(table) -> np.ndarray:
    y = np.asarray(table, float)
    return y[:, np.isfinite(y).all(axis=0)]


def _spread(t: Tested) -> str:
    if t.blocked:
        return f"{_g(math.sqrt(block_anova(t.x)['ms_error']))} (residual)"
    if t.y is None:
        return _g(math.sqrt(_var(t.x)))
    return f"{_g(math.sqrt(_var(t.x)))}, {_g(math.sqrt(_var(t.y)))}"


def _seeds(t: Tested, d: float, need: float) -> str:
    if t.blocked:
        return "n/a (a claim of no difference)"
    if not math.isfinite(d):
        return "n/a"
    if d < 0:
        return "none: the effect goes the other way"
    if d == 0:
        return "none: no effect observed"
    return f"> {MAX_SEEDS:,}" if math.isinf(need) else f"{int(need):,}"


def _pv(p: float) -> str:
    return "< 0.0001" if p < 1e-4 else f"{p:.2g}"


def _g(x: float) -> str:
    x = float(x)
    if not math.isfinite(x):
        return "n/a"
    return f"{x:,.0f}" if abs(x) >= 100 else f"{x:.3g}"

