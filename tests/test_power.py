"""Power (mjx_curio/analysis/power.py): the noncentral t tail against SciPy and closed forms, the
seeds it asks for against Cohen's tables, its power against simulations of the claims' own tests,
and the table on synthetic sweeps with planted effects."""

import dataclasses
import math

import numpy as np
import pytest

from mjx_curio import analysis as an
from mjx_curio.analysis import claims as cl
from mjx_curio.analysis import power as pw
from mjx_curio.analysis.stats import mean_ci

from test_claims import POLICIES, fake_sweep

# Three values with sample sd 1, shifted to a mean: a group whose spread is exactly known.
UNIT = np.array([-1.0, 0.0, 1.0])


@pytest.mark.parametrize("df", [1.0, 1.3, 2.0, 4.5, 30.0, 2000.0])
@pytest.mark.parametrize("ncp", [-1.0, 0.0, 0.7, 3.0, 9.0])
def test_noncentral_t_sf_matches_scipy(df, ncp):
    stats = pytest.importorskip("scipy.stats")  # an independent implementation (not a dependency)
    for c in (-2.0, 0.0, 1.0, 2.3, 12.7):
        assert pw.noncentral_t_sf(c, df, ncp) == pytest.approx(float(stats.nct.sf(c, df, ncp)), abs=1e-5)


@pytest.mark.parametrize("df", [1.0, 2.5, 7.0, 40.0])
def test_noncentral_t_sf_closed_forms(df):
    # No shift: the central t, whose two-sided tail the claims' tests use; and symmetry about 0.
    for c in (0.5, 2.0, 6.0):
        assert pw.noncentral_t_sf(c, df, 0.0) == pytest.approx(an.t_pvalue(c, df) / 2, abs=1e-6)
    assert pw.noncentral_t_sf(0.0, df, 0.0) == pytest.approx(0.5, abs=1e-6)
    # P(T > 0) = P(Z > -ncp) whatever the denominator.
    assert pw.noncentral_t_sf(0.0, df, 1.5) == pytest.approx(0.5 * math.erfc(-1.5 / math.sqrt(2)), abs=1e-6)
    # The critical value is the quantile of the two-sided test.
    assert an.t_pvalue(pw.t_critical(df), df) == pytest.approx(0.05, rel=1e-9)


def test_seeds_needed_reproduces_cohens_tables():
    # Cohen (1988), table 2.4.1: two groups, two-sided alpha 0.05, power 0.8: d = 0.5 needs 64 a
    # group, d = 0.8 needs 26. One sample, d = 0.5: 34 (power 0.808; 33 gives 0.799).
    assert pw.seeds_needed(cl.Tested(UNIT + 0.5, UNIT)) == 64
    assert pw.seeds_needed(cl.Tested(UNIT + 0.8, UNIT)) == 26
    assert pw.seeds_needed(cl.Tested(UNIT + 0.5)) == 34
    assert pw.t_power(0.5 * math.sqrt(34), 33) == pytest.approx(0.808, abs=5e-4)
    # Against a null other than 0, and runs pooled over policies (three runs a seed).
    assert pw.seeds_needed(cl.Tested(UNIT + 1.0, null=0.5)) == 34
    assert pw.seeds_needed(cl.Tested(UNIT + 0.5, runs_per_seed=2)) == 17
    # The other way, or no effect to find: no number of seeds finds it.
    assert math.isnan(pw.seeds_needed(cl.Tested(UNIT - 0.5)))
    assert math.isnan(pw.seeds_needed(cl.Tested(UNIT, UNIT)))
    assert math.isinf(pw.seeds_needed(cl.Tested(UNIT + 0.001)))


def test_detectable_is_the_effect_that_needs_exactly_those_seeds():
    for seeds in (3, 8, 20):
        mde = pw.detectable(cl.Tested(UNIT), seeds)
        assert pw.t_power(mde * math.sqrt(seeds), seeds - 1) == pytest.approx(pw.POWER, abs=1e-6)
        assert pw.seeds_needed(cl.Tested(UNIT + mde * 1.001)) == seeds
        assert pw.seeds_needed(cl.Tested(UNIT + mde * 0.999)) == seeds + 1
    # A detectable effect scales with the spread.
    assert pw.detectable(cl.Tested(3 * UNIT), 5) == pytest.approx(3 * pw.detectable(cl.Tested(UNIT), 5))


