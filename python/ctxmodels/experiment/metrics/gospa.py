r"""GOSPA, the Generalized Optimal Sub-Pattern Assignment metric, on positions.

Rahmathullah, García-Fernández, Svensson, "Generalized optimal sub-pattern
assignment metric", FUSION 2017, with :math:`\alpha = 2`. For truth positions
:math:`X` and track positions :math:`Y` at one time,

.. math::
    d^{(c,2)}_p(X, Y) = \left( \min_{\gamma} \sum_{(i,j)\in\gamma} d_{ij}^p
        + \frac{c^p}{2} \left(|X| + |Y| - 2|\gamma|\right) \right)^{1/p},

minimising over partial assignments :math:`\gamma` whose pairs are closer than
:math:`c`. The three terms are reported separately (``localisation``,
``missed``, ``false``, in units of distance to the power :math:`p`, so
``distance**p == localisation + missed + false``, as Stone Soup's
``GOSPAMetric`` reports them). The paper's single number is the RMS over
evaluation times, :math:`\sqrt{\frac{1}{T}\sum_t d_t^2}`; :func:`combine_gospa`
pools the times of several sequences before taking it. :func:`gospa_split` splits
its square (at :math:`p = 2`) into the means over times of the three terms,

.. math::
    \frac{1}{T}\sum_t d_t^2 = \overline{\text{localisation}} + \overline{\text{missed}}
        + \overline{\text{false}},

in square metres: how much of the RMS GOSPA is poor positions, missed targets and
false tracks.
"""
from __future__ import annotations

import datetime
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from .frames import EvaluationFrame, frame_list, frames_from_stonesoup, pairwise_distances

GOSPA_C = 30.0
GOSPA_P = 2.0


def _positive_finite(value, name: str) -> float:
    number = float(value)
    if not np.isfinite(number) or number <= 0:
        raise ValueError(f"{name} must be a positive finite number, got {value!r}")
    return number


def check_gospa_parameters(c, p):
    c = _positive_finite(c, "c")
    p = float(p)
    if not (np.isfinite(p) and p >= 1):
        raise ValueError(f"p must be a finite number >= 1, got {p!r}")
    return c, p


@dataclass(frozen=True, eq=False)
class GOSPAResult:
    """GOSPA (alpha = 2) per evaluation time.

    ``distance`` is the GOSPA value at each time; ``localisation``,
    ``missed`` and ``false`` are its terms in units of distance**p
    (``distance**p == localisation + missed + false``); ``num_missed`` and
    ``num_false`` count the unassigned truths and tracks.
    """
    c: float
    p: float
    distance: np.ndarray
    localisation: np.ndarray
    missed: np.ndarray
    false: np.ndarray
    num_missed: np.ndarray
    num_false: np.ndarray

    @property
    def rms(self) -> float:
        """Root mean square of the per-time GOSPA: the paper's reported value."""
        return float(np.sqrt(np.mean(self.distance ** 2)))

    @property
    def mean(self) -> float:
        """Plain mean of the per-time GOSPA."""
        return float(np.mean(self.distance))


def gospa_assignment(truth_positions: np.ndarray, track_positions: np.ndarray, c: float,
                      p: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """GOSPA's optimal assignment at one time: the assigned pairs' truth rows, track rows
    and distances, only pairs closer than ``c`` (the track-management metrics match truths
    to tracks with exactly these pairs)."""
    if truth_positions.shape[0] == 0 or track_positions.shape[0] == 0:
        empty = np.zeros(0, dtype=np.intp)
        return empty, empty, np.zeros(0)
    distance = pairwise_distances(truth_positions, track_positions)
    # Assigning a pair at distance >= c costs c**p, the same as leaving both
    # unassigned (2 * c**p / 2), so capping at c gives the optimal partial
    # assignment through a complete rectangular one.
    rows, cols = linear_sum_assignment(np.minimum(distance, c) ** p)
    pair_distance = distance[rows, cols]
    proper = pair_distance < c
    return rows[proper], cols[proper], pair_distance[proper]


def _gospa_one_time(truth_positions: np.ndarray, track_positions: np.ndarray, c: float,
                    p: float) -> tuple[float, int, int]:
    """Return (localisation term, number missed, number false) at one time."""
    _, _, pair_distance = gospa_assignment(truth_positions, track_positions, c, p)
    n_assigned = pair_distance.size
    localisation = float(np.sum(pair_distance ** p))
    return (localisation, truth_positions.shape[0] - n_assigned,
            track_positions.shape[0] - n_assigned)


def gospa_from_frames(frames: Iterable[EvaluationFrame], *, c: float = GOSPA_C,
                      p: float = GOSPA_P) -> GOSPAResult:
    """GOSPA (alpha = 2) of the positions at each frame."""
    frames = frame_list(frames, "frames")
    c, p = check_gospa_parameters(c, p)
    per_time = [_gospa_one_time(frame.truth_positions, frame.track_positions, c, p)
                for frame in frames]
    localisation = np.array([term[0] for term in per_time], dtype=float)
    num_missed = np.array([term[1] for term in per_time], dtype=np.int64)
    num_false = np.array([term[2] for term in per_time], dtype=np.int64)
    unassigned_cost = c ** p / 2
    missed = num_missed * unassigned_cost
    false = num_false * unassigned_cost
    distance = (localisation + missed + false) ** (1 / p)
    return GOSPAResult(c=c, p=p, distance=distance, localisation=localisation, missed=missed,
                       false=false, num_missed=num_missed, num_false=num_false)


def combine_gospa(results: Iterable[GOSPAResult]) -> GOSPAResult:
    """Pool the evaluation times of several sequences (for an RMS over all)."""
    results = list(results)
    if not results:
        raise ValueError("results must contain at least one GOSPAResult")
    for index, result in enumerate(results):
        if not isinstance(result, GOSPAResult):
            raise TypeError(
                f"results[{index}] must be a GOSPAResult, got {type(result).__name__}")
    if len({(result.c, result.p) for result in results}) != 1:
        raise ValueError("results must all use the same c and p")
    return GOSPAResult(
        c=results[0].c, p=results[0].p,
        **{field: np.concatenate([getattr(result, field) for result in results])
           for field in ("distance", "localisation", "missed", "false", "num_missed",
                         "num_false")})


def gospa_split(result: GOSPAResult) -> tuple[float, float, float]:
    """``(localisation, missed, false)``: the mean over evaluation times of each GOSPA term
    (units of distance**p: square metres at p = 2). They add up to the mean of
    ``distance**p``, so at p = 2 to ``result.rms ** 2`` (up to rounding); pool sequences
    with :func:`combine_gospa` first, as for the RMS."""
    if not isinstance(result, GOSPAResult):
        raise TypeError(f"result must be a GOSPAResult, got {type(result).__name__}")
    return (float(np.mean(result.localisation)), float(np.mean(result.missed)),
            float(np.mean(result.false)))


def gospa(truths: Iterable, tracks: Iterable, timestamps: Iterable[datetime.datetime], *,
          position_mapping: Sequence[int] = (0, 2), c: float = GOSPA_C,
          p: float = GOSPA_P) -> GOSPAResult:
    """GOSPA (alpha = 2) of Stone Soup truths and tracks at the given timestamps."""
    return gospa_from_frames(
        frames_from_stonesoup(truths, tracks, timestamps, position_mapping=position_mapping),
        c=c, p=p)
