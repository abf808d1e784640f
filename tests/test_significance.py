"""The significance tests (mjx_curio/analysis/significance.py) against closed forms and hand
computations: the t and F tails, Welch's t, one-way and block ANOVA, Pearson's r."""

import math

import numpy as np
import pytest

from mjx_curio.analysis import significance as sig

# ------------------------------------------------------------------------- p-values vs closed forms


@pytest.mark.parametrize("t", [0.0, 0.3, 1.0, 2.5, 12.7, -4.0])
def test_t_pvalue_matches_closed_forms(t):
    # df = 1 is the Cauchy distribution, df = 2 has a closed-form CDF as well.
    assert sig.t_pvalue(t, 1) == pytest.approx(1 - 2 / math.pi * math.atan(abs(t)), abs=1e-12)
    assert sig.t_pvalue(t, 2) == pytest.approx(1 - abs(t) / math.sqrt(2 + t * t), abs=1e-12)


@pytest.mark.parametrize("f,d2", [(0.5, 3), (3.0, 6), (12.0, 6), (40.0, 17.5)])
def test_f_pvalue_matches_closed_form(f, d2):
    # With df1 = 2 the F tail is (1 + 2 f / d2) ** (-d2 / 2).
    assert sig.f_pvalue(f, 2, d2) == pytest.approx((1 + 2 * f / d2) ** (-d2 / 2), rel=1e-10)


def test_betainc_special_cases():
    for x in (0.01, 0.3, 0.77, 0.999):
        assert sig.betainc(3.5, 1, x) == pytest.approx(x**3.5, rel=1e-10)
        assert sig.betainc(1, 2.5, x) == pytest.approx(1 - (1 - x) ** 2.5, rel=1e-10)
        assert sig.betainc(2, 3, x) + sig.betainc(3, 2, 1 - x) == pytest.approx(1, abs=1e-12)


def test_welch_t_two_by_two_by_hand():
    # x, y each [-1, 1] shifted by d: variances 2, se^2 = 2/2 + 2/2 = 2, df = 4 / (1 + 1) = 2.
    d = 3.0
    w = sig.welch_t(np.array([-1.0, 1.0]) + d, np.array([-1.0, 1.0]))
    t = d / math.sqrt(2)
    assert w["diff"] == pytest.approx(d) and w["se"] == pytest.approx(math.sqrt(2))
    assert w["t"] == pytest.approx(t)
    assert w["df"] == pytest.approx(2)
    assert w["p"] == pytest.approx(1 - t / math.sqrt(2 + t * t))


def test_welch_t_unequal_variances_by_hand():
    x, y = np.array([1.0, 2.0, 3.0, 4.0]), np.array([2.0, 4.0, 6.0, 8.0, 10.0, np.nan])
    vx, vy = 5 / 3 / 4, 10.0 / 5  # sample variances 5/3 and 10, over n
    t = (2.5 - 6.0) / math.sqrt(vx + vy)
    df = (vx + vy) ** 2 / (vx**2 / 3 + vy**2 / 4)
    w = sig.welch_t(x, y)
    assert (w["t"], w["df"], w["ny"]) == (pytest.approx(t), pytest.approx(df), 5)
    try:  # an independent implementation where one is installed (scipy is not a dependency)
        from scipy import stats as sps
    except ImportError:
        return
    assert w["p"] == pytest.approx(sps.ttest_ind(x, y[:5], equal_var=False).pvalue, rel=1e-8)


def test_one_way_anova_by_hand():
    # Group means 2, 5, 8, grand mean 5: SS between = 3 * (9 + 0 + 9) = 54; SS within = 2 + 2 + 2 = 6;
    # F = (54 / 2) / (6 / 6) = 27 on (2, 6) degrees of freedom; p = (1 + 2 * 27 / 6) ** -3 = 1e-3.
    a = sig.one_way_anova([[1, 2, 3], [4, 5, 6], [7, 8, 9]])
    assert a["F"] == pytest.approx(27.0)
    assert (a["df1"], a["df2"]) == (2, 6)
    assert a["p"] == pytest.approx(10.0**-3)
    assert a["eta2"] == pytest.approx(54 / 60)
    same = sig.one_way_anova([[1, 2, 3], [2, 1, 3], [3, 2, 1]])
    assert same["F"] == pytest.approx(0.0) and same["p"] == pytest.approx(1.0)



