"""The findings' declared verdicts: one-sided superiority and non-inferiority tests, Holm's
correction over the family, the size verdict against the paper's Table II, and the summary
figure drawing them as the findings table gives them. Hand-computed on constructed scores.

Most cases use three seeds with differences (m − 1, m, m + 1): standard deviation 1 and two
degrees of freedom, where Student's t has closed forms — the quantile
t_p = (2p − 1) √(2 / (4p(1 − p))) and the tail P(T > t) = 1/2 − t / (2 √(2 + t²)).
"""
import math
import random
from types import SimpleNamespace

import numpy as np
import pytest

from ctxmodels.experiment import figures, summary_plots
from ctxmodels.experiment.findings import (FINDINGS, Finding, evaluate, evaluate_all,
                                           findings_markdown, paper_effect)
from ctxmodels.experiment.statistics import (INCONCLUSIVE, INFERIOR, MARGINS, NO_PAPER_EFFECT,
                                             NON_INFERIOR, NON_INFERIORITY, NOT_REPRODUCED,
                                             REPRODUCED, SIZE_INSIDE, SIZE_LARGER,
                                             SIZE_SMALLER, Interval, holm,
                                             one_sided_p, one_sided_test, overall_verdict,
                                             size_verdict, t_interval, verdict)


def t2_quantile(p: float) -> float:
    return (2 * p - 1) * math.sqrt(2 / (4 * p * (1 - p)))


def t2_tail(t: float) -> float:
    return 0.5 - t / (2 * math.sqrt(2 + t * t))


#: One-sided 95 % half-width of (m − 1, m, m + 1): t_{0.95, 2} · 1 / √3 ≈ 1.686.
HALF = t2_quantile(0.95) / math.sqrt(3)


def spread(m: float) -> list[float]:
    return [m - 1, m, m + 1]


# --- the declared margins and kinds ----------------------------------------------------

def test_margins_and_kinds_are_the_declared_ones():
    # Declared before the confirmatory run; not to be tuned to its results.
    assert MARGINS == {"hota": 1.0, "gospa": 1.0}
    kinds = {f.key: f.test for f in FINDINGS}
    assert {k for k, v in kinds.items() if v == NON_INFERIORITY} == {
        "context-beats-pd-aware", "learned-clutter-matches-context", "learned-matches-context",
        "solent-learned-matches-sight"}
    assert all(("≥" in f.claim) == (f.test == NON_INFERIORITY) for f in FINDINGS)
    with pytest.raises(ValueError, match="test must be"):
        Finding("x", "A ≈ B", "ours", ("a",), ("b",), "islands", test="equivalence")


# --- paper effects ---------------------------------------------------------------------

def test_paper_effects_from_table_ii():
    effects = {f.key: paper_effect(f) for f in FINDINGS}
    expected = {"uniform-loses-radar-only-tracks": (75.5, 37.2),  # 85.6 − 10.1, 61.4 − 24.2
                "uniform-is-worst": (25.5, 14.0),  # JPDA is closest: 67.5 − 42.0, 49.2 − 35.2
                "pd-aware-beats-radar-only": (5.8, 3.3),
                "context-beats-pd-aware": (1.3, 2.3),
                "context-beats-jpda": (13.9, 8.1)}
    for key, (hota, gospa) in expected.items():
        assert effects[key] == pytest.approx((hota, gospa), abs=1e-9), key
    # Our findings have no paper effect, nor has a paper finding without Table II rows.
    assert all(effects[f.key] is None for f in FINDINGS if f.source == "ours")
    assert paper_effect(Finding("x", "", "paper", ("gmphd-context",), ("jpda",), "islands")) is None
    assert paper_effect(Finding("y", "", "paper", ("gmphd-sight",), ("jpda",), "combined")) is None


# --- size verdict ----------------------------------------------------------------------

