r"""Track deletion: observability-aware miss counting, and duplicate tracks.

A miss-counting deleter (Stone Soup's
:class:`~stonesoup.deleter.time.UpdateTimeStepsDeleter`) treats every scan without a
detection as evidence against a track. Fused with a 10 Hz lidar that cannot see past 80 m,
a radar-only track 500 m away "misses" twelve lidar scans between two radar scans, so the
deleter must tolerate dozens of misses (the paper needed N = 30 for its JPDA) — which also
keeps false tracks alive that long. Weighting each miss by the probability that the sensor
could have detected the target removes the trade-off: a scan that cannot see the track
costs it nothing.

Two tracks may also follow one target (two holding tracks confirmed on the same detections,
or a track split by clutter): :class:`DuplicateTrackDeleter` deletes one of each such pair
by the standard track-to-track association test.

Each deletion rule, ctxmodels' and the Stone Soup deleters' the array paths evaluate, is
written here once as a verdict from what the rule reads — the distinct times or the
:math:`P_D` of the states since a track's last detection-backed one, its latest
detection-backed time, its last covariance: :func:`time_steps_verdict`,
:func:`update_time_verdict`, :func:`covariance_verdict` and
:meth:`ExpectedMissesDeleter.deletes_after`, with the readers of those quantities off a
track (:func:`times_since_detection`, :func:`latest_detection_time`,
:meth:`ExpectedMissesDeleter.prob_detect_since_detection`). ctxmodels' deleters reach their
``check_for_deletion`` through them, and the array paths (the JPDA tracker's and the M-of-N
initiator's), which keep those quantities per track as scans go by, call the same functions;
the stock deleters' own ``check_for_deletion`` is their reference, held against them in the
tests. Why one long module: each verdict sits beside the deleter whose rule it is, and
both paths import it from there.
"""
from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from numbers import Integral, Real

import numpy as np
from stonesoup.base import Property
from stonesoup.deleter.base import Deleter
from stonesoup.deleter.time import UpdateTimeStepsDeleter as _StockUpdateTimeStepsDeleter

from ...foreign import as_array_context
from .composite_deleter import PairwiseDeleter
from .._batch import plain_track_lists
from ._pd_record import PDRecord
from .hypothesiser import PDAHypothesiser, is_detection_backed, prob_detect_at
from ..ordering import track_key


def times_since_detection(states) -> set:
    """The distinct timestamps of ``states`` (a track's, oldest first) from the last
    detection-backed one (an :class:`~stonesoup.types.update.Update` with a non-empty
    hypothesis), that state's included, to the last; of all of them if none is
    detection-backed. What :func:`time_steps_verdict` counts."""
    stamps = set()
    for state in reversed(states):
        stamps.add(state.timestamp)
        if is_detection_backed(state):
            break
    return stamps


def latest_detection_time(states):
    """The latest timestamp of a detection-backed state of ``states``, or None if there is
    none. Every state is read: a track's states need not be in time order."""
    latest = None
    for state in states:
        if is_detection_backed(state):
            stamp = state.timestamp
            if latest is None or stamp > latest:
                latest = stamp
    return latest


def time_steps_verdict(deleter, distinct_times):
    r"""The verdict of an ``UpdateTimeStepsDeleter`` (Stone Soup's
    :class:`~stonesoup.deleter.time.UpdateTimeStepsDeleter` or ctxmodels'
    :class:`UpdateTimeStepsDeleter`) on a track whose states since its last
    detection-backed one (that state included, see :func:`times_since_detection`) carry
    ``distinct_times`` distinct timestamps:

    .. math::
        \text{delete} \iff \bigl|\{t_k : k_0 \le k \le K\}\bigr| \ >\ N,

    :math:`N` the deleter's ``time_steps_since_update``, :math:`k_0` the last
    detection-backed state (the first state if none is). Given an array of counts, the
    verdicts elementwise."""
    return distinct_times > deleter.time_steps_since_update


