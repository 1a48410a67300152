"""The claims' rule set (experiments/claims_rules.py) on synthetic numbers: each rule's
edge cases (significant, weak, tie, the close-to band's edges, too few runs)."""

from __future__ import annotations

import numpy as np
import pytest
from skinny_mj.experiments import claims_rules as cr
from skinny_mj.experiments.claims_rules import RULES, Verdict, compare


def _runs(mean: float, sd: float, n: int = 20, seed: int = 0) -> np.ndarray:
    """n values with exactly this mean and sample SD (no sampling luck in the tests)."""
    z = np.random.default_rng(seed).standard_normal(n)
    z = (z - z.mean()) / z.std(ddof=1)
    return mean + sd * z


def test_rules_are_frozen_and_declared_once():
    rule = RULES["better"]
    with pytest.raises(AttributeError):
        rule.name = "other"  # type: ignore[misc]
    assert RULES["better"].test.alpha == RULES["best"].test.alpha == RULES["tie"].test.alpha \
        == cr.ALPHA == 0.05
    assert all(r.statistic == "mean" for r in RULES.values()
               if r.kind in ("better", "best", "tie", "close", "threshold"))
    assert RULES["significantly"].kind == RULES["better"].kind


# -- better / significantly ----------------------------------------------------------
def test_better_holds_when_significant():
    v = compare(_runs(0.02, 0.005), _runs(0.05, 0.01), "<", "better")
    assert v.outcome == "holds" and v.holds and not v.weak and v.p < 0.05


def test_better_in_the_right_direction_but_not_significant_is_weak_and_does_not_count():
    v = compare(_runs(0.049, 0.02), _runs(0.05, 0.02), "<", "better")
    assert v.outcome == "does not hold" and v.weak and not v.holds
    assert v.label == "does not hold (weak)"
    assert v.p >= 0.05


def test_better_in_the_wrong_direction_is_not_weak():
    v = compare(_runs(0.06, 0.005), _runs(0.05, 0.005), "<", "better")
    assert v.outcome == "does not hold" and not v.weak


def test_greater_direction():
    assert compare(_runs(30, 2), _runs(20, 2), ">", "significantly").holds
    assert not compare(_runs(20, 2), _runs(30, 2), ">", "significantly").holds


def test_same_margin_same_verdict_whatever_the_claim():
    """The rule has no per-claim escape: an effect at p ~ 0.26 is weak for every claim."""
    a, b = _runs(1.0, 1.0, 10), _runs(1.3, 1.0, 10)
    v1 = compare(a, b, "<", "better")
    v2 = compare(a, b, "<", "significantly")
    assert v1 == v2 and v1.weak and not v1.holds


def test_constant_groups_do_not_give_nan():
    assert compare([1.0] * 5, [2.0] * 5, "<", "better").holds
    v = compare([1.0] * 5, [1.0] * 5, "<", "better")
    assert v.outcome == "does not hold" and not v.weak
    assert compare([1.0] * 5, [1.0] * 5, "~", "tie").holds


# -- best ------------------------------------------------------------------------------
def test_best_needs_every_comparison_significant():
    a = _runs(0.06, 0.005, 10)
    far, near = _runs(0.08, 0.005, 10), _runs(0.0605, 0.005, 10)
    assert compare(a, [far, _runs(0.09, 0.005, 10)], "<", "best").holds
    v = compare(a, [far, near], "<", "best")
    assert v.outcome == "does not hold" and v.weak  # lowest mean, one competitor a tie
    assert len(v.details) == 2


def test_best_not_lowest_is_not_weak():
    v = compare(_runs(0.07, 0.005, 10), [_runs(0.06, 0.005, 10)], "<", "best")
    assert v.outcome == "does not hold" and not v.weak


# -- tie -------------------------------------------------------------------------------
def test_tie_holds_without_a_significant_difference_and_fails_with_one():
    assert compare(_runs(0.08, 0.01, 10), _runs(0.081, 0.01, 10), "~", "tie").holds
    v = compare(_runs(0.08, 0.002, 10), _runs(0.09, 0.002, 10), "~", "tie")
    assert v.outcome == "does not hold" and not v.weak and v.p < 0.05


def test_tie_at_too_few_runs_is_not_testable_not_a_hold():
    v = compare(_runs(0.08, 0.01, 5), _runs(0.081, 0.01, 5), "~", "tie", required_runs=10)
    assert v.outcome == "not testable" and not v.holds


# -- close to --------------------------------------------------------------------------
@pytest.mark.parametrize("mean, ok", [(0.3 * 1.5, True), (0.3 / 1.5, True),
                                      (0.3 * 1.5 * 1.001, False), (0.3 / 1.5 * 0.999, False)])
def test_close_to_a_number_band_edges_inclusive(mean, ok):
    v = compare(_runs(mean, 0.01, 20), 0.3, "~", "close")
    assert v.holds is ok
    assert v.details == pytest.approx((0.2, 0.45))


