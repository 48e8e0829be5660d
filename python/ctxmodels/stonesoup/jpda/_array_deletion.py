r"""Deletion on :class:`~ctxmodels.stonesoup.ArrayJPDATracker`'s array path: the deleter's
verdicts reached without walking every track at every scan.

Each supported (member) deleter is evaluated from what the array path already holds:

* miss counters, kept per track as states are appended (read from the track once, or
  again after a change from outside): the distinct timestamps since the last
  detection-backed state (``UpdateTimeStepsDeleter``), the P_D of each state since then
  (:class:`~ctxmodels.stonesoup.ExpectedMissesDeleter`), the time of the latest
  detection-backed state (Stone Soup's :class:`~stonesoup.deleter.time.UpdateTimeDeleter`);
* the last state's covariance (:class:`~stonesoup.deleter.error.CovarianceBasedDeleter`);
* the scan's posterior means and covariances, stacked
  (:class:`~ctxmodels.stonesoup.DuplicateTrackDeleter`, which compares tracks in pairs).

A :class:`~stonesoup.deleter.multi.CompositeDeleter` (Stone Soup's, or ctxmodels'
:class:`~ctxmodels.stonesoup.CompositeDeleter`, the one that takes a pairwise member) of
such members is evaluated with its own rule, member by member in its order.
"""
from __future__ import annotations

import datetime

import numpy as np
from stonesoup.deleter.error import CovarianceBasedDeleter
from stonesoup.deleter.multi import CompositeDeleter
from stonesoup.deleter.time import UpdateTimeDeleter
from stonesoup.deleter.time import UpdateTimeStepsDeleter as _StockUpdateTimeStepsDeleter
from stonesoup.types.array import CovarianceMatrix

from .composite_deleter import CompositeDeleter as _PairwiseCompositeDeleter
from .deleter import DuplicateTrackDeleter, ExpectedMissesDeleter, UpdateTimeStepsDeleter
from .._batch import plain_track_lists
from .hypothesiser import is_detection_backed
from ..scan_context import context_kwargs

_COMPOSITES = (CompositeDeleter, _PairwiseCompositeDeleter)


def _track_length(track) -> int:
    lists = plain_track_lists(track)
    return len(track) if lists is None else len(lists[0])


def _last_timestamp(track):
    """``track.timestamp`` (its last state's), read without Stone Soup's attribute proxy."""
    lists = plain_track_lists(track)
    return track.timestamp if lists is None else lists[0][-1].timestamp


def latest_backed_time(states):
    """The latest timestamp of a detection-backed state of ``states`` (all of them are read:
    a track's states need not be in time order), or None if there is none."""
    latest = None
    for state in states:
        if is_detection_backed(state):
            stamp = state.timestamp
            if latest is None or stamp > latest:
                latest = stamp
    return latest


def update_time_verdict(latest_backed, last, time_since_update) -> bool:
    """``UpdateTimeDeleter.check_for_deletion`` from a track's latest detection-backed time
    and last timestamp. The deleter looks for a detection-backed state in
    ``track[last - time_since_update:]``, and Stone Soup's time slice keeps the states with
    ``timestamp >= start`` (it skips ``timestamp < start``): the window includes its start,
    so a track last updated exactly ``time_since_update`` ago is kept."""
    return latest_backed is None or latest_backed < last - time_since_update


class _MissCounter:
    """Per track and counting deleter (``values``, one entry per member of the deletion plan
    with a counter), what it reads from the states since the track's last detection-backed
    one: the distinct timestamps (``UpdateTimeStepsDeleter``) or the P_D of each state,
    newest last (``ExpectedMissesDeleter``; zeros are dropped, as adding 0.0 never changes a
    sum); or the latest detection-backed timestamp, None before the first
    (``UpdateTimeDeleter``). ``length`` is the track length the entry describes: a track
    changed from outside is re-read once."""

    __slots__ = ("length", "values")

    def __init__(self, length, values):
        self.length = length
        self.values = values


