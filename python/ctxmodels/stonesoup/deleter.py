r"""Observability-aware track deletion: count the detections a track *should* have produced.

A miss-counting deleter (Stone Soup's
:class:`~stonesoup.deleter.time.UpdateTimeStepsDeleter`) treats every scan without a
detection as evidence against a track. Fused with a 10 Hz lidar that cannot see past 80 m,
a radar-only track 500 m away "misses" twelve lidar scans between two radar scans, so the
deleter must tolerate dozens of misses (the paper needed N = 30 for its JPDA) — which also
keeps false tracks alive that long. Weighting each miss by the probability that the sensor
could have detected the target removes the trade-off: a scan that cannot see the track
costs it nothing.
"""
from __future__ import annotations

import math

from stonesoup.base import Property
from stonesoup.deleter.base import Deleter
from stonesoup.deleter.time import UpdateTimeStepsDeleter as _StockUpdateTimeStepsDeleter
from stonesoup.types.update import Update

from .hypothesiser import PDAHypothesiser, is_detection_backed


class ExpectedMissesDeleter(Deleter):
    r"""Deletes a track once the number of detections it was expected to produce, but did
    not, since its last detection-backed state reaches :attr:`expected_misses`:

    .. math::
        \text{delete} \iff \sum_{k = k_0 + 1}^{K} P_D(\hat{x}_k; S_k) \ \ge\ N_E,

    where :math:`k_0` is the index of the track's last detection-backed state (an
    :class:`~stonesoup.types.update.Update` with a non-empty hypothesis — the criterion of
    Stone Soup's own deleters — or the track's first state if it has none), :math:`K` its
    last state, and :math:`P_D(\hat{x}_k; S_k)` the detection probability the hypothesiser
    used for the prediction that became state :math:`k`, in the context :math:`S_k` of that
    scan. A track updated through its missed-detection hypothesis in a scan that cannot see
    it (:math:`P_D = 0`) accrues nothing; a miss where it was surely visible accrues 1. (In
    :class:`~stonesoup.tracker.simple.MultiTargetMixtureTracker` a state is such an update
    exactly when some detection's association weight exceeded the missed detection's.)

    With :math:`P_D \equiv 1` this is :class:`~stonesoup.deleter.time.UpdateTimeStepsDeleter`
    with ``time_steps_since_update`` :math:`= N_E`: delete after :math:`N_E` states without
    a detection. (The stock deleter counts distinct *timestamps*; this one counts states,
    so two sensors' scans at the same instant are two looks, each accruing its own
    :math:`P_D`.) With a constant :math:`P_D = p` it deletes after :math:`\lceil N_E/p\rceil`
    misses. (Summing :math:`-\log(1 - P_D)` instead would threshold the likelihood of the
    miss run; :math:`\sum P_D` is its first-order form and stays finite at :math:`P_D = 1`.)

    The :math:`P_D` per state comes from :attr:`hypothesiser`, which records, per track,
    the :math:`P_D` it used at each scan (see
    :meth:`ctxmodels.stonesoup.PDAHypothesiser.recorded_prob_detect`); it must be the
    hypothesiser of the tracker's data associator. This works inside the stock
    :class:`~stonesoup.tracker.simple.MultiTargetMixtureTracker` loop (associate, append one
    state per track, delete), including its Gaussian-mixture reduction to a prediction when
    no detection outweighs the miss. States without a record (e.g. made in an initiator by
    another hypothesiser) accrue :attr:`default_prob_detect`.
    """

    expected_misses: float = Property(
        doc="Delete when the expected number of missed detections since the last "
            "detection-backed state reaches this (> 0).")
    hypothesiser: PDAHypothesiser = Property(
        default=None,
        doc="The context-aware :class:`~ctxmodels.stonesoup.PDAHypothesiser` whose recorded "
            "P_D per track and scan is summed. None: every state accrues "
            ":attr:`default_prob_detect`.")
    default_prob_detect: float = Property(
        default=1.0, doc="P_D accrued by a state the hypothesiser has no record for.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        try:
            threshold = float(self.expected_misses)
        except (TypeError, ValueError):
            raise TypeError(f"expected_misses: expected a number, "
                            f"got {self.expected_misses!r}") from None
        if not (math.isfinite(threshold) and threshold > 0):
            raise ValueError(f"expected_misses: must be finite and > 0, got {threshold}")
        try:
            default = float(self.default_prob_detect)
        except (TypeError, ValueError):
            raise TypeError(f"default_prob_detect: expected a number, "
                            f"got {self.default_prob_detect!r}") from None
        if not 0.0 <= default <= 1.0:
            raise ValueError(f"default_prob_detect: must lie in [0, 1], got {default}")
        if self.hypothesiser is not None \
                and not callable(getattr(self.hypothesiser, "recorded_prob_detect", None)):
            raise TypeError(
                f"hypothesiser: {type(self.hypothesiser).__name__} records no P_D per scan; "
                "use ctxmodels.stonesoup.PDAHypothesiser (or None to count misses)")

    def _prob_detect(self, track, index: int) -> float:
        recorded = None if self.hypothesiser is None \
            else self.hypothesiser.recorded_prob_detect(track, index)
        return float(self.default_prob_detect) if recorded is None else recorded

    def expected_misses_since_detection(self, track, stop_at: float = math.inf) -> float:
        """:math:`\\sum P_D` over the states after the track's last detection-backed one
        (summing stops early once it reaches ``stop_at``)."""
        total = 0.0
        for index in range(len(track) - 1, 0, -1):  # the first state is the anchor
            if is_detection_backed(track[index]):
                break
            total += self._prob_detect(track, index)
            if total >= stop_at:
                break
        return total

    def check_for_deletion(self, track, **kwargs) -> bool:
        """Whether the track's expected misses since its last detection reached
        :attr:`expected_misses`."""
        threshold = float(self.expected_misses)
        return self.expected_misses_since_detection(track, stop_at=threshold) >= threshold


class UpdateTimeStepsDeleter(_StockUpdateTimeStepsDeleter):
    """:class:`stonesoup.deleter.time.UpdateTimeStepsDeleter` that reads only a track's
    trailing states. The stock check walks ``track[::-1]``, a reversed copy of the whole
    track, at every scan, so its cost grows with the square of a track's length (a sixth of
    a JPDA run's time); this walks back from the last state and stops where the stock loop
    does, with the same answer: delete once more than ``time_steps_since_update`` distinct
    timestamps pass without an :class:`~stonesoup.types.update.Update` backed by a
    detection."""

    def check_for_deletion(self, track, **kwargs) -> bool:
        timestamps = set()
        for state in reversed(track.states):
            timestamps.add(state.timestamp)
            if len(timestamps) > self.time_steps_since_update:
                return True
            if isinstance(state, Update) and state.hypothesis:
                return False
        return False


__all__ = ["ExpectedMissesDeleter", "UpdateTimeStepsDeleter"]