def test_power_is_the_rate_at_which_the_claims_own_tests_find_an_effect():
    rng = np.random.default_rng(0)
    # One sample, the 95% interval above 0 (stats.mean_ci): exact for normal runs.
    n, d, reps = 4, 1.2, 20_000
    found = (mean_ci(rng.normal(d, 1.0, (reps, n)), axis=1)[1] > 0).mean()
    assert found == pytest.approx(pw.t_power(d * math.sqrt(n), n - 1), abs=0.012)  # 3.5 standard errors
    # Welch's t, p < 0.05 in the paper's direction: the power uses Welch's approximate degrees of
    # freedom, so it is itself approximate (off by ~0.01 here).
    n, d, sx, sy, reps = 5, 2.0, 1.0, 2.0, 6_000
    xs, ys = rng.normal(d, sx, (reps, n)), rng.normal(0.0, sy, (reps, n))
    hits = [(w["p"] < 0.05 and w["diff"] > 0) for w in (an.welch_t(x, y) for x, y in zip(xs, ys))]
    se, df = pw.design(cl.Tested(d + sx * UNIT, sy * UNIT), n)
    assert np.mean(hits) == pytest.approx(pw.t_power(d / se, df), abs=0.035)
    # Blocked: two of 5 treatments compared with the residual error of `block_anova`, seeds with
    # levels of their own that the design removes.
    k, b, d, reps = 5, 3, 2.5, 20_000
    y = rng.normal(0.0, 1.0, (reps, k, b)) + rng.normal(0.0, 5.0, (reps, 1, b))
    y[:, 0] += d
    resid = y - y.mean(axis=2, keepdims=True) - y.mean(axis=1, keepdims=True) + y.mean(axis=(1, 2), keepdims=True)
    ms = (resid ** 2).sum(axis=(1, 2)) / ((k - 1) * (b - 1))
    t = (y[:, 0].mean(axis=1) - y[:, 1].mean(axis=1)) / np.sqrt(2 * ms / b)
    found = (t > pw.t_critical((k - 1) * (b - 1))).mean()
    se, df = pw.design(cl.Tested(rng.normal(0.0, 1.0, (k, b)), blocked=True), b)
    assert df == (k - 1) * (b - 1)
    assert found == pytest.approx(pw.t_power(d / math.sqrt(2 / b), df), abs=0.012)


def test_claims_record_the_values_their_tests_compare():
    rng = np.random.default_rng(1)
    s = fake_sweep("multi_agent", 2, POLICIES, 2000, seeds=4)  # 40,000 steps
    planted = {"eps": 500, "boltzmann": 100, "ucb": 1000}  # object contact steps per run
    for g in s.groups():
        for i in g.indices:
            s.metrics["contact_object"][i, :planted[g.policy] + int(rng.integers(-20, 21)), 0, 2] = 1
    r = cl.claim_contact_ranking({"multi_agent": s})
    t = r.tests["objects UCB > Boltzmann"]
    assert pw.effect(t) == pytest.approx(r.values["objects ucb"] - r.values["objects boltzmann"])
    assert pw.seeds_now(t) == 4 and pw.seeds_needed(t) == 2  # a 900-step gap over a spread of ~12
    # The claims over every run of the sweep count a seed's runs of all three policies together.
    r = cl.claim_agents_move_together({"multi_agent": s})
    assert r.tests["within-run z - cross-run z"].runs_per_seed == 3


def test_power_table_on_planted_sweeps():
    rng = np.random.default_rng(2)
    multi = fake_sweep("multi_agent", 2, POLICIES, 2000, seeds=3)
    temps = fake_sweep("boltzmann_temperatures", 2, [("boltzmann", t) for t in (0.5, 1.5, 2.5)], 2000, seeds=3)
    for s in (multi, temps):
        s.metrics["curiosity"][:] = rng.normal(0.5, 0.05, s.metrics["curiosity"].shape)
    table = an.power_table({"multi_agent": multi, "boltzmann_temperatures": temps})
    keys = [v["key"] for v in table.values]
    # The claims these two sweeps test; 8 and 9 have nothing to compare here (no predictions, nothing
    # in view), and a test without two seeds' values gets no row.
    assert set(keys) == {"1", "2", "4", "6a", "6b", "7", "11"}, keys
    assert all(len(row) == len(table.columns) for row in table.rows)
    row7 = table.rows[keys.index("7")]
    assert row7[8] == "n/a (a claim of no difference)"
    assert math.isfinite(table.values[keys.index("7")]["detectable_now"])
    # Holm's adjustment runs over every test of the table but claim 7's.
    ps = [math.nan if v["p"] is None else v["p"] for v in table.values]
    assert table.values[keys.index("7")]["p"] is None and row7[6] == "n/a"
    np.testing.assert_allclose([math.nan if v["p_holm"] is None else v["p_holm"] for v in table.values], an.holm(ps))
    # Its largest difference not ruled out is claim 7's equivalence bound.
    assert table.values[keys.index("7")]["largest_allowed"] == pytest.approx(
        cl.claim_temperatures_alike({"boltzmann_temperatures": temps}).values["equivalence_bound"])
    # 8 seeds detect smaller effects than 3 (where the runs differ at all).
    for v in table.values:
        if v["detectable_now"]:
            assert v["detectable_planned"] < v["detectable_now"], v
    # No contacts in any run: no effect and no spread.
    assert "| objects UCB > ε | 0 | 0, 0 | 0 | n/a | 3 | none: no effect observed | 0 | 0 |" in table.to_markdown()


