"""The paper's findings (and some of ours) as paired comparisons with computed verdicts.

Each :class:`Finding` says "every tracker in ``better`` beats every tracker in ``worse``"
on one *scope*: a scenario, or ``"combined"`` (Scenarios 1 and 2 aggregated per seed as
the paper's Table II does: HOTA with TrackEval's multi-sequence aggregation, GOSPA as the
RMS over all evaluation times). Per seed, the finding's difference is the smallest of its
pairwise differences — for "uniform is worst", the margin to the closest competitor — so
it is positive on a seed only if the claim holds on that seed for every pair. Mean,
paired interval, the declared one-sided test (superiority for "A > B", non-inferiority with
the margins of :data:`~.statistics.MARGINS` for "A ≥ B"), Holm's correction over all
findings × both metrics, and the size verdict against the paper's own effect
(:func:`paper_effect`) follow :mod:`ctxmodels.experiment.statistics`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import metrics
from .paper import PAPER_JPDA, paper_row
from .solent.scene import DISTANCE_SCALE as SOLENT_SCALE
from .statistics import (ALPHA, MARGINS, NO_PAPER_EFFECT, NON_INFERIORITY, SUPERIORITY,
                         Interval, OneSidedTest, holm, one_sided_test, overall_verdict,
                         size_verdict, t_interval)

COMBINED = "combined"
#: The scenarios the paper's combined score aggregates.
COMBINED_SCENARIOS = ("mixed-range", "formation")


@dataclass(frozen=True)
class Finding:
    key: str
    claim: str
    source: str  # "paper" or "ours"
    better: tuple[str, ...]
    worse: tuple[str, ...]
    scope: str  # a scenario name or COMBINED
    short: str = ""  # "A − B" for figures
    #: SUPERIORITY ("A > B": H0 Δ ≤ 0) or NON_INFERIORITY ("A ≥ B": H0 Δ ≤ −margin).
    test: str = SUPERIORITY
    #: Where the paper's own effect of the claim is read (its Table II scope), when that is
    #: not ``scope``: the Solent replicates claims the paper made on its own scenarios.
    paper_scope: str | None = None
    #: The GOSPA margin's scale: a scene whose scores' distances are the paper's × this
    #: (the Solent: 10, see its run's ``distance_scale``).
    distance_scale: float = 1.0

    def __post_init__(self):
        if self.test not in (SUPERIORITY, NON_INFERIORITY):
            raise ValueError(f"{self.key}: test must be {SUPERIORITY!r} or "
                             f"{NON_INFERIORITY!r}, got {self.test!r}")

    @property
    def trackers(self) -> tuple[str, ...]:
        return self.better + self.worse

    def margin(self, metric: str) -> float:
        """The non-inferiority margin of ``metric`` ("hota"/"gospa", the latter times
        ``distance_scale``); 0 for superiority."""
        if self.test != NON_INFERIORITY:
            return 0.0
        return MARGINS[metric] * (self.distance_scale if metric == "gospa" else 1.0)


FINDINGS: tuple[Finding, ...] = (
    Finding("uniform-loses-radar-only-tracks",
            "uniform P_D/λ loses the radar-only tracks: radar-only GM-PHD > uniform (S1)",
            "paper", ("gmphd-radar-only",), ("gmphd-uniform",), "mixed-range",
            "radar-only − uniform (S1)"),
    Finding("uniform-is-worst",
            "the uniform GM-PHD is the worst of the paper's five (margin to the closest)",
            "paper", (PAPER_JPDA, "gmphd-radar-only", "gmphd-pd-aware", "gmphd-context"),
            ("gmphd-uniform",), COMBINED, "closest other − uniform"),
    Finding("pd-aware-beats-radar-only", "P_D-aware GM-PHD > radar-only", "paper",
            ("gmphd-pd-aware",), ("gmphd-radar-only",), COMBINED, "P_D-aware − radar-only"),
    Finding("context-beats-pd-aware", "context-aware GM-PHD ≥ P_D-aware", "paper",
            ("gmphd-context",), ("gmphd-pd-aware",), COMBINED, "context − P_D-aware", test=NON_INFERIORITY),
    Finding("context-beats-jpda",
            "context-aware GM-PHD > JPDA (the better of literal and tuned: the tuned)", "paper",
            ("gmphd-context",), (PAPER_JPDA,), COMBINED, "context − tuned JPDA"),
    Finding("context-jpda-beats-jpda", "context-aware JPDA > JPDA", "ours",
            ("jpda-context",), ("jpda",), COMBINED, "context JPDA − JPDA"),
    Finding("sight-beats-context", "line-of-sight GM-PHD > context-aware (S3)", "ours",
            ("gmphd-sight",), ("gmphd-context",), "islands", "line of sight − context (S3)"),
    Finding("coastal-beats-sight",
            "coastal-λ GM-PHD > line-of-sight (S3: a hand-written coastal band)", "ours",
            ("gmphd-coastal",), ("gmphd-sight",), "islands", "coastal λ − line of sight (S3)"),
    # Learned observability (the radar's clutter map and P_D bands, learned online from the
    # tracker's own output):
    Finding("learned-beats-pd-aware",
            "learned-λ GM-PHD > P_D-aware (λ 1e-3, the map's prior)", "ours",
            ("gmphd-learned-clutter",), ("gmphd-pd-aware",), COMBINED,
            "learned λ − P_D-aware"),
    Finding("learned-clutter-matches-context",
            "learned-λ GM-PHD ≥ context-aware (the paper's λ)",
            "ours", ("gmphd-learned-clutter",), ("gmphd-context",), COMBINED,
            "learned λ − context", test=NON_INFERIORITY),
    Finding("learned-matches-context",
            "learned-λ-and-P_D GM-PHD ≥ context-aware (the paper's λ and P_D)",
            "ours", ("gmphd-learned",), ("gmphd-context",), COMBINED,
            "learned λ, P_D − context", test=NON_INFERIORITY),
    Finding("learned-beats-context-on-coasts",
            "learned-λ-and-P_D GM-PHD > context-aware (S3: coastal returns)", "ours",
            ("gmphd-learned",), ("gmphd-context",), "islands",
            "learned λ, P_D − context (S3)"),
    # The Solent (real coast, real traffic; declared before its confirmatory run): the
    # paper's two mechanism claims replicated, and the real geography's own.
    Finding("solent-uniform-loses-tracks",
            "uniform P_D loses what only the Foreland sees: radar-only GM-PHD > uniform "
            "(Solent)", "paper", ("gmphd-radar-only",), ("gmphd-uniform",), "solent",
            "radar-only − uniform (Solent)", paper_scope="mixed-range", distance_scale=SOLENT_SCALE),
    Finding("solent-pd-aware-beats-radar-only", "P_D-aware GM-PHD > radar-only (Solent)",
            "paper", ("gmphd-pd-aware",), ("gmphd-radar-only",), "solent",
            "P_D-aware − radar-only (Solent)", paper_scope=COMBINED, distance_scale=SOLENT_SCALE),
    Finding("solent-sight-beats-pd-aware",
            "line-of-sight GM-PHD (land, shadows, horizon) > P_D-aware range bands (Solent)",
            "ours", ("gmphd-sight",), ("gmphd-pd-aware",), "solent",
            "line of sight − P_D-aware (Solent)", distance_scale=SOLENT_SCALE),
    Finding("solent-learned-matches-sight",
            "learned-λ-and-P_D GM-PHD ≥ line-of-sight (Solent)", "ours",
            ("gmphd-learned",), ("gmphd-sight",), "solent",
            "learned λ, P_D − line of sight (Solent)", test=NON_INFERIORITY, distance_scale=SOLENT_SCALE),
)


def paper_effect(finding: Finding) -> tuple[float, float] | None:
    """The paper's own (ΔHOTA pp, ΔGOSPA m) for ``finding``, from its Table II on the
    finding's scope (or ``paper_scope``; GOSPA times ``distance_scale``) by the simulated
    difference's rule (the smallest over better/worse
    pairs; GOSPA as worse − better); None for our findings and wherever Table II has no
    row for a tracker or the scope."""
    if finding.source != "paper":
        return None
    scope = finding.paper_scope or finding.scope
    row = {t: paper_row(t).get(scope) for t in finding.trackers}
    if any(score is None for score in row.values()):
        return None
    # (Rounded off the float noise of subtracting one-decimal table entries.)
    # (GOSPA in the finding's scene's metres: the paper's times its distance scale)
    return (round(min(row[b].hota - row[w].hota
                      for b in finding.better for w in finding.worse), 6),
            round(finding.distance_scale * min(row[w].gospa - row[b].gospa
                                               for b in finding.better for w in finding.worse), 6))


def seed_scores(by_key: dict, tracker: str, scope: str) -> dict[int, tuple[float, float]]:
    """``{seed: (HOTA %, GOSPA m)}`` of ``tracker`` on ``scope``, from job results keyed by
    ``(tracker, scenario, seed)``; seeds missing a needed scenario are left out."""
    seeds = sorted({seed for (t, _, seed) in by_key if t == tracker})
    scores = {}
    for seed in seeds:
        if scope == COMBINED:
            parts = [by_key.get((tracker, s, seed)) for s in COMBINED_SCENARIOS]
            if any(p is None for p in parts):
                continue
            scores[seed] = (100 * metrics.combine_hota([p.hota for p in parts]).hota,
                            metrics.combine_gospa([p.gospa for p in parts]).rms)
        elif (tracker, scope, seed) in by_key:
            result = by_key[(tracker, scope, seed)]
            scores[seed] = (100 * result.hota.hota, result.gospa.rms)
    return scores


@dataclass(frozen=True)
class MetricStats:
    """One metric of one finding: the declared test, its raw and Holm-adjusted p-values and
    verdicts, and the paper's effect with the size verdict."""

    test: OneSidedTest
    p_holm: float | None  # None: no p-value (fewer than two seeds)
    verdict: str  # with the Holm-adjusted p-value: the finding's verdict on this metric
    unadjusted: str  # with the raw p-value (no multiplicity correction)
    paper: float | None  # the paper's effect; None: no Table II row
    size: str

    def as_dict(self) -> dict:
        return {"test": self.test.kind, "null": self.test.null, "p": self.test.p,
                "p_holm": self.p_holm, "one_sided_lower": self.test.lower,
                "one_sided_upper": self.test.upper, "verdict": self.verdict,
                "verdict_unadjusted": self.unadjusted, "paper_effect": self.paper,
                "size_verdict": self.size}


