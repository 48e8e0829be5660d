"""Paired statistics, bootstrap intervals and the findings' verdict logic on hand-computed
and constructed inputs."""
import math
from types import SimpleNamespace

import numpy as np
import pytest

from ctxmodels.experiment import findings, metrics
from ctxmodels.experiment.findings import COMBINED, Finding, evaluate, seed_scores
from ctxmodels.experiment.statistics import (INCONCLUSIVE, NOT_REPRODUCED, REPRODUCED, Interval,
                                             bootstrap_mean, overall_verdict, paired_difference,
                                             t_interval, verdict)


def test_paired_difference_by_hand():
    # d = (2, 3, 4): mean 3, s = 1; with 2 degrees of freedom the t quantile has a closed
    # form, t_p = (2p − 1) sqrt(2 / (4 p (1 − p))), here p = 0.975; half = t / sqrt(3).
    interval = paired_difference([3.0, 5.0, 7.0], [1.0, 2.0, 3.0])
    half = 0.95 * math.sqrt(2 / (4 * 0.975 * 0.025)) / math.sqrt(3)
    assert interval.mean == pytest.approx(3.0)
    assert (interval.low, interval.high) == pytest.approx((3 - half, 3 + half), rel=1e-12)
    # Lower is better (GOSPA): the same scores favour the second tracker.
    flipped = paired_difference([3.0, 5.0, 7.0], [1.0, 2.0, 3.0], lower_is_better=True)
    assert (flipped.mean, flipped.low, flipped.high) == pytest.approx((-3, -3 - half, -3 + half))


def test_paired_difference_uses_the_pairs_not_the_two_spreads():
    # Large spread across seeds, constant advantage: the paired interval is a point.
    a = [10.0, 50.0, 90.0]
    b = [9.0, 49.0, 89.0]
    interval = paired_difference(a, b)
    assert interval.low == pytest.approx(1.0) and interval.high == pytest.approx(1.0)
    assert verdict(interval) == REPRODUCED


def test_paired_difference_rejects_bad_input():
    with pytest.raises(ValueError, match="one value per seed"):
        paired_difference([1.0, 2.0], [1.0])
    with pytest.raises(ValueError, match="finite"):
        paired_difference([1.0, math.nan], [1.0, 2.0])
    with pytest.raises(ValueError, match="empty"):
        paired_difference([], [])
    single = t_interval([2.0])
    assert single.mean == 2.0 and math.isnan(single.low) and verdict(single) == INCONCLUSIVE


@pytest.mark.parametrize("values", [[0.0, 0.0, 100.0], [99.0, 100.0, 100.0, 100.0],
                                    [0.0, 0.1, 0.0, 0.0, 0.0], [50.0, 0.0, 100.0, 0.0, 100.0]])
def test_bootstrap_interval_stays_in_the_metrics_range(values):
    interval = bootstrap_mean(values)
    assert min(values) <= interval.low <= interval.mean <= interval.high <= max(values)
    assert 0.0 <= interval.low and interval.high <= 100.0
    # Mean ± t·s on the same few values runs outside [0, 100] for the first two.
    if values[:3] in ([0.0, 0.0, 100.0], [99.0, 100.0, 100.0]):
        t = t_interval(values)
        assert t.low < 0.0 or t.high > 100.0


def test_bootstrap_is_reproducible_and_covers_the_mean():
    rng = np.random.default_rng(3)
    values = rng.uniform(20, 80, size=10)
    first, second = bootstrap_mean(values), bootstrap_mean(values.copy())
    assert first == second  # fixed resampling seed: same scores, same interval
    assert first.low < np.mean(values) < first.high
    # Roughly the normal-theory width for ten values (a loose check on the percentiles).
    t = t_interval(values)
    assert 0.6 < (first.high - first.low) / (t.high - t.low) < 1.1
    constant = bootstrap_mean([42.0] * 5)
    assert (constant.low, constant.mean, constant.high) == (42.0, 42.0, 42.0)
    assert math.isnan(bootstrap_mean([1.0]).low)


def test_verdicts():
    assert verdict(Interval(1.0, 0.5, 2.0)) == REPRODUCED
    assert verdict(Interval(-1.0, -2.0, -0.5)) == NOT_REPRODUCED
    assert verdict(Interval(0.1, -1.0, 1.0)) == INCONCLUSIVE
    assert verdict(Interval(0.0, 0.0, 0.0)) == INCONCLUSIVE  # touching 0 is not excluding it
    assert verdict(Interval(1.0, math.nan, math.nan)) == INCONCLUSIVE
    assert overall_verdict([REPRODUCED, REPRODUCED]) == REPRODUCED
    assert overall_verdict([REPRODUCED, INCONCLUSIVE]) == INCONCLUSIVE
    assert overall_verdict([REPRODUCED, NOT_REPRODUCED]) == NOT_REPRODUCED
    assert overall_verdict([INCONCLUSIVE, NOT_REPRODUCED]) == NOT_REPRODUCED
    assert overall_verdict([]) == INCONCLUSIVE