def test_block_anova_with_two_treatments_is_the_paired_t_test():
    # Two treatments in four blocks: the differences 1, 2, 2, 1 have mean 1.5 and standard deviation
    # sqrt(1/3), so the paired t = 1.5 / (sqrt(1/3) / 2) = sqrt(27) on 3 degrees of freedom, and the
    # blocked F on (1, 3) degrees of freedom is t^2 = 27 with the same p-value.
    y = np.array([[1.0, 2, 3, 4], [2, 4, 5, 5]])
    b = sig.block_anova(y)
    assert b["F"] == pytest.approx(27.0) and (b["df1"], b["df2"], b["b"]) == (1, 3, 4)
    assert b["p"] == pytest.approx(sig.t_pvalue(math.sqrt(27.0), 3))
    # The error variance of one treatment's value against the other's is that of the differences.
    assert 2 * b["ms_error"] == pytest.approx(1 / 3)
    try:  # an independent implementation where one is installed (scipy is not a dependency)
        from scipy import stats as sps
    except ImportError:
        return
    assert b["p"] == pytest.approx(sps.ttest_rel(y[0], y[1]).pvalue, rel=1e-8)


def test_block_anova_removes_block_levels_that_the_one_way_test_counts_as_error():
    rng = np.random.default_rng(0)
    y = 0.1 * np.arange(3.0)[:, None] + rng.normal(0, 0.01, (3, 5))  # three treatments, five blocks
    offsets = np.array([0.0, 3.0, -2.0, 5.0, 1.0])  # each block's own level, shared by its treatments
    plain, shifted = sig.block_anova(y), sig.block_anova(y + offsets)
    assert shifted["F"] == pytest.approx(plain["F"]) and shifted["p"] < 1e-6
    assert shifted["block_share"] > 0.99
    assert sig.one_way_anova(list(y + offsets))["p"] > 0.5  # the offsets drown the effect in the error term
    # A block with a missing value is left out; an exactly additive table has no residual.
    gappy = np.concatenate([y, [[np.nan], [0.0], [0.0]]], axis=1)
    assert sig.block_anova(gappy)["F"] == pytest.approx(plain["F"]) and sig.block_anova(gappy)["b"] == 5
    exact = sig.block_anova(np.arange(3.0)[:, None] + offsets)
    assert exact["F"] == math.inf and exact["p"] == 0.0
    assert math.isnan(sig.block_anova(y[:, :1])["p"])


def test_t_critical_inverts_the_tail():
    # df = 1 is the Cauchy distribution: P(|T| >= t) = alpha at t = tan(pi (1 - alpha) / 2).
    for alpha in (0.05, 0.1, 0.01):
        assert sig.t_critical(1, alpha) == pytest.approx(math.tan(math.pi * (1 - alpha) / 2), rel=1e-9)
    assert sig.t_critical(3, 0.1) == pytest.approx(2.353363, abs=1e-6)  # the one-sided 95 % point (tables)
    assert math.isnan(sig.t_critical(0))


def test_equivalence_bound_of_two_treatments_is_the_paired_interval():
    # The table of the paired t test above: differences 1, 2, 2, 1, mean 1.5, sd sqrt(1/3). The
    # two one-sided tests at 5 % pass for every margin beyond the far end of the 90 % interval of
    # the paired difference, 1.5 + t(0.95, 3) sqrt(1/3) / 2.
    y = np.array([[1.0, 2, 3, 4], [2, 4, 5, 5]])
    e = sig.equivalence_bound(y)
    assert (e["largest"], e["df"]) == (1.5, 3) and e["se"] == pytest.approx(math.sqrt(1 / 3) / 2)
    assert e["bound"] == pytest.approx(1.5 + 2.353363 * math.sqrt(1 / 3) / 2, abs=1e-6)
    # Block levels change nothing; a block with a NaN is left out; no residual, no bound.
    assert sig.equivalence_bound(y + np.array([0.0, 7.0, -3.0, 1.0]))["bound"] == pytest.approx(e["bound"])
    assert sig.equivalence_bound(np.concatenate([y, [[np.nan], [9.0]]], axis=1))["bound"] == pytest.approx(e["bound"])
    assert math.isnan(sig.equivalence_bound(y[:, :1])["bound"])