def update_time_verdict(deleter, latest_detection, last) -> bool:
    r"""The verdict of Stone Soup's :class:`~stonesoup.deleter.time.UpdateTimeDeleter` on a
    track whose latest detection-backed state is at :math:`t_d` = ``latest_detection``
    (None: it has none, see :func:`latest_detection_time`), asked at :math:`t_K` = ``last``
    (its last state's time, the deleter's default). The deleter deletes when no
    detection-backed state lies in ``track[last - Δ:]``, and Stone Soup's time slice keeps
    the states with ``timestamp >= last - Δ``; so, with :math:`\Delta` its
    ``time_since_update``,

    .. math::
        \text{delete} \iff t_d \text{ is None} \ \lor\ t_d < t_K - \Delta :

    the window includes its start, and a track last updated exactly :math:`\Delta` ago is
    kept."""
    return latest_detection is None or latest_detection < last - deleter.time_since_update


def covariance_verdict(deleter, covars):
    r"""The verdict of Stone Soup's :class:`~stonesoup.deleter.error.CovarianceBasedDeleter`
    on a track whose last state has the covariance ``covars`` (D, D); given a stack
    (N, D, D), the N verdicts as a boolean array. With :math:`\tau` the deleter's
    ``covar_trace_thresh`` and :math:`m` its ``mapping``,

    .. math::
        \text{delete} \iff \sum_{i \in m} P_{ii} \ >\ \tau,

    strictly; :math:`m` is every index when ``mapping`` is None or empty, and is otherwise
    the positions Stone Soup's indexing of the covariance's diagonal by ``mapping`` selects
    (the same selection, and the same errors for a mapping the deleter cannot index with,
    such as a tuple of two). Each sum is NumPy's sum of the selected entries in a contiguous
    row: the pairwise order of ``np.sum`` over the same entries as a 1-D array, so each
    number, and each verdict, is the deleter's (tested against it on random covariances of
    1 to 12 dimensions and at the threshold)."""
    covars = np.asarray(covars)
    diagonals = covars.diagonal(0, -2, -1)
    mapping = deleter.mapping
    if mapping:  # the positions Stone Soup's indexing selects (a list of ints: itself)
        if type(mapping) is not list or any(type(i) is not int for i in mapping):
            mapping = np.arange(diagonals.shape[-1])[mapping].ravel()
        diagonals = diagonals.take(mapping, axis=-1)  # (into a new, contiguous array)
    sums = np.add.reduce(np.ascontiguousarray(diagonals), axis=-1)
    says = sums > deleter.covar_trace_thresh
    return bool(says) if covars.ndim == 2 else says


def _sum_until(values, stop_at: float) -> float:
    """The sum of ``values`` in their order, from 0.0, stopping once it reaches
    ``stop_at``."""
    total = 0.0
    for value in values:
        total += value
        if total >= stop_at:
            break
    return total