def test_size_verdict_by_hand():
    assert size_verdict(Interval(75.0, 70.0, 80.0), 75.5) == SIZE_INSIDE
    assert size_verdict(Interval(1.3, 1.3, 2.0), 1.3) == SIZE_INSIDE  # touching is inside
    assert size_verdict(Interval(29.1, 27.3, 30.9), 1.3) == SIZE_LARGER
    assert size_verdict(Interval(11.0, 10.1, 12.0), 75.5) == SIZE_SMALLER
    assert size_verdict(Interval(-74.2, -75.8, -72.6), 37.2) == SIZE_SMALLER
    assert size_verdict(Interval(3.0, 2.0, 4.0), None) == NO_PAPER_EFFECT == "—"
    assert size_verdict(Interval(3.0, math.nan, math.nan), 1.3) == INCONCLUSIVE


# --- one-sided tests -------------------------------------------------------------------

def test_one_sided_p_by_hand():
    # (1, 2, 3): t = 2 √3 on two degrees of freedom.
    assert one_sided_p(spread(2.0)) == pytest.approx(t2_tail(2 * math.sqrt(3)), rel=1e-10)
    # Against −2: t = (2 + 2) √3.
    assert one_sided_p(spread(2.0), null=-2.0) == pytest.approx(t2_tail(4 * math.sqrt(3)))
    assert one_sided_p(spread(0.0)) == pytest.approx(0.5)
    assert one_sided_p([1.0]) is None
    assert one_sided_p([3.0, 3.0]) == 0.0 and one_sided_p([-3.0, -3.0]) == 1.0


def test_superiority_is_one_sided_at_five_percent():
    # (1, 2, 3): the two-sided 95 % interval contains 0 (the old rule: inconclusive), the
    # one-sided 95 % bound 2 − 1.686 does not.
    assert verdict(t_interval(spread(2.0))) == INCONCLUSIVE
    test = one_sided_test(spread(2.0))
    assert test.null == 0.0 and test.lower == pytest.approx(2 - HALF)
    assert test.p == pytest.approx(t2_tail(2 * math.sqrt(3))) and 0.025 < test.p < 0.05
    assert test.verdict(test.p) == REPRODUCED
    # The same bound, the other way: not reproduced when the upper bound is below 0.
    against = one_sided_test(spread(-2.0))
    assert against.upper == pytest.approx(-2 + HALF) and against.verdict(against.p) == NOT_REPRODUCED
    assert one_sided_test([5.0]).verdict(None) == INCONCLUSIVE


@pytest.mark.parametrize("metric", ["hota", "gospa"])
def test_non_inferiority_at_the_margins(metric):
    margin = MARGINS[metric]
    # Non-inferior when the one-sided 95 % lower bound m − HALF is above −margin.
    edge = -margin + HALF
    inside, outside = one_sided_test(spread(edge + 0.01), NON_INFERIORITY, margin), \
        one_sided_test(spread(edge - 0.01), NON_INFERIORITY, margin)
    assert inside.null == -margin
    assert inside.lower == pytest.approx(-margin + 0.01)
    assert inside.p < 0.05 < outside.p  # the test and the bound agree (TOST's lower test)
    assert inside.verdict(inside.p) == NON_INFERIOR
    assert outside.verdict(outside.p) == INCONCLUSIVE
    # Inferior when the upper bound m + HALF is below −margin.
    edge = -margin - HALF
    below = one_sided_test(spread(edge - 0.01), NON_INFERIORITY, margin)
    above = one_sided_test(spread(edge + 0.01), NON_INFERIORITY, margin)
    assert below.upper == pytest.approx(-margin - 0.01)
    assert below.verdict(below.p) == INFERIOR and above.verdict(above.p) == INCONCLUSIVE
    # Its bounds are the two-sided 90 % interval's ends.
    ninety = t_interval(spread(edge), confidence=0.90)
    assert ninety.low == pytest.approx(edge - HALF) and ninety.high == pytest.approx(edge + HALF)
    with pytest.raises(ValueError, match="margin"):
        one_sided_test(spread(0.0), NON_INFERIORITY, 0.0)