def test_close_to_a_range_widens_both_ends():
    rng = (0.10, 0.19)
    assert compare(_runs(0.19 * 1.5, 0.01), rng, "~", "close").holds
    assert compare(_runs(0.10 / 1.5, 0.001), rng, "~", "close").holds
    assert not compare(_runs(0.19 * 1.5 + 0.001, 0.01), rng, "~", "close").holds
    assert not compare(_runs(0.10 / 1.5 - 0.001, 0.001), rng, "~", "close").holds


def test_close_to_another_row():
    assert compare(_runs(0.015, 0.002), _runs(0.0103, 0.002), "~", "close").holds
    assert not compare(_runs(0.016, 0.002), _runs(0.0103, 0.002), "~", "close").holds


# -- threshold, extremes, stable -----------------------------------------------------------
def test_threshold_significant_weak_and_wrong_side():
    assert compare(_runs(0.1, 0.05, 10), 0.3, "<", "threshold").holds
    v = compare(_runs(0.29, 0.1, 10), 0.3, "<", "threshold")
    assert v.outcome == "does not hold" and v.weak
    v = compare(_runs(0.35, 0.1, 10), 0.3, "<", "threshold")
    assert v.outcome == "does not hold" and not v.weak
    assert compare(_runs(0.9, 0.05, 10), 0.6, ">", "threshold").holds


def test_extremes_are_literal():
    assert compare([0.01, 0.02, 0.024], [0.025, 0.03, 0.05], "<", "extremes").holds
    v = compare([0.01, 0.02, 0.026], [0.025, 0.03, 0.05], "<", "extremes")
    assert v.outcome == "does not hold" and not v.weak
    assert compare([30, 40], [10, 20], ">", "extremes").holds


def test_stable_share_edge():
    assert compare([1] * 9 + [0], None, "~", "stable").holds  # 90 %
    assert not compare([1] * 8 + [0] * 2, None, "~", "stable").holds


# -- run counts ------------------------------------------------------------------------------
@pytest.mark.parametrize("rule, rel, b", [("better", "<", [0.1] * 20), ("tie", "~", [0.1] * 20),
                                          ("close", "~", 0.1), ("threshold", "<", 0.3),
                                          ("extremes", "<", [0.1] * 20),
                                          ("best", "<", [[0.1] * 20, [0.2] * 20])])
def test_too_few_runs_is_not_testable(rule, rel, b):
    v = compare(_runs(0.05, 0.01, 19), b, rel, rule, required_runs=20)
    assert v.outcome == "not testable" and not v.holds and not v.weak
    assert "19 runs where 20" in v.reason


def test_a_single_run_is_never_testable():
    v = compare([0.01], [0.02, 0.03], "<", "better")
    assert v.outcome == "not testable"


def test_non_finite_values_are_dropped_before_counting():
    a = [0.01, 0.02, float("nan"), 0.015]
    v = compare(a, [0.05, 0.06, 0.055], "<", "better", required_runs=4)
    assert v.outcome == "not testable"


def test_run_counts_are_the_thesiss_where_stated():
    assert cr.RUNS["A"].runs == 10 and cr.RUNS["D"].runs == 50 and cr.RUNS["E"].runs == 20
    assert cr.RUNS["E-fig4"].runs == cr.RUNS["E-fig5"].runs == 10


# -- readings and the verdict type ------------------------------------------------------------
def test_fitted_readings_are_never_counted():
    fitted = [r for r in cr.READINGS.values() if r.status == "fitted"]
    assert {r.name for r in fitted} == {"fitted-gain-2", "fitted-tt-noise"}
    assert not any(r.counted for r in fitted)
    assert cr.counted_reading(["default", "fitted-gain-2", "recorded"]) == "recorded"
    assert cr.counted_reading(["default", "fitted-gain-2"]) == "default"
    assert cr.counted_reading(["default", "b-noise-free", "b-sr0.9-nu0.02"]) == "b-noise-free"
    with pytest.raises(ValueError):
        cr.counted_reading(["fitted-gain-2"])


def test_every_non_default_counted_reading_has_a_quote():
    for r in cr.READINGS.values():
        if r.status in ("supported", "partly supported"):
            assert r.quote and r.line, r.name
    assert cr.READINGS["gain-band"].band == (0.5, 1.0, 2.0)


def test_weak_labels_only_a_does_not_hold():
    with pytest.raises(ValueError):
        Verdict("holds", weak=True)
    with pytest.raises(ValueError):
        Verdict("weak")


def test_relation_must_fit_the_rule():
    with pytest.raises(ValueError):
        compare([1, 2], [1, 2], "~", "better")
    with pytest.raises(ValueError):
        compare([1, 2], [1, 2], "<", "tie")


def test_ratio_band():
    assert cr.ratio_band_holds(4.4 * 1.5, 4.4) and cr.ratio_band_holds(4.4 / 1.5, 4.4)
    assert not cr.ratio_band_holds(1.14, 4.4)