@dataclass(frozen=True)
class FindingResult:
    finding: Finding
    seeds: tuple[int, ...]
    hota: Interval | None  # None: not run (a tracker or scenario is missing)
    gospa: Interval | None
    hota_verdict: str  # after Holm's correction (see MetricStats)
    gospa_verdict: str
    verdict: str
    hota_stats: MetricStats | None = None  # None: not run
    gospa_stats: MetricStats | None = None

    def as_dict(self) -> dict:
        f = self.finding
        paper = paper_effect(f)
        return {"key": f.key, "claim": f.claim, "source": f.source, "scope": f.scope,
                "better": list(f.better), "worse": list(f.worse), "test": f.test,
                "margin": {m: f.margin(m) for m in ("hota", "gospa")},
                "seeds": list(self.seeds),
                "hota_difference": self.hota.as_dict() if self.hota else None,
                "gospa_difference": self.gospa.as_dict() if self.gospa else None,
                "paper_effect": {"hota": paper[0], "gospa": paper[1]} if paper else None,
                "hota_test": self.hota_stats.as_dict() if self.hota_stats else None,
                "gospa_test": self.gospa_stats.as_dict() if self.gospa_stats else None,
                "hota_verdict": self.hota_verdict, "gospa_verdict": self.gospa_verdict,
                "verdict": self.verdict}