def test_overall_verdicts_of_both_kinds():
    assert overall_verdict([NON_INFERIOR, NON_INFERIOR]) == NON_INFERIOR
    assert overall_verdict([NON_INFERIOR, INCONCLUSIVE]) == INCONCLUSIVE
    assert overall_verdict([NON_INFERIOR, INFERIOR]) == INFERIOR
    assert overall_verdict([REPRODUCED, NOT_REPRODUCED]) == NOT_REPRODUCED


# --- Holm ------------------------------------------------------------------------------

def holm_rejections(pvalues, alpha):
    """Holm's procedure as stated: step through the p-values in ascending order, reject
    while p_(k) ≤ α / (m − k + 1), stop at the first that is not."""
    order = sorted(range(len(pvalues)), key=lambda i: pvalues[i])
    rejected = set()
    for k, i in enumerate(order):
        if pvalues[i] > alpha / (len(pvalues) - k):
            break
        rejected.add(i)
    return rejected


def test_holm_on_known_p_values():
    # Sorted 0.005, 0.01, 0.03, 0.04 → 4·0.005, 3·0.01, 2·0.03, max(1·0.04, 0.06).
    assert holm([0.01, 0.04, 0.03, 0.005]) == pytest.approx([0.03, 0.06, 0.06, 0.02])
    assert holm([0.6, 0.7]) == [1.0, 1.0]  # capped at 1
    assert holm([None, 0.01, 0.04, None]) == [None, pytest.approx(0.02), pytest.approx(0.04), None]
    assert holm([]) == [] and holm([0.2]) == [0.2]
    with pytest.raises(ValueError):
        holm([1.5])


def test_holm_matches_the_step_down_procedure():
    rng = random.Random(7)
    for _ in range(200):
        p = [rng.choice([rng.random(), rng.random() / 50]) for _ in range(rng.randint(1, 24))]
        adjusted = holm(p)
        for alpha in (0.01, 0.05, 0.1):
            assert {i for i, q in enumerate(adjusted) if q <= alpha} == holm_rejections(p, alpha)
        assert all(a >= b for a, b in zip(adjusted, p))


# --- findings: constructed scores ------------------------------------------------------

def _by_key(scores: dict) -> dict:
    """{(tracker, scenario): [(hota %, gospa m), ...per seed]} -> job results."""
    return {(t, s, seed): SimpleNamespace(hota=SimpleNamespace(hota=h / 100),
                                          gospa=SimpleNamespace(rms=g))
            for (t, s), values in scores.items() for seed, (h, g) in enumerate(values)}


def _pair(a: str, b: str, hota_d, gospa_d, scope="mixed-range") -> dict:
    """Scores of ``a`` and ``b`` whose per-seed differences (positive: a better) are the
    given ones."""
    return {(b, scope): [(50.0, 30.0)] * len(hota_d),
            (a, scope): [(50.0 + h, 30.0 - g) for h, g in zip(hota_d, gospa_d)]}


def test_a_geq_finding_losing_half_a_point_is_non_inferior_where_the_old_rule_said_not():
    claim = Finding("a-matches-b", "A ≥ B", "ours", ("a",), ("b",), "mixed-range",
                    test=NON_INFERIORITY)
    scores = _by_key(_pair("a", "b", [-0.6, -0.5, -0.4], [-0.2, -0.1, 0.0]))
    result = evaluate(claim, scores)
    assert result.hota.mean == pytest.approx(-0.5)
    # The earlier editions: the interval lies below 0, so "not reproduced".
    assert verdict(result.hota) == NOT_REPRODUCED
    assert overall_verdict([verdict(result.hota), verdict(result.gospa)]) == NOT_REPRODUCED
    # Declared now: a loss of half a point ± 0.1 is well inside the 1-point margin.
    assert result.hota_stats.test.null == -1.0 and result.gospa_stats.test.null == -1.0
    assert (result.hota_verdict, result.gospa_verdict, result.verdict) == (NON_INFERIOR,) * 3
    # The same differences read as a superiority claim are not reproduced.
    strict = evaluate(Finding("a-beats-b", "A > B", "ours", ("a",), ("b",), "mixed-range"),
                      scores)
    assert strict.verdict == NOT_REPRODUCED