def test_tost_bound_is_the_far_end_of_the_90_percent_interval():
    # The welch test above (difference 3, se sqrt(2), df 2): its 90 % interval reaches
    # 3 + t(0.95, 2) sqrt(2), with t(0.95, 2) = 2.919986 (tables); the sign does not matter.
    assert sig.tost_bound(3.0, math.sqrt(2), 2) == pytest.approx(3 + 2.919986 * math.sqrt(2), abs=1e-5)
    assert sig.tost_bound(-3.0, math.sqrt(2), 2) == sig.tost_bound(3.0, math.sqrt(2), 2)
    assert sig.tost_bound(3.0, math.sqrt(2), 2, alpha=0.025) == pytest.approx(
        3 + sig.t_critical(2, 0.05) * math.sqrt(2))  # alpha = 0.025 a side: the 95 % interval
    assert math.isnan(sig.tost_bound(math.nan, 1.0, 5)) and math.isnan(sig.tost_bound(1.0, math.nan, 5))


def test_holm_by_hand():
    # Four finite p-values, sorted 0.005, 0.01, 0.03, 0.04: times 4, 3, 2, 1 gives 0.02, 0.03, 0.06,
    # 0.04, and the running maximum keeps the order: 0.02, 0.03, 0.06, 0.06. A NaN is no test.
    q = sig.holm([0.01, 0.04, 0.03, np.nan, 0.005])
    np.testing.assert_allclose(q, [0.03, 0.06, 0.06, np.nan, 0.02])
    assert sig.holm([0.5, 0.9])[1] == 1.0 and sig.holm([]).shape == (0,)
    # Holm's definition, written out: the i-th smallest p-value's adjusted value is the largest
    # of (m - j) p_(j) over j <= i, capped at 1.
    p = np.random.default_rng(0).uniform(0, 0.3, 12)
    ranked = np.sort(p)
    by_rank = [min(1.0, max((len(p) - j) * ranked[j] for j in range(i + 1))) for i in range(len(p))]
    np.testing.assert_allclose(sig.holm(p), np.array(by_rank)[np.argsort(np.argsort(p))])


@pytest.mark.parametrize("means,level", [((0.0, 1.0), "at"), ((0.0, 0.5, 1.0, 1.0), "below")])
def test_equivalence_bound_keeps_its_level(means, level):
    # Simulated block designs (6 seeds, unit noise, seeds with levels of their own) whose two most
    # distant treatments are exactly D apart: the bound falls below D, calling them equivalent
    # at D, in 5 % of tables when two treatments are compared, and in no more when the other
    # pairs must pass too (the intersection-union test is conservative).
    rng, b, d, reps = np.random.default_rng(0), 6, 3.0, 3000
    k = len(means)
    y = d * np.array(means)[None, :, None] + rng.normal(0, 1, (reps, k, b)) + rng.normal(0, 4, (reps, 1, b))
    called = np.mean([sig.equivalence_bound(t)["bound"] < d for t in y])
    sd = math.sqrt(0.05 * 0.95 / reps)  # the binomial spread of the rate, 0.004
    if level == "at":
        assert called == pytest.approx(0.05, abs=4 * sd), called
    else:  # ... but not never: a bound that can never fall below D would pass the first check
        assert 0.002 < called <= 0.05 + 4 * sd, called

def test_pearson_r_known_values():
    x = np.arange(10.0)
    assert sig.pearson_r(x, 3 * x + 1) == pytest.approx(1.0)
    assert sig.pearson_r(x, -x) == pytest.approx(-1.0)
    # Orthogonal centred vectors: r = 0 exactly.
    assert sig.pearson_r([1, -1, 1, -1], [1, 1, -1, -1]) == pytest.approx(0.0)
    assert math.isnan(sig.pearson_r([1, 2], [3, 4]))