NOT_RUN = "not run"


@dataclass(frozen=True)
class _Raw:
    """A finding's differences and unadjusted tests, before Holm's correction."""

    finding: Finding
    seeds: tuple[int, ...]
    intervals: tuple[Interval, Interval] | None
    tests: tuple[OneSidedTest, OneSidedTest] | None


def _raw(finding: Finding, by_key: dict) -> _Raw:
    scores = {t: seed_scores(by_key, t, finding.scope) for t in finding.trackers}
    common = sorted(set.intersection(*(set(s) for s in scores.values())))
    if not common:
        return _Raw(finding, (), None, None)
    hota_d = np.array([min(scores[b][s][0] - scores[w][s][0]
                           for b in finding.better for w in finding.worse) for s in common])
    gospa_d = np.array([min(scores[w][s][1] - scores[b][s][1]
                            for b in finding.better for w in finding.worse) for s in common])
    return _Raw(finding, tuple(common), (t_interval(hota_d), t_interval(gospa_d)),
                tuple(one_sided_test(d, finding.test, finding.margin(m))
                      for d, m in ((hota_d, "hota"), (gospa_d, "gospa"))))


def _adjusted(raws: list[_Raw], alpha: float = ALPHA) -> list[FindingResult]:
    """Holm's correction over every test of ``raws`` (findings × metrics)."""
    tests = [t for r in raws if r.tests for t in r.tests]
    adjusted = iter(holm([t.p for t in tests]))
    results = []
    for r in raws:
        if r.tests is None:
            results.append(FindingResult(r.finding, (), None, None, NOT_RUN, NOT_RUN, NOT_RUN))
            continue
        paper = paper_effect(r.finding) or (None, None)
        stats = []
        for test, interval, effect in zip(r.tests, r.intervals, paper):
            p_holm = next(adjusted)
            stats.append(MetricStats(test, p_holm, test.verdict(p_holm, alpha),
                                     test.verdict(test.p, alpha), effect,
                                     size_verdict(interval, effect)))
        verdicts = (stats[0].verdict, stats[1].verdict)
        results.append(FindingResult(r.finding, r.seeds, *r.intervals, *verdicts,
                                     overall_verdict(verdicts), *stats))
    return results


def evaluate(finding: Finding, by_key: dict) -> FindingResult:
    """The finding's paired differences (positive supports it), tests and verdicts, on its
    own: Holm's correction over its two metrics only. The study evaluates all findings
    together (:func:`evaluate_all`)."""
    return _adjusted([_raw(finding, by_key)])[0]