class MissesNotWeighedWarning(UserWarning):
    """An :class:`ExpectedMissesDeleter` found a miss without :math:`P_D` and counted it
    with its ``default_prob_detect``."""


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
    no detection outweighs the miss.

    As an initiator's deleter (its holding tracks are predicted by a distance hypothesiser,
    which records no :math:`P_D`), it takes the scan's context instead:
    :meth:`delete_tracks` called with ``detector_context`` evaluates
    :math:`P_D(\hat{x}_K; S_K)` at each track's last state when that state is a miss without
    a record — ctxmodels' :class:`~ctxmodels.stonesoup.MultiMeasurementInitiator` passes the
    context its tracker received. A state with neither a record nor a context accrues
    :attr:`default_prob_detect`, and the first such state raises a
    :class:`MissesNotWeighedWarning` (once per deleter): the misses are then counted, not
    weighed.
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
        if recorded is None:
            recorded = self._from_context(track, index)
        if recorded is None:
            if not self.__dict__.get("_warned"):
                self.__dict__["_warned"] = True
                warnings.warn(
                    "ExpectedMissesDeleter: a miss with no P_D (no record from its hypothesiser "
                    "and no detector_context) accrues default_prob_detect="
                    f"{float(self.default_prob_detect)}: misses are counted, not weighed. Give "
                    "the tracker's ctxmodels PDAHypothesiser as hypothesiser, or the scan's "
                    "context (an initiator's deleter: use ctxmodels' "
                    "MultiMeasurementInitiator inside ctxmodels' MultiTargetMixtureTracker)",
                    MissesNotWeighedWarning, stacklevel=3)
            return float(self.default_prob_detect)
        return recorded

    def delete_tracks(self, tracks, detector_context=None, **kwargs) -> set:
        """The tracks to delete (Stone Soup's :meth:`~stonesoup.deleter.base.Deleter.delete_tracks`).
        With the scan's ``detector_context``, each track whose last state is a miss with no
        record from :attr:`hypothesiser` gets :math:`P_D` of that state in the context first
        (an initiator's holding tracks)."""
        if detector_context is not None:
            self._weigh_last_misses(tracks, detector_context)
        return super().delete_tracks(tracks, **kwargs)

    def _weigh_last_misses(self, tracks, detector_context) -> None:
        context = as_array_context(detector_context, "prob_detection_states",
                                   "clutter_spatial_density_detections")
        for track in tracks:
            n = len(track)
            if n < 2 or is_detection_backed(track[-1]):
                continue
            if self.hypothesiser is not None \
                    and self.hypothesiser.recorded_prob_detect(track, -1) is not None:
                continue
            prob_detect = prob_detect_at(context, track[-1])
            if not 0.0 <= prob_detect <= 1.0:
                raise ValueError(f"detector_context: P_D must lie in [0, 1], got {prob_detect} "
                                 f"for a track at {track[-1].timestamp}")
            self.record_prob_detect(track, n - 1, prob_detect)

    def record_prob_detect(self, track, index: int, prob_detect: float) -> None:
        """Records ``prob_detect`` as the P_D of the miss at ``index`` of ``track`` (a state
        after its last detection-backed one; what :meth:`delete_tracks` records from a
        context, and the array initiator for the holding tracks it builds)."""
        log = self.__dict__.get("_context_log")
        if log is None:
            log = self.__dict__["_context_log"] = PDRecord()
        log.record(track, index, track[index].timestamp, float(prob_detect),
                   restart=is_detection_backed(track[index - 1]))

    def prob_detect_since_detection(self, track) -> list[float]:
        """The P_D of each state after the track's last detection-backed one, oldest first
        (what :meth:`expected_misses_since_detection` sums, newest first)."""
        values = list(self._newest_first(track))
        values.reverse()
        return values

    def _newest_first(self, track):
        """The P_D of each state after the track's last detection-backed one, newest first,
        each looked up only when read."""
        for index in range(len(track) - 1, 0, -1):  # the first state is the anchor
            if is_detection_backed(track[index]):
                return
            yield self._prob_detect(track, index)

    def _from_context(self, track, index: int):
        log = self.__dict__.get("_context_log")
        return None if log is None else \
            log.get(track, index % len(track), track[index].timestamp)

    def expected_misses_since_detection(self, track, stop_at: float = math.inf) -> float:
        """:math:`\\sum P_D` over the states after the track's last detection-backed one
        (summing stops early once it reaches ``stop_at``)."""
        return _sum_until(self._newest_first(track), stop_at)

    def deletes_after(self, prob_detect) -> bool:
        r"""Whether a track is deleted whose states since its last detection-backed one had
        the detection probabilities ``prob_detect``, newest first (any iterable; read only
        as far as the verdict needs):

        .. math::
            \text{delete} \iff \sum_{k} P_{D,k} \ \ge\ N_E,

        summed from 0.0 newest first and stopping as soon as the sum reaches :math:`N_E`
        (:attr:`expected_misses`). :meth:`check_for_deletion` hands it the track's P_D;
        the array paths, the P_D they keep per track."""
        threshold = float(self.expected_misses)
        return _sum_until(prob_detect, threshold) >= threshold

    def check_for_deletion(self, track, **kwargs) -> bool:
        """Whether the track's expected misses since its last detection reached
        :attr:`expected_misses` (:meth:`deletes_after` of its P_D)."""
        return self.deletes_after(self._newest_first(track))


class UpdateTimeStepsDeleter(_StockUpdateTimeStepsDeleter):
    """:class:`stonesoup.deleter.time.UpdateTimeStepsDeleter` that reads only a track's
    trailing states. The stock check walks ``track[::-1]``, a reversed copy of the whole
    track, at every scan, so its cost grows with the square of a track's length (a sixth of
    a JPDA run's time); this reads the states back to the last detection-backed one
    (:func:`times_since_detection`) and gives :func:`time_steps_verdict` of their distinct
    timestamps: the stock verdict, deleting once more than ``time_steps_since_update``
    distinct timestamps pass without an :class:`~stonesoup.types.update.Update` backed by a
    detection."""

    def check_for_deletion(self, track, **kwargs) -> bool:
        states = track.states
        if not states:
            return False  # (no state, no timestamp to count: kept, as stock keeps it)
        return bool(time_steps_verdict(self, len(times_since_detection(states))))