def test_standardised_effect_is_the_effect_and_its_interval_over_the_runs_spread():
    # One sample 1, 2, 3, 4 against 0: mean 2.5, sd sqrt(5/3), se sd / 2, t(0.975, 3) = 3.182446.
    one = cl.Tested(np.array([1.0, 2.0, 3.0, 4.0, np.nan]))
    sd = math.sqrt(5 / 3)
    d, lo, hi = pw.standardised_effect(one)
    assert (d, lo, hi) == pytest.approx((2.5 / sd, (2.5 - 3.182446 * sd / 2) / sd, (2.5 + 3.182446 * sd / 2) / sd),
                                        abs=1e-5)
    # Its interval excludes 0 exactly when the claim's own two-sided test is significant.
    assert (lo > 0) == (pw.p_value(one) < 0.05)
    # Two samples, the second's spread three times the first's: sd the root of the mean variance,
    # interval from Welch's standard error and degrees of freedom, t(0.975, 2.22...) from the tables' rule.
    two = cl.Tested(np.array([2.0, 3.0, 4.0]), np.array([-3.0, 0.0, 3.0]))
    w = an.welch_t(two.x, two.y)
    d, lo, hi = pw.standardised_effect(two)
    sd = math.sqrt((1.0 + 9.0) / 2)
    half = an.t_critical(w["df"]) * w["se"]
    assert (d, lo, hi) == pytest.approx((3.0 / sd, (3.0 - half) / sd, (3.0 + half) / sd))
    assert (lo > 0) == (w["p"] < 0.05)
    # No effect to standardise: a blocked claim of no difference, one run, no spread.
    for t in (cl.Tested(np.ones((3, 3)), blocked=True), cl.Tested(np.array([1.0])), cl.Tested(np.ones(4))):
        assert all(math.isnan(v) for v in pw.standardised_effect(t)), t


def test_largest_allowed_is_the_one_sided_upper_confidence_bound():
    # One sample 1, 2, 3, 4 against 0: mean 2.5, se sqrt(5/3) / 2, t(0.95, 3) = 2.353363 (tables).
    one = cl.Tested(np.array([1.0, 2.0, 3.0, 4.0, np.nan]))
    assert pw.largest_allowed(one) == pytest.approx(2.5 + 2.353363 * math.sqrt(5 / 3) / 2, abs=1e-5)
    # Against a null of 3 the effect is negative, and so is the bound: the paper's direction is ruled out.
    assert pw.largest_allowed(dataclasses.replace(one, null=5.0)) == pytest.approx(
        pw.largest_allowed(one) - 5.0)
    # Two samples: Welch's difference 3, se sqrt(2), df 2, t(0.95, 2) = 2.919986.
    two = cl.Tested(np.array([-1.0, 1.0]) + 3.0, np.array([-1.0, 1.0]))
    assert pw.largest_allowed(two) == pytest.approx(3 + 2.919986 * math.sqrt(2), abs=1e-5)
    assert math.isnan(pw.largest_allowed(cl.Tested(np.array([1.0]))))
    # The tests' own p: Student's t of 1, 2, 3 against 0 is 2 sqrt(3) on 2 degrees of freedom,
    # whose two-sided tail is 1 - t / sqrt(2 + t^2); Welch's for two samples; none for a blocked table.
    t = 2 * math.sqrt(3)
    assert pw.p_value(cl.Tested(np.array([1.0, 2.0, 3.0]))) == pytest.approx(1 - t / math.sqrt(2 + t * t))
    assert pw.p_value(two) == pytest.approx(an.welch_t(two.x, two.y)["p"])
    assert math.isnan(pw.p_value(cl.Tested(np.ones((3, 3)), blocked=True)))
    # It covers: over many draws of 5 runs with a true effect of 1, the bound falls below 1 in 5 %.
    rng, reps = np.random.default_rng(3), 4000
    below = np.mean([pw.largest_allowed(cl.Tested(rng.normal(1.0, 2.0, 5))) < 1.0 for _ in range(reps)])
    assert below == pytest.approx(0.05, abs=4 * math.sqrt(0.05 * 0.95 / reps)), below