def evaluate_all(by_key: dict, findings=FINDINGS) -> list[FindingResult]:
    """Every finding, with Holm's correction over the whole family (findings × metrics)."""
    return _adjusted([_raw(f, by_key) for f in findings])


def _p(value: float | None) -> str:
    if value is None:
        return "—"
    return "<0.0001" if value < 1e-4 else f"{value:.4f}"


def _interval_cell(interval) -> str:
    if interval is None:
        return "—"
    if math.isnan(interval.low):
        return f"{interval.mean:+.1f}"
    return f"{interval.mean:+.1f} [{interval.low:+.1f}, {interval.high:+.1f}]"


def _scope_label(scope: str) -> str:
    return {"mixed-range": "S1", "formation": "S2", "islands": "S3", "solent": "S4",
            COMBINED: "S1+S2"}.get(scope, scope)


def _test_label(finding: Finding) -> str:
    if finding.test == SUPERIORITY:
        return "> (H0: Δ ≤ 0)"
    return f"≥ (H0: Δ ≤ −{finding.margin('hota'):g} pp / −{finding.margin('gospa'):g} m)"


def findings_markdown(results: list[FindingResult]) -> str:
    """The findings tables: paired differences (positive supports the claim), the declared
    tests with raw and Holm-adjusted p-values and verdicts; then the simulated effects
    beside the paper's, with the size verdicts."""
    lines = ["| Finding | Source | Scope | Test | ΔHOTA (pp) [95 % CI] | p HOTA (raw / Holm) | "
             "ΔGOSPA (m) [95 % CI] | p GOSPA (raw / Holm) | Verdict |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        f = r.finding
        detail = "" if r.verdict == NOT_RUN or r.hota_verdict == r.gospa_verdict else \
            f" (HOTA {r.hota_verdict}, GOSPA {r.gospa_verdict})"
        p = ["—" if s is None else f"{_p(s.test.p)} / {_p(s.p_holm)}"
             for s in (r.hota_stats, r.gospa_stats)]
        lines.append(f"| {f.claim} | {f.source} | {_scope_label(f.scope)} | {_test_label(f)} | "
                     f"{_interval_cell(r.hota)} | {p[0]} | {_interval_cell(r.gospa)} | {p[1]} | "
                     f"**{r.verdict}**{detail} |")
    lines += ["", "Differences are paired by seed and signed so that positive supports the "
              "claim (ΔGOSPA = the other tracker's GOSPA minus the claimed better one's); "
              "interval: two-sided 95 % paired t over seeds, unadjusted. Tests, declared "
              "before the run: \">\" findings by a one-sided paired t-test of H0: Δ ≤ 0, \"≥\" "
              f"findings by a non-inferiority test of H0: Δ ≤ −margin (margins "
              f"{MARGINS['hota']:g} HOTA points and {MARGINS['gospa']:g} m GOSPA, the GOSPA "
              f"margin times a scene's distance scale: {MARGINS['gospa'] * SOLENT_SCALE:g} m on "
              f"the Solent), each at 5 %; "
              "p-values Holm-adjusted over all findings × both metrics (family-wise 5 %). A "
              "metric is reproduced / non-inferior when its Holm-adjusted p is below 0.05, not "
              "reproduced / inferior when its one-sided 95 % upper bound lies below 0 / "
              "−margin, otherwise inconclusive; a finding is reproduced / non-inferior when "
              "both metrics are, not reproduced / inferior when either is."]
    lines += ["", "Effect sizes against the paper's Table II (the paper's effect by the same "
              "rule: the smallest over the finding's pairs; GOSPA as worse − better):", "",
              "| Finding | Scope | ΔHOTA (pp) [95 % CI] | paper | HOTA size | "
              "ΔGOSPA (m) [95 % CI] | paper | GOSPA size |",
              "|---|---|---|---|---|---|---|---|"]
    for r in results:
        f = r.finding
        paper = paper_effect(f)
        cells = []
        for i, (interval, stats) in enumerate(((r.hota, r.hota_stats), (r.gospa, r.gospa_stats))):
            effect = "—" if paper is None else f"{paper[i]:+.1f}"
            size = stats.size if stats else (NO_PAPER_EFFECT if paper is None else NOT_RUN)
            cells.append(f"{_interval_cell(interval)} | {effect} | {size}")
        lines.append(f"| {f.claim} | {_scope_label(f.scope)} | {cells[0]} | {cells[1]} |")
    lines += ["", "Size verdict: the paper's effect inside the simulated difference's 95 % "
              "interval, or the interval entirely above it (simulated effect larger) or below "
              "it (smaller); descriptive, not adjusted for multiplicity. \"—\": the paper "
              "reports no such effect (our findings)."]
    return "\n".join(lines)
