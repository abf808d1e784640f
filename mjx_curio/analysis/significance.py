"""Significance tests in NumPy and the standard library: Student t and F tails and the t a test must
exceed, Welch's t, one-way and block ANOVA, equivalence bounds (two one-sided tests), Holm's
adjustment for many tests, Pearson's r and Fisher's z.

The tails come from the regularised incomplete beta function (`betainc`, a continued fraction),
so the analysis needs no SciPy; the tests check them against closed forms and hand computations.
The claims (`claims/`), the power of their tests (`power.py`) and the
measure-by-measure tables (`temperatures.py`, `walls.py`) use them. Imports nothing of the package.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np


def finite(x) -> np.ndarray:
    """`x` flattened, without its NaNs and infinities."""
    x = np.asarray(x, float).reshape(-1)
    return x[np.isfinite(x)]


def betainc(a: float, b: float, x: float) -> float:
    """Regularised incomplete beta function I_x(a, b), by its continued fraction (modified Lentz;
    the symmetry I_x(a, b) = 1 - I_{1-x}(b, a) keeps the fraction where it converges fast)."""
    if not (a > 0 and b > 0) or not np.isfinite(x):
        return math.nan
    if x <= 0:
        return 0.0
    if x >= 1:
        return 1.0
    log_front = math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b) + a * math.log(x) + b * math.log1p(-x)
    if x > (a + 1) / (a + b + 2):
        return 1.0 - betainc(b, a, 1.0 - x)
    tiny, eps = 1e-300, 1e-15
    c, d = 1.0, 1.0 - (a + b) * x / (a + 1)
    d = 1.0 / (d if abs(d) > tiny else tiny)
    h = d
    for m in range(1, 10_000):
        for num in (m * (b - m) * x / ((a + 2 * m - 1) * (a + 2 * m)),
                    -(a + m) * (a + b + m) * x / ((a + 2 * m) * (a + 2 * m + 1))):
            d = 1.0 + num * d
            d = 1.0 / (d if abs(d) > tiny else tiny)
            c = 1.0 + num / c
            c = c if abs(c) > tiny else tiny
            h *= c * d
        if abs(c * d - 1.0) < eps:
            break
    return math.exp(log_front) * h / a


def t_pvalue(t: float, df: float) -> float:
    """Two-sided p-value of Student's t with `df` (real) degrees of freedom: P(|T| >= |t|)."""
    if not (np.isfinite(t) and np.isfinite(df) and df > 0):
        return math.nan
    return betainc(df / 2.0, 0.5, df / (df + t * t))


def f_pvalue(f: float, df1: float, df2: float) -> float:
    """Upper tail of the F distribution: P(F >= f) with (df1, df2) degrees of freedom."""
    if not (np.isfinite(f) and df1 > 0 and df2 > 0):
        return math.nan
    if f <= 0:
        return 1.0
    return betainc(df2 / 2.0, df1 / 2.0, df2 / (df2 + df1 * f))


def t_critical(df: float, alpha: float = 0.05) -> float:
    """The t a two-sided test at level `alpha` must exceed: P(|T| >= t) = alpha, `df` real."""
    if not (df > 0 and math.isfinite(df)):
        return math.nan
    lo, hi = 0.0, 1.0
    while t_pvalue(hi, df) > alpha:
        lo, hi = hi, 2.0 * hi
    for _ in range(200):
        mid = (lo + hi) / 2.0
        lo, hi = (mid, hi) if t_pvalue(mid, df) > alpha else (lo, mid)
        if hi - lo < 1e-12 * hi:
            break
    return (lo + hi) / 2.0