def _result(hota: float, gospa: float):
    return SimpleNamespace(hota=SimpleNamespace(hota=hota / 100), gospa=SimpleNamespace(rms=gospa))


def _by_key(scores: dict) -> dict:
    """{(tracker, scenario): [(hota %, gospa), ...per seed]} -> job results keyed as the
    experiment keys them."""
    return {(t, s, seed): _result(*value) for (t, s), values in scores.items()
            for seed, value in enumerate(values)}


def test_finding_verdicts_on_constructed_scores():
    claim = Finding("a-beats-b", "A > B", "test", ("a",), ("b",), "mixed-range")
    better = _by_key({("a", "mixed-range"): [(60, 20), (62, 21), (58, 19)],
                      ("b", "mixed-range"): [(50, 30), (51, 31), (49, 28)]})
    result = evaluate(claim, better)
    assert result.seeds == (0, 1, 2)
    assert result.hota.mean == pytest.approx(10.0) and result.gospa.mean == pytest.approx(29 / 3)
    assert (result.hota_verdict, result.gospa_verdict, result.verdict) == (REPRODUCED,) * 3
    # B better on both: not reproduced; mixed evidence: the opposite metric decides.
    swapped = evaluate(Finding("b-beats-a", "B > A", "test", ("b",), ("a",), "mixed-range"), better)
    assert swapped.verdict == NOT_REPRODUCED and swapped.hota.mean == pytest.approx(-10.0)
    noisy = _by_key({("a", "mixed-range"): [(60, 20), (40, 21), (55, 19)],
                     ("b", "mixed-range"): [(50, 30), (50, 31), (50, 28)]})
    mixed = evaluate(claim, noisy)
    assert (mixed.hota_verdict, mixed.gospa_verdict, mixed.verdict) == \
        (INCONCLUSIVE, REPRODUCED, INCONCLUSIVE)
    missing = evaluate(Finding("c", "C > B", "test", ("c",), ("b",), "mixed-range"), better)
    assert missing.verdict == findings.NOT_RUN and missing.hota is None


def test_several_better_trackers_use_the_closest_margin():
    claim = Finding("b-is-worst", "B worst", "test", ("a", "c"), ("b",), "formation")
    scores = _by_key({("a", "formation"): [(60, 20), (61, 20)],
                      ("c", "formation"): [(52, 40), (53, 41)],
                      ("b", "formation"): [(50, 30), (50, 31)]})
    result = evaluate(claim, scores)
    # HOTA: margins (10, 2) and (11, 3): the closest is c's, 2 and 3.
    assert result.hota.mean == pytest.approx(2.5)
    # GOSPA: b − a = (10, 11), b − c = (−10, −10): c is worse than b, so the claim fails.
    assert result.gospa.mean == pytest.approx(-10.0) and result.gospa_verdict == NOT_REPRODUCED
    assert result.verdict == NOT_REPRODUCED


def test_combined_scope_aggregates_both_scenarios_per_seed():
    frames = {
        "mixed-range": [metrics.EvaluationFrame([0], [[0.0, 0.0]], [0], [[1.0, 0.0]])],
        "formation": [metrics.EvaluationFrame([0], [[0.0, 0.0]], [0], [[20.0, 0.0]]),
                      metrics.EvaluationFrame([0], [[0.0, 0.0]], [], np.zeros((0, 2)))],
    }
    by_key = {("a", s, 0): SimpleNamespace(hota=metrics.hota_from_frames(f),
                                           gospa=metrics.gospa_from_frames(f))
              for s, f in frames.items()}
    (hota, gospa), = seed_scores(by_key, "a", COMBINED).values()
    parts = [by_key[("a", s, 0)] for s in findings.COMBINED_SCENARIOS]
    assert hota == 100 * metrics.combine_hota([p.hota for p in parts]).hota
    assert gospa == metrics.combine_gospa([p.gospa for p in parts]).rms
    # Not the mean of the two scenarios' scores: the evaluation times are pooled.
    assert gospa != pytest.approx(np.mean([p.gospa.rms for p in parts]))
    # A seed without both scenarios has no combined score.
    del by_key[("a", "formation", 0)]
    assert seed_scores(by_key, "a", COMBINED) == {}