def test_holm_over_the_family_can_undo_an_unadjusted_win():
    first = Finding("a-beats-b", "A > B", "ours", ("a",), ("b",), "mixed-range")
    second = Finding("c-beats-d", "C > D", "ours", ("c",), ("d",), "mixed-range")
    scores = _by_key({**_pair("a", "b", spread(2.0), spread(10.0)),
                      **_pair("c", "d", spread(0.0), spread(0.0))})
    p_hota = t2_tail(2 * math.sqrt(3))  # ≈ 0.0371
    p_gospa = t2_tail(10 * math.sqrt(3))
    alone = evaluate(first, scores)
    # Alone (a family of its two metrics): 2·p_gospa, then max(that, 1·p_hota).
    assert alone.hota_stats.test.p == pytest.approx(p_hota)
    assert alone.hota_stats.p_holm == pytest.approx(p_hota)
    assert alone.gospa_stats.p_holm == pytest.approx(2 * p_gospa)
    assert alone.verdict == REPRODUCED
    together = evaluate_all(scores, (first, second))
    a, c = together
    # Four tests: p_gospa·4, p_hota·3, then 0.5·2 → 1 (capped) twice.
    assert a.gospa_stats.p_holm == pytest.approx(4 * p_gospa)
    assert a.hota_stats.p_holm == pytest.approx(3 * p_hota)
    assert c.hota_stats.p_holm == c.gospa_stats.p_holm == 1.0
    assert a.hota_stats.unadjusted == REPRODUCED and a.hota_verdict == INCONCLUSIVE
    assert (a.gospa_verdict, a.verdict) == (REPRODUCED, INCONCLUSIVE)
    assert c.verdict == INCONCLUSIVE
    # The as_dict and the tables carry both p-values.
    record = a.as_dict()
    assert record["hota_test"]["p"] == pytest.approx(p_hota)
    assert record["hota_test"]["p_holm"] == pytest.approx(3 * p_hota)
    assert record["hota_test"]["verdict_unadjusted"] == REPRODUCED
    text = findings_markdown(together)
    assert f"{p_hota:.4f} / {3 * p_hota:.4f}" in text


def test_one_seed_has_no_p_value_and_is_not_in_the_family():
    first = Finding("a-beats-b", "A > B", "ours", ("a",), ("b",), "mixed-range")
    lone = Finding("c-beats-d", "C > D", "ours", ("c",), ("d",), "formation")
    scores = _by_key({**_pair("a", "b", spread(2.0), spread(10.0)),
                      **_pair("c", "d", [40.0], [40.0], scope="formation")})
    a, c = evaluate_all(scores, (first, lone))
    assert c.hota_stats.test.p is None and c.hota_stats.p_holm is None
    assert (c.hota_verdict, c.gospa_verdict, c.verdict) == (INCONCLUSIVE,) * 3
    assert a.hota_stats.p_holm == pytest.approx(a.hota_stats.test.p)  # a family of two


def test_paper_finding_reports_its_size():
    finding = next(f for f in FINDINGS if f.key == "pd-aware-beats-radar-only")
    # HOTA about the paper's, GOSPA far more. (The combined scope needs real HOTA results
    # to aggregate: the same finding on Scenario 1 instead.)
    scores = _by_key(_pair("gmphd-pd-aware", "gmphd-radar-only", spread(6.0), spread(21.0)))
    one = Finding(finding.key, finding.claim, "paper", finding.better, finding.worse,
                  "mixed-range")
    result = evaluate(one, scores)
    effect = paper_effect(one)
    assert effect == pytest.approx((89.5 - 85.6, 24.2 - 22.1))
    assert result.hota_stats.paper == pytest.approx(effect[0])
    assert result.hota_stats.size == SIZE_INSIDE  # 3.9 in 6 ± 2.5
    assert result.gospa_stats.size == SIZE_LARGER  # 21 ± 2.5 above 2.1
    assert result.as_dict()["paper_effect"] == pytest.approx({"hota": 3.9, "gospa": 2.1})
    text = findings_markdown([result])
    assert f"| +3.9 | {SIZE_INSIDE} |" in text and f"| +2.1 | {SIZE_LARGER} |" in text
    ours = evaluate(Finding("a-beats-b", "A > B", "ours", ("a",), ("b",), "mixed-range"),
                    _by_key(_pair("a", "b", spread(2.0), spread(2.0))))
    assert ours.hota_stats.size == NO_PAPER_EFFECT and ours.as_dict()["paper_effect"] is None