def welch_t(x, y) -> dict:
    """Welch's unequal-variance t-test of mean(x) - mean(y) (NaNs dropped): {"diff", "se" (its
    standard error), "t", "df", "p" (two-sided), "nx", "ny"}; se, t, df and p are NaN below 2
    values a side or with no spread."""
    x, y = finite(x), finite(y)
    out = {"diff": math.nan, "se": math.nan, "t": math.nan, "df": math.nan, "p": math.nan, "nx": len(x), "ny": len(y)}
    if len(x) and len(y):
        out["diff"] = float(x.mean() - y.mean())
    if len(x) < 2 or len(y) < 2:
        return out
    vx, vy = x.var(ddof=1) / len(x), y.var(ddof=1) / len(y)
    se2 = vx + vy
    if se2 <= 0:
        return out
    t = out["diff"] / math.sqrt(se2)
    df = se2**2 / (vx**2 / (len(x) - 1) + vy**2 / (len(y) - 1)) if vx > 0 and vy > 0 else (
        len(x) - 1 if vx > 0 else len(y) - 1)
    out.update(se=math.sqrt(se2), t=float(t), df=float(df), p=t_pvalue(t, df))
    return out


def tost_bound(diff: float, se: float, df: float, alpha: float = 0.05) -> float:
    """The smallest margin D at which two one-sided tests (TOST) at level `alpha` call a difference
    `diff` with standard error `se` on `df` degrees of freedom equivalent to none, |difference| <
    D: |diff| + t(1 - alpha, df) se, the far end of its (1 - 2 alpha) interval. Where a test finds
    no difference, this says how large a one the data rule out. NaN where se or df is undefined."""
    if not (math.isfinite(diff) and math.isfinite(se) and se >= 0):
        return math.nan
    return abs(diff) + t_critical(df, 2.0 * alpha) * se


def one_way_anova(groups: Sequence) -> dict:
    """One-way ANOVA across `groups` (each a 1-D array; NaNs dropped, groups with no value left
    out): {"F", "df1", "df2", "p", "eta2" (between-group share of the total sum of squares), "k",
    "n"}. NaN where fewer than 2 groups, no within-group degrees of freedom, or no spread."""
    gs = [g for g in (finite(g) for g in groups) if len(g)]
    k, n = len(gs), sum(len(g) for g in gs)
    out = {"F": math.nan, "df1": k - 1, "df2": n - k, "p": math.nan, "eta2": math.nan, "k": k, "n": n}
    if k < 2 or n - k < 1:
        return out
    grand = np.concatenate(gs).mean()
    ss_between = sum(len(g) * (g.mean() - grand) ** 2 for g in gs)
    ss_within = sum(((g - g.mean()) ** 2).sum() for g in gs)
    if ss_between + ss_within <= 0:
        return out
    out["eta2"] = float(ss_between / (ss_between + ss_within))
    if ss_within <= 0:
        return out
    f = (ss_between / (k - 1)) / (ss_within / (n - k))
    out.update(F=float(f), p=f_pvalue(f, k - 1, n - k))
    return out


def block_anova(table) -> dict:
    """Two-way ANOVA without interaction on a [treatments, blocks] table, one value a cell: the
    treatment effect tested after removing each block's own level (a randomized complete block
    design). Runs of one seed share their random numbers, so a seed is a block; removing its level
    takes the variance the runs of one seed share out of the error term. Blocks with a NaN are
    left out. {"F", "df1", "df2", "p", "eta2" (treatment share of the sum of squares left after
    the blocks'), "block_share" (the blocks' share of the total), "ms_error" (the residual mean
    square, the error variance of a comparison of treatments), "k", "b"}. NaN where fewer than
    2 treatments or 2 blocks or no spread; F = inf, p = 0 where the residual is exactly 0 but the
    treatments differ."""
    y = np.asarray(table, float)
    y = y[:, np.isfinite(y).all(axis=0)]
    k, b = y.shape
    out = {"F": math.nan, "df1": k - 1, "df2": (k - 1) * (b - 1), "p": math.nan, "eta2": math.nan,
           "block_share": math.nan, "ms_error": math.nan, "k": k, "b": b}
    if k < 2 or b < 2:
        return out
    grand = y.mean()
    ss_treat = b * ((y.mean(axis=1) - grand) ** 2).sum()
    ss_block = k * ((y.mean(axis=0) - grand) ** 2).sum()
    ss_total = ((y - grand) ** 2).sum()
    ss_error = max(ss_total - ss_treat - ss_block, 0.0)
    if ss_total <= 0:
        return out
    out["block_share"] = float(ss_block / ss_total)
    out["ms_error"] = float(ss_error / out["df2"])
    out["eta2"] = float(ss_treat / (ss_treat + ss_error)) if ss_treat + ss_error > 0 else math.nan
    # The residual of an exactly additive table is 0 up to rounding of the sums above.
    if ss_error <= 1e-12 * ss_total:
        if ss_treat > 1e-12 * ss_total:
            out.update(F=math.inf, p=0.0)
        return out
    f = (ss_treat / out["df1"]) / (ss_error / out["df2"])
    out.update(F=float(f), p=f_pvalue(f, out["df1"], out["df2"]))
    return out


