r"""Statistics over seeds: per-tracker intervals, paired differences and the findings' verdicts.

Every tracker runs on the same seeded scenarios, so two trackers are compared *paired by
seed*: the seed fixes every detection, clutter point and noise draw both trackers see, and
the difference of their scores on one seed is free of the scenario-to-scenario spread
that dominates each tracker's own interval.

Per-tracker interval
    Percentile bootstrap of the mean over seeds (:data:`BOOTSTRAP_RESAMPLES` resamples of
    the seeds with replacement; the 2.5 and 97.5 percentiles of the resampled means). A
    resampled mean lies between the smallest and largest score, so the interval stays inside
    the metric's range (HOTA in [0, 100] %, GOSPA ≥ 0) — unlike mean ± t·s on few seeds. The
    resampling draws come from a fixed generator: the same scores give the same interval.

Paired difference
    For a finding "A beats B", :math:`d_s` is A's score minus B's on seed :math:`s`, signed
    so that positive means A is better (HOTA: :math:`h_A - h_B`; GOSPA, lower is better:
    :math:`g_B - g_A`). The interval is Student's t on the differences,
    :math:`\bar d \pm t_{0.975,\,n-1}\, s_d / \sqrt{n}` — the paired t-test's interval, which
    keeps its 95 % coverage on 10 seeds, where the percentile bootstrap is known to cover
    less. Differences are not bounded the way scores are, so no bootstrap is needed to
    keep them in range.

Verdict (per metric)
    *reproduced* when the whole interval lies above 0 (A better), *not reproduced* when it
    lies below 0 (B better), *inconclusive* when it contains 0 or fewer than two seeds ran.
    A finding's overall verdict is *reproduced* when both HOTA and GOSPA reproduce it, *not
    reproduced* when either metric shows the opposite, and *inconclusive* otherwise.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

BOOTSTRAP_RESAMPLES = 10_000
#: Fixed seed of the bootstrap's resampling: identical scores give identical intervals.
BOOTSTRAP_SEED = 20_240_601
CONFIDENCE = 0.95

REPRODUCED = "reproduced"
NOT_REPRODUCED = "not reproduced"
INCONCLUSIVE = "inconclusive"


@dataclass(frozen=True)
class Interval:
    mean: float
    low: float
    high: float

    def as_dict(self) -> dict:
        return {"mean": self.mean, "low": self.low, "high": self.high}

    def excludes_zero(self) -> bool:
        return self.low > 0 or self.high < 0


def _finite(values, name: str) -> np.ndarray:
    values = np.asarray(values, dtype=float).reshape(-1)
    if not np.all(np.isfinite(values)):
        raise ValueError(f"{name} must be finite, got {values.tolist()}")
    return values


def bootstrap_mean(values: Sequence[float], resamples: int = BOOTSTRAP_RESAMPLES,
                   seed: int = BOOTSTRAP_SEED) -> Interval:
    """Mean of ``values`` with its percentile-bootstrap 95 % interval (NaN bounds for fewer
    than two values)."""
    values = _finite(values, "values")
    if values.size == 0:
        raise ValueError("values must not be empty")
    mean = float(np.mean(values))
    if values.size < 2:
        return Interval(mean, math.nan, math.nan)
    rng = np.random.default_rng(seed)
    picks = rng.integers(0, values.size, size=(resamples, values.size))
    means = values[picks].mean(axis=1)
    tail = 100 * (1 - CONFIDENCE) / 2
    low, high = np.percentile(means, [tail, 100 - tail])
    # Rounding in the resampled means must not step outside the data's range.
    return Interval(mean, float(max(low, values.min())), float(min(high, values.max())))


def paired_difference(better: Sequence[float], worse: Sequence[float],
                      lower_is_better: bool = False) -> Interval:
    """Mean of the per-seed differences ``better − worse`` (negated when lower scores are
    better, so positive always favours ``better``) with its paired-t 95 % interval."""
    a, b = _finite(better, "better"), _finite(worse, "worse")
    if a.shape != b.shape:
        raise ValueError(f"paired scores need one value per seed on both sides, got "
                         f"{a.size} and {b.size}")
    if a.size == 0:
        raise ValueError("paired scores must not be empty")
    return t_interval(b - a if lower_is_better else a - b)


def t_interval(differences: Sequence[float]) -> Interval:
    """Mean with the Student-t 95 % interval (NaN bounds for fewer than two values)."""
    d = _finite(differences, "differences")
    mean = float(np.mean(d))
    if d.size < 2:
        return Interval(mean, math.nan, math.nan)
    from scipy.stats import t
    half = float(t.ppf(0.5 + CONFIDENCE / 2, d.size - 1) * np.std(d, ddof=1) / math.sqrt(d.size))
    return Interval(mean, mean - half, mean + half)


def verdict(interval: Interval) -> str:
    """reproduced / not reproduced / inconclusive for a difference signed so that positive
    supports the finding (see the module docs)."""
    if math.isnan(interval.low) or math.isnan(interval.high):
        return INCONCLUSIVE
    if interval.low > 0:
        return REPRODUCED
    if interval.high < 0:
        return NOT_REPRODUCED
    return INCONCLUSIVE


def overall_verdict(verdicts: Sequence[str]) -> str:
    """One verdict from the per-metric ones (see the module docs)."""
    verdicts = list(verdicts)
    if not verdicts:
        return INCONCLUSIVE
    if NOT_REPRODUCED in verdicts:
        return NOT_REPRODUCED
    if all(v == REPRODUCED for v in verdicts):
        return REPRODUCED
    return INCONCLUSIVE