# --- the summary figure: the findings table's signs and verdicts -----------------------

def test_summary_figure_draws_the_findings_table(tmp_path):
    # A finding that wins HOTA and loses GOSPA, like radar-only − uniform on S1 in the
    # study's run (HOTA +11, GOSPA −74): each panel shows its own verdict, GOSPA with the
    # table's sign.
    finding = next(f for f in FINDINGS if f.key == "uniform-loses-radar-only-tracks")
    scores = _by_key(_pair("gmphd-radar-only", "gmphd-uniform", spread(11.0), spread(-74.0)))
    result, = evaluate_all(scores, (finding,))
    assert (result.hota_verdict, result.gospa_verdict, result.verdict) == \
        (REPRODUCED, NOT_REPRODUCED, NOT_REPRODUCED)
    score = {"hota": Interval(50.0, 45.0, 55.0), "gospa": Interval(30.0, 28.0, 32.0)}
    fake = SimpleNamespace(
        scores=lambda: [{"tracker": "gmphd-radar-only", "label": "GM-PHD (radar only)",
                         "mixed-range": score},
                        {"tracker": "gmphd-uniform", "label": "GM-PHD (uniform)",
                         "mixed-range": score}],
        management=lambda: [{"tracker": "gmphd-radar-only", "scope": "mixed-range",
                             "false_tracks_per_scan": 0.4, "tracked_percent": 95.0}],
        findings=lambda: [result], scopes=lambda: ["mixed-range"],
        config=SimpleNamespace(seeds=(0, 1, 2)))
    (scope, fields), = figures._summaries(fake)
    assert scope == "mixed-range"
    # the track-management row per tracker: the uniform GM-PHD has no row here (NaN)
    assert list(fields["false_tracks"][:1]) == [0.4] and np.isnan(fields["false_tracks"][1])
    assert list(fields["tracked"][:1]) == [95.0]
    assert tuple(fields["gospa_diff"][0]) == pytest.approx(
        (result.gospa.mean, result.gospa.low, result.gospa.high))
    assert fields["gospa_diff"][0][0] == pytest.approx(-74.0)  # as the table: not +74
    assert list(fields["hota_paper"]) == pytest.approx([75.5])
    fig = summary_plots._figure_summary(**fields)
    *_, d_hota, d_gospa = fig.axes  # scores, track management, then the differences
    for ax, interval, verdict_ in ((d_hota, result.hota, REPRODUCED),
                                   (d_gospa, result.gospa, NOT_REPRODUCED)):
        (container,) = ax.containers
        point = container.lines[0]
        assert point.get_xdata()[0] == pytest.approx(interval.mean)
        assert point.get_marker() == summary_plots.VERDICT_STYLES[verdict_]["marker"]
        assert point.get_color() == summary_plots.VERDICT_STYLES[verdict_]["color"]
    # The paper's effect beside it, on the same signed axis.
    paper = [line for line in d_gospa.lines if line.get_gid() == "paper-GOSPA"]
    assert len(paper) == 1 and paper[0].get_xdata()[0] == pytest.approx(37.2)
    assert "B − A" in d_gospa.get_title() and "A better →" in d_gospa.get_title()
    figures._draw_summary(tmp_path, scope, fields)
    assert (tmp_path / "summary_mixed-range.png").stat().st_size > 0