def equivalence_bound(table, alpha: float = 0.05) -> dict:
    """How alike the treatments of a [treatments, blocks] table are shown to be: the smallest margin
    D at which two one-sided tests (TOST) at level `alpha` find every two treatments' means within
    +-D of each other. For one pair it is |difference| + t(1 - alpha) x its standard error, the far
    end of the (1 - 2 alpha) interval; every pair must pass for all of them to be called
    equivalent, so the bound is the largest of these, and the intersection-union principle keeps
    the level at `alpha` without a correction for the number of pairs (`tost_bound` of the largest
    difference, as every pair has the same standard error). The standard error is the
    block ANOVA's (`block_anova`): sqrt(2 ms_error / b) on (k - 1)(b - 1) degrees of freedom,
    blocks with a NaN left out as there. A "no difference" verdict from a p-value says only that
    none was found; this says how large a difference the data rule out.

    {"bound", "largest" (the largest |difference| between two treatments' means), "se", "df"};
    NaN where `block_anova` has no residual mean square."""
    y = np.asarray(table, float)
    y = y[:, np.isfinite(y).all(axis=0)]
    a = block_anova(y)
    out = {"bound": math.nan, "largest": math.nan, "se": math.nan, "df": a["df2"]}
    if not math.isfinite(a["ms_error"]):
        return out
    means = y.mean(axis=1)
    out["largest"] = float(means.max() - means.min())
    out["se"] = math.sqrt(2.0 * a["ms_error"] / a["b"])
    out["bound"] = tost_bound(out["largest"], out["se"], a["df2"], alpha)  # every pair's se is the same
    return out


def holm(pvalues) -> np.ndarray:
    """Holm's step-down adjustment of a family of p-values: the i-th smallest becomes the largest
    of (m - j + 1) p_(j) over j <= i, capped at 1, for the m finite ones (NaNs stay NaN and do
    not count). A test whose adjusted p is below alpha is significant with the chance of any false
    finding in the whole family held at alpha, whatever the tests' dependence."""
    p = np.asarray(pvalues, float)
    out = np.full(p.shape, np.nan)
    idx = np.flatnonzero(np.isfinite(p))
    order = idx[np.argsort(p[idx], kind="stable")]
    m = len(order)
    out[order] = np.minimum(np.maximum.accumulate((m - np.arange(m)) * p[order]), 1.0)
    return out


def pearson_r(x, y) -> float:
    """Pearson correlation over the positions where both are finite; NaN below 3 or with no spread."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = np.isfinite(x) & np.isfinite(y)
    if ok.sum() < 3:
        return math.nan
    x, y = x[ok] - x[ok].mean(), y[ok] - y[ok].mean()
    den = math.sqrt(float((x * x).sum() * (y * y).sum()))
    return float((x * y).sum() / den) if den > 0 else math.nan


def fisher_z(r) -> np.ndarray:
    """arctanh(r), with |r| clipped below 1 so a perfect correlation stays finite."""
    return np.arctanh(np.clip(np.asarray(r, float), -0.999999, 0.999999))