class ArrayDeletion:
    """The array path's deletion, a mixin of :class:`~ctxmodels.stonesoup.ArrayJPDATracker`
    (call :meth:`_init_deletion` from ``__init__``): the deletion plan of the tracker's
    ``deleter``, each track's counters, and the verdicts."""

    def _init_deletion(self) -> None:
        self._counters: dict = {}  # track -> _MissCounter
        self._plan = None

    def _deletion_plan(self):
        """How the array path reaches the deleter's verdicts, or None to call the deleter.
        A supported deleter, or a ``CompositeDeleter`` of supported deleters, is a
        :class:`_DeletionPlan`; the composite's own ``delete_last_pred`` must be off (its
        members' is never read: the composite asks only their ``check_for_deletion``, or a
        pairwise member's ``tracks_to_delete``). Stone Soup's composite cannot hold a
        pairwise member (it would ask it about one track): it is called, and raises."""
        deleter = self.deleter
        if getattr(deleter, "delete_last_pred", False):
            return None
        plan = self._plan
        if plan is not None and plan.deleter is deleter and plan.still_describes(deleter):
            return plan
        if type(deleter) in _COMPOSITES:
            members = deleter.deleters
            if not isinstance(members, (list, tuple)):
                return None  # (a set's order, a one-shot iterator: the deleter decides)
            kinds = [_member_kind(member) for member in members]
            if any(kind is None for kind in kinds) or (
                    "pairwise" in kinds and type(deleter) is CompositeDeleter):
                return None
            plan = _DeletionPlan(deleter, bool(deleter.intersect), list(zip(kinds, members)))
        else:
            kind = _member_kind(deleter)
            if kind is None:
                return None
            plan = _DeletionPlan(deleter, True, [(kind, deleter)])
        self._plan = plan
        self._counters.clear()  # counters of another plan: re-read
        return plan

    @staticmethod
    def _counting(plan, hypothesiser):
        """Per counter slot of ``plan``, what ``_count`` keeps: "steps" (the timestamp of
        a miss), "time" (the timestamp of a detection-backed state), or the P_D the
        expected-misses member reads for a miss (the scan's P_D when its hypothesiser is the
        scan's, else its default: None)."""
        counting = []
        for kind, member in plan.counted:
            if kind in ("steps", "time"):
                counting.append((kind, None))
            elif member.hypothesiser is not None and member.hypothesiser is hypothesiser:
                counting.append(("expected", None))
            else:
                counting.append(("expected", float(member.default_prob_detect)))
        return counting

    def _count(self, tracks, lengths, backed, timestamp, prob_detect, counting):
        """Counts each track's state at ``timestamp``, just appended to it, into the track's
        miss counter; per track (aligned lists) its ``length`` before the append, whether
        the state is ``backed`` by a detection and the P_D of the scan."""
        counters = self._counters
        for track, length, is_backed, pd_scan in zip(tracks, lengths, backed, prob_detect):
            counter = counters.get(track)
            if counter is None or counter.length != length:
                counters.pop(track, None)
                continue  # re-read from the track when next needed
            counter.length = length + 1
            values = counter.values
            for k, (kind, default) in enumerate(counting):
                if kind == "steps":
                    if is_backed:
                        values[k] = {timestamp}
                    else:
                        values[k].add(timestamp)
                elif kind == "time":
                    if is_backed and (values[k] is None or timestamp > values[k]):
                        values[k] = timestamp
                elif is_backed:
                    values[k] = []
                else:
                    pd = pd_scan if default is None else default
                    if pd != 0.0:
                        values[k].append(pd)

    def _read_counter(self, track, plan):
        """The counter of ``track`` read from its states (once per track, or after a change
        from outside)."""
        states = track.states
        values = []
        for kind, member in plan.counted:
            if kind == "steps":
                stamps = set()
                for state in reversed(states):
                    stamps.add(state.timestamp)
                    if is_detection_backed(state):
                        break
                values.append(stamps)
            elif kind == "time":
                values.append(latest_backed_time(states))
            else:
                misses = []
                for index in range(len(states) - 1, 0, -1):
                    if is_detection_backed(states[index]):
                        break
                    pd = member._prob_detect(track, index)
                    if pd != 0.0:
                        misses.append(pd)
                misses.reverse()
                values.append(misses)
        counter = _MissCounter(len(track), values)
        self._counters[track] = counter
        return counter

    def _delete(self, tracks, detections, latest=None, counted_now=frozenset()):
        """The tracks of ``tracks`` to delete. ``latest``: (the scan's tracks in order,
        their posterior means (N, D), covariances (N, D, D), the scan time), which a
        pairwise member reads when they are all of ``tracks``. ``counted_now``: plain tracks
        whose one state of this scan was just appended to their lists and counted
        (:meth:`_count`): a counter they still have describes them."""
        plan = self._deletion_plan()
        if plan is None:
            deleter = self.deleter
            return deleter.delete_tracks(tracks,
                                         **context_kwargs(detections, deleter.delete_tracks))
        # each member's check, its parameters read once a scan, in the composite's order
        checks = []
        for kind, member, k in plan.members:
            if kind == "steps":
                checks.append((kind, k, member.time_steps_since_update))
            elif kind == "expected":
                checks.append((kind, k, float(member.expected_misses)))
            elif kind == "time":
                window = member.time_since_update
                if type(window) is datetime.timedelta:
                    checks.append((kind, k, window))
                else:  # (times that are not datetimes: the deleter's own arithmetic)
                    checks.append(("call", k, member.check_for_deletion))
            elif kind == "pairwise":
                checks.append((kind, k, _pairwise_verdicts(member, tracks, latest)))
            else:
                checks.append((kind, k, _covariance_check(member, latest)))
        deleted = set()
        counters = self._counters
        intersect = plan.intersect
        counted = bool(plan.counted)
        for track in tracks:
            if counted:
                counter = counters.get(track)
                if counter is None or (track not in counted_now
                                       and counter.length != _track_length(track)):
                    counter = self._read_counter(track, plan)
            # the composite's rule, member by member in its order: all (intersect) or any
            verdict = intersect
            for kind, k, parameter in checks:
                if kind == "steps":
                    says = len(counter.values[k]) > parameter
                elif kind == "time":
                    says = update_time_verdict(counter.values[k], _last_timestamp(track),
                                               parameter)
                elif kind == "pairwise":
                    says = track in parameter
                elif kind == "expected":
                    total = 0.0
                    says = False
                    for pd in reversed(counter.values[k]):  # newest first, as the deleter sums
                        total += pd
                        if total >= parameter:
                            says = True
                            break
                else:
                    says = bool(parameter(track))
                if says != intersect:
                    verdict = says
                    break
            if verdict:
                deleted.add(track)
        for track in deleted:
            counters.pop(track, None)
        return deleted