class DuplicateTrackDeleter(PairwiseDeleter):
    r"""Deletes one track of each pair of duplicates, by the standard track-to-track
    association test.

    Two tracks whose latest states share a timestamp are duplicates when

    .. math::
        d^2 = \Delta^\mathsf{T} (P_1 + P_2)^{-1} \Delta \ <\ \gamma,
        \qquad \Delta = H (\hat{x}_1 - \hat{x}_2), \quad P_i = H P_i^{x} H^\mathsf{T},

    where :math:`\hat{x}_i, P_i^{x}` are the latest mean and covariance of track :math:`i`
    and :math:`H` selects the components in :attr:`mapping` (the position). If both tracks
    estimate one target with independent errors, :math:`\Delta` is zero-mean with covariance
    :math:`P_1 + P_2` and :math:`d^2` is :math:`\chi^2`-distributed with ``len(mapping)``
    degrees of freedom, so :attr:`threshold` :math:`\gamma` is a :math:`\chi^2` quantile:
    the default 9.21 is the 99 % quantile with 2 degrees of freedom
    (:math:`-2 \ln 0.01 = 9.2103`; 95 %: 5.99; for 3 degrees of freedom 11.34 at 99 %). The
    cross-covariance :math:`P_{12}` of the two estimates (common process noise, shared
    detections) is neglected: it is positive, so the true :math:`\operatorname{Cov}\Delta
    = P_1 + P_2 - P_{12} - P_{12}^\mathsf{T}` is smaller and the test calls duplicates
    somewhat more readily than the exact one. A pair whose :math:`P_1 + P_2` is singular, or
    whose :math:`d^2` is NaN, is not a pair of duplicates.

    Of a pair, the track with fewer detection-backed states (each an
    :class:`~stonesoup.types.update.Update` with a non-empty hypothesis: Stone Soup's
    deleters' criterion) is deleted; on a tie the younger one (later first state); then the
    later in content order (:func:`~ctxmodels.stonesoup.ordering.track_key`, then the
    track ``id``) — never by memory address or set order. Chains (A duplicates B, B
    duplicates C) are resolved pair by pair in increasing :math:`d^2` (ties in content
    order): a pair one of whose tracks is already deleted is skipped, so a deleted track
    deletes no other; a track that kept its place in one pair can still lose a later one.
    The verdicts do not depend on the order of the tracks handed in: each :math:`d^2` is the
    same number whichever track comes first (:math:`\Delta` only changes sign, exactly).

    The verdict on a track depends on the other tracks, so there is no per-track
    ``check_for_deletion`` (it raises ``TypeError``); :meth:`delete_tracks` judges a set.
    Combined with per-track deleters, use :class:`~ctxmodels.stonesoup.CompositeDeleter`
    (Stone Soup's asks its members one track at a time).
    """

    threshold: float = Property(
        default=9.21,
        doc="The gate γ on d² (finite, > 0): a χ² quantile with len(mapping) degrees of "
            "freedom; the default is the 99 % quantile with 2.")
    mapping: Sequence[int] = Property(
        default=(0, 2),
        doc="The state components compared (distinct indices, non-empty): the position, "
            "x and y of a constant-velocity state [x, vx, y, vy] by default.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._parameters()

    def _parameters(self):
        """(γ as a float, the mapping as an index array), checked (read at every call: the
        Properties may be set after construction)."""
        threshold = self.threshold
        if isinstance(threshold, bool) or not isinstance(threshold, Real):
            raise TypeError(f"threshold: expected a number, got {threshold!r}")
        if not (math.isfinite(threshold) and threshold > 0):
            raise ValueError(f"threshold: must be finite and > 0, got {threshold}")
        mapping = self.mapping
        try:
            indices = list(mapping)
        except TypeError:
            raise TypeError(f"mapping: expected a sequence of state indices, "
                            f"got {mapping!r}") from None
        if not indices:
            raise ValueError("mapping: must name at least one state component, got an "
                             "empty sequence")
        if any(isinstance(i, bool) or not isinstance(i, Integral) or i < 0 for i in indices):
            raise TypeError(f"mapping: expected non-negative integer indices, got {mapping!r}")
        if len(set(indices)) != len(indices):
            raise ValueError(f"mapping: indices must be distinct, got {mapping!r}")
        return float(threshold), np.array([int(i) for i in indices])

    def tracks_to_delete(self, tracks, **kwargs) -> set:
        """The tracks of ``tracks`` (any iterable) to delete; nothing is changed."""
        tracks = [t for t in tracks if len(t)]
        latest = []
        for track in tracks:
            lists = plain_track_lists(track)
            latest.append(track.states[-1] if lists is None else lists[0][-1])
        if len(latest) < 2:
            return set()
        means = np.array([np.asarray(s.state_vector, dtype=np.float64)[:, 0] for s in latest])
        covars = np.array([np.asarray(s.covar, dtype=np.float64) for s in latest])
        return self.duplicates(tracks, means, covars, [s.timestamp for s in latest])

    def duplicates(self, tracks, means, covars, timestamps) -> set:
        """The tracks to delete, given each track's latest mean (rows of ``means``,
        (N, D)), covariance (``covars``, (N, D, D)) and timestamp, aligned with the list
        ``tracks``."""
        threshold, index = self._parameters()
        means = means[:, index]
        covars = covars[:, index][:, :, index]
        groups: dict = {}
        for k, stamp in enumerate(timestamps):
            groups.setdefault(stamp, []).append(k)
        candidates = []  # (d², k, l)
        for members in groups.values():
            if len(members) < 2:
                continue
            members = np.asarray(members)
            i, j = np.triu_indices(len(members), 1)
            a, b = members[i], members[j]
            d2 = _squared_distances(means[a] - means[b], covars[a] + covars[b])
            for p in np.flatnonzero(d2 < threshold).tolist():
                candidates.append((float(d2[p]), int(a[p]), int(b[p])))
        if not candidates:
            return set()
        keys: dict = {}

        def key(k):
            if k not in keys:
                keys[k] = (track_key(tracks[k]), str(getattr(tracks[k], "id", "")))
            return keys[k]
        # increasing d², then the pair's content order: the same order for any input order
        candidates.sort(key=lambda c: (c[0],) + tuple(sorted((key(c[1]), key(c[2])))))
        backed: dict = {}
        deleted = set()
        for _, k, m in candidates:
            if k in deleted or m in deleted:
                continue  # a deleted track deletes no other
            deleted.add(self._loser(tracks, k, m, key, backed))
        return {tracks[k] for k in deleted}

    @staticmethod
    def _loser(tracks, k, m, key, backed):
        """Which of tracks ``k`` and ``m`` (duplicates) is deleted."""
        for n in (k, m):
            if n not in backed:
                backed[n] = sum(1 for s in tracks[n].states if is_detection_backed(s))
        if backed[k] != backed[m]:
            return k if backed[k] < backed[m] else m
        first_k, first_m = tracks[k].states[0].timestamp, tracks[m].states[0].timestamp
        if first_k is not None and first_m is not None and first_k != first_m:
            return k if first_k > first_m else m  # the younger
        return k if key(m) < key(k) else m


def _squared_distances(delta, covars):
    """Δᵀ S⁻¹ Δ per row of ``delta`` (K, m) and ``covars`` (K, m, m), each from its own
    LU solve (so a row's value does not depend on the others); NaN where S is singular.
    Negating Δ negates the solution exactly, so the value is symmetric in the pair."""
    try:
        solved = np.linalg.solve(covars, delta[:, :, np.newaxis])[:, :, 0]
    except np.linalg.LinAlgError:  # some S singular: row by row (rare)
        solved = np.full(delta.shape, np.nan)
        for p in range(len(delta)):
            try:
                solved[p] = np.linalg.solve(covars[p], delta[p][:, np.newaxis])[:, 0]
            except np.linalg.LinAlgError:
                pass
    total = delta[:, 0] * solved[:, 0]
    for c in range(1, delta.shape[1]):  # left to right, the same sum for every row
        total = total + delta[:, c] * solved[:, c]
    return total


__all__ = ["DuplicateTrackDeleter", "ExpectedMissesDeleter", "MissesNotWeighedWarning",
           "UpdateTimeStepsDeleter", "covariance_verdict", "latest_detection_time",
           "time_steps_verdict", "times_since_detection", "update_time_verdict"]
