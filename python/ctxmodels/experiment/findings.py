"""The paper's findings (and some of ours) as paired comparisons with computed verdicts.

Each :class:`Finding` says "every tracker in ``better`` beats every tracker in ``worse``"
on one *scope*: a scenario, or ``"combined"`` (Scenarios 1 and 2 aggregated per seed as
the paper's Table II does: HOTA with TrackEval's multi-sequence aggregation, GOSPA as the
RMS over all evaluation times). Per seed, the finding's difference is the smallest of its
pairwise differences — for "uniform is worst", the margin to the closest competitor — so
it is positive on a seed only if the claim holds on that seed for every pair. Mean,
paired interval and verdict follow :mod:`ctxmodels.experiment.statistics`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import metrics
from .statistics import (INCONCLUSIVE, Interval, overall_verdict, t_interval, verdict)

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

    @property
    def trackers(self) -> tuple[str, ...]:
        return self.better + self.worse


FINDINGS: tuple[Finding, ...] = (
    Finding("uniform-loses-radar-only-tracks",
            "uniform P_D/λ loses the radar-only tracks: radar-only GM-PHD > uniform (S1)",
            "paper", ("gmphd-radar-only",), ("gmphd-uniform",), "mixed-range",
            "radar-only − uniform (S1)"),
    Finding("uniform-is-worst",
            "the uniform GM-PHD is the worst of the paper's five (margin to the closest)",
            "paper", ("jpda", "gmphd-radar-only", "gmphd-pd-aware", "gmphd-context"),
            ("gmphd-uniform",), COMBINED, "closest other − uniform"),
    Finding("pd-aware-beats-radar-only", "P_D-aware GM-PHD > radar-only", "paper",
            ("gmphd-pd-aware",), ("gmphd-radar-only",), COMBINED, "P_D-aware − radar-only"),
    Finding("context-beats-pd-aware", "context-aware GM-PHD ≥ P_D-aware", "paper",
            ("gmphd-context",), ("gmphd-pd-aware",), COMBINED, "context − P_D-aware"),
    Finding("context-beats-jpda", "context-aware GM-PHD > JPDA", "paper",
            ("gmphd-context",), ("jpda",), COMBINED, "context − JPDA"),
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
            "learned-λ GM-PHD ≥ context-aware (the paper's λ, here the simulation's truth)",
            "ours", ("gmphd-learned-clutter",), ("gmphd-context",), COMBINED,
            "learned λ − context"),
    Finding("learned-matches-context",
            "learned-λ-and-P_D GM-PHD ≥ context-aware (the paper's λ and P_D: the truth)",
            "ours", ("gmphd-learned",), ("gmphd-context",), COMBINED,
            "learned λ, P_D − context"),
    Finding("learned-beats-context-on-coasts",
            "learned-λ-and-P_D GM-PHD > context-aware (S3: coastal returns)", "ours",
            ("gmphd-learned",), ("gmphd-context",), "islands",
            "learned λ, P_D − context (S3)"),
)


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
class FindingResult:
    finding: Finding
    seeds: tuple[int, ...]
    hota: Interval | None  # None: not run (a tracker or scenario is missing)
    gospa: Interval | None
    hota_verdict: str
    gospa_verdict: str
    verdict: str

    def as_dict(self) -> dict:
        f = self.finding
        return {"key": f.key, "claim": f.claim, "source": f.source, "scope": f.scope,
                "better": list(f.better), "worse": list(f.worse), "seeds": list(self.seeds),
                "hota_difference": self.hota.as_dict() if self.hota else None,
                "gospa_difference": self.gospa.as_dict() if self.gospa else None,
                "hota_verdict": self.hota_verdict, "gospa_verdict": self.gospa_verdict,
                "verdict": self.verdict}


NOT_RUN = "not run"


def evaluate(finding: Finding, by_key: dict) -> FindingResult:
    """The finding's paired differences (positive supports it) and verdicts."""
    scores = {t: seed_scores(by_key, t, finding.scope) for t in finding.trackers}
    common = sorted(set.intersection(*(set(s) for s in scores.values())))
    if not common:
        return FindingResult(finding, (), None, None, NOT_RUN, NOT_RUN, NOT_RUN)
    hota_d = np.array([min(scores[b][s][0] - scores[w][s][0]
                           for b in finding.better for w in finding.worse) for s in common])
    gospa_d = np.array([min(scores[w][s][1] - scores[b][s][1]
                            for b in finding.better for w in finding.worse) for s in common])
    hota, gospa = t_interval(hota_d), t_interval(gospa_d)
    verdicts = (verdict(hota), verdict(gospa))
    return FindingResult(finding, tuple(common), hota, gospa, *verdicts,
                         overall_verdict(verdicts))


def evaluate_all(by_key: dict, findings=FINDINGS) -> list[FindingResult]:
    return [evaluate(f, by_key) for f in findings]


def findings_markdown(results: list[FindingResult]) -> str:
    """The findings table: paired differences (positive supports the claim) and verdicts."""
    lines = ["| Finding | Source | Scope | ΔHOTA (pp) [95 % CI] | ΔGOSPA (m) [95 % CI] | Verdict |",
             "|---|---|---|---|---|---|"]

    def cell(interval):
        if interval is None:
            return "—"
        if math.isnan(interval.low):
            return f"{interval.mean:+.1f}"
        return f"{interval.mean:+.1f} [{interval.low:+.1f}, {interval.high:+.1f}]"

    for r in results:
        f = r.finding
        scope = {"mixed-range": "S1", "formation": "S2", "islands": "S3",
                 COMBINED: "S1+S2"}.get(f.scope, f.scope)
        detail = "" if r.verdict in (NOT_RUN,) or r.hota_verdict == r.gospa_verdict else \
            f" (HOTA {r.hota_verdict}, GOSPA {r.gospa_verdict})"
        lines.append(f"| {f.claim} | {f.source} | {scope} | {cell(r.hota)} | {cell(r.gospa)} | "
                     f"**{r.verdict}**{detail} |")
    lines += ["", "Differences are paired by seed and signed so that positive supports the "
              "claim (ΔGOSPA = the other tracker's GOSPA minus the claimed better one's); "
              "interval: paired t over seeds. Verdict: reproduced when the interval of both "
              "metrics lies above 0, not reproduced when either lies below 0, otherwise "
              f"{INCONCLUSIVE}."]
    return "\n".join(lines)