def _member_kind(deleter):
    """What the array path evaluates for a (member) deleter: counters ("steps", "expected",
    "time"), the last covariance ("covariance"), the scan's posteriors ("pairwise"), or None
    (not supported)."""
    kind = type(deleter)
    if kind in (UpdateTimeStepsDeleter, _StockUpdateTimeStepsDeleter):
        return "steps"
    if kind is ExpectedMissesDeleter:
        return "expected"
    if kind is UpdateTimeDeleter:
        return "time"
    if kind is CovarianceBasedDeleter:
        return "covariance"
    if kind is DuplicateTrackDeleter:
        return "pairwise"
    return None


def _pairwise_verdicts(member, tracks, latest) -> set:
    """The tracks a pairwise member deletes: from the scan's stacked posteriors when they
    are those of all ``tracks`` (the states are views of these arrays: the same numbers),
    else asked of the tracks."""
    if latest is not None and len(latest[0]) == len(tracks):
        scan_tracks, means, covars, time = latest
        return member.duplicates(scan_tracks, means, covars, [time] * len(scan_tracks))
    return member.tracks_to_delete(tracks)


class _DeletionPlan:
    """A supported deleter as the array path evaluates it: ``members`` are (kind, deleter,
    counter slot) in the composite's order (one member for a plain deleter; a plain deleter
    is an intersection of one), ``counted`` the members with a miss counter, in slot order.
    The plan is rebuilt when the composite's members or rule change."""

    __slots__ = ("deleter", "intersect", "members", "counted", "_seen")

    def __init__(self, deleter, intersect, members):
        self.deleter = deleter
        self.intersect = intersect
        self.counted = [(kind, member) for kind, member in members
                        if kind in ("steps", "expected", "time")]
        slots = {id(member): k for k, (_, member) in enumerate(self.counted)}
        self.members = [(kind, member, slots.get(id(member))) for kind, member in members]
        self._seen = self._signature(deleter)

    @staticmethod
    def _signature(deleter):
        if type(deleter) in _COMPOSITES:
            return (bool(deleter.intersect), tuple(id(m) for m in deleter.deleters))
        return None

    def still_describes(self, deleter) -> bool:
        return self._signature(deleter) == self._seen


def _covariance_check(deleter, latest=None):
    """``CovarianceBasedDeleter.check_for_deletion`` as a function of the track: Stone Soup
    1.9.1 deletes when the sum of the last state's covariance diagonal over ``mapping`` (all
    of it when ``mapping`` is None or empty) is strictly greater than ``covar_trace_thresh``.
    With a list of one or two plain int indices and a float threshold the sum is read
    directly (NumPy's sum of two float64 is their one IEEE addition, so the verdict is the
    same); any other mapping or threshold, or a covariance that is not a 2-D float64 array,
    asks the deleter. ``latest`` (see :meth:`ArrayDeletion._delete`): the scan's posterior
    covariances, whose sums are taken for all its plain tracks at once (each such track's
    last state holds its row: the same numbers, the same additions)."""
    mapping = deleter.mapping
    threshold = deleter.covar_trace_thresh
    if not (type(mapping) is list and 0 < len(mapping) <= 2
            and all(type(i) is int for i in mapping) and type(threshold) is float):
        return lambda track: bool(deleter.check_for_deletion(track))
    i, j = mapping if len(mapping) == 2 else (mapping[0], None)
    scan: dict = {}
    if latest is not None:
        covars = latest[2]
        size = covars.shape[1]
        if covars.dtype == np.float64 and -size <= min(i, j or 0) and max(i, j or 0) < size:
            traces = covars[:, i, i] if j is None else covars[:, i, i] + covars[:, j, j]
            scan = {track: says for track, says in zip(latest[0], (traces > threshold).tolist())
                    if plain_track_lists(track) is not None}  # (appended to its list)

    def check(track) -> bool:
        says = scan.get(track)
        if says is not None:
            return says
        lists = plain_track_lists(track)
        covar = (track.states if lists is None else lists[0])[-1].covar
        if not (type(covar) in _COVARIANCE_TYPES and covar.dtype == np.float64
                and covar.ndim == 2):
            return bool(deleter.check_for_deletion(track))
        trace = covar.item(i, i) if j is None else covar.item(i, i) + covar.item(j, j)
        return trace > threshold
    return check


_COVARIANCE_TYPES = (CovarianceMatrix, np.ndarray)


__all__ = ["ArrayDeletion"]
