r"""Deletion on :class:`~ctxmodels.stonesoup.ArrayJPDATracker`'s array path: what the deleter
reads, kept per track as states are appended, so that the verdicts never walk every track at
every scan.

The verdicts are the deleters' own (:mod:`~ctxmodels.stonesoup.jpda.deleter`,
:mod:`~ctxmodels.stonesoup.jpda.composite_deleter`); this module keeps what they read:

* miss counters, kept per track as states are appended (read from the track once, or
  again after a change from outside): the distinct timestamps since the last
  detection-backed state (``UpdateTimeStepsDeleter``,
  :func:`~ctxmodels.stonesoup.jpda.deleter.time_steps_verdict`), the P_D of each state since
  then (:meth:`ExpectedMissesDeleter.deletes_after
  <ctxmodels.stonesoup.ExpectedMissesDeleter.deletes_after>`), the time of the latest
  detection-backed state (Stone Soup's :class:`~stonesoup.deleter.time.UpdateTimeDeleter`,
  :func:`~ctxmodels.stonesoup.jpda.deleter.update_time_verdict`);
* the scan's posterior covariances, stacked (Stone Soup's
  :class:`~stonesoup.deleter.error.CovarianceBasedDeleter`,
  :func:`~ctxmodels.stonesoup.jpda.deleter.covariance_verdict`) and means
  (:class:`~ctxmodels.stonesoup.DuplicateTrackDeleter`, which compares tracks in pairs).

A :class:`~stonesoup.deleter.multi.CompositeDeleter` (Stone Soup's, or ctxmodels'
:class:`~ctxmodels.stonesoup.CompositeDeleter`, the one that takes a pairwise member) of
such members is evaluated by
:func:`~ctxmodels.stonesoup.jpda.composite_deleter.composite_verdicts`, member by member in
its order.
"""
from __future__ import annotations

import datetime

from stonesoup.deleter.error import CovarianceBasedDeleter
from stonesoup.deleter.multi import CompositeDeleter
from stonesoup.deleter.time import UpdateTimeDeleter
from stonesoup.deleter.time import UpdateTimeStepsDeleter as _StockUpdateTimeStepsDeleter

from .composite_deleter import CompositeDeleter as _PairwiseCompositeDeleter
from .composite_deleter import composite_verdicts
from .deleter import (DuplicateTrackDeleter, ExpectedMissesDeleter, UpdateTimeStepsDeleter,
                      covariance_verdict, latest_detection_time, time_steps_verdict,
                      times_since_detection, update_time_verdict)
from .._batch import plain_track_lists
from ..scan_context import context_kwargs

_COMPOSITES = (CompositeDeleter, _PairwiseCompositeDeleter)


def _track_length(track) -> int:
    lists = plain_track_lists(track)
    return len(track) if lists is None else len(lists[0])


def _last_state(track):
    """``track.state`` (its last), read without Stone Soup's attribute proxy."""
    lists = plain_track_lists(track)
    return (track.states if lists is None else lists[0])[-1]


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
    ``deleter``, each track's counters, and the deleter's verdicts from them."""

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
        from outside), by the deleters' own readers."""
        states = track.states
        values = []
        for kind, member in plan.counted:
            if kind == "steps":
                values.append(times_since_detection(states))
            elif kind == "time":
                values.append(latest_detection_time(states))
            else:
                values.append([pd for pd in member.prob_detect_since_detection(track)
                               if pd != 0.0])
        counter = _MissCounter(len(track), values)
        self._counters[track] = counter
        return counter

    def _delete(self, tracks, detections, latest=None, counted_now=frozenset()):
        """The tracks of ``tracks`` to delete. ``latest``: (the scan's tracks in order,
        their posterior means (N, D), covariances (N, D, D), the scan time), which a
        pairwise or covariance member reads. ``counted_now``: plain tracks whose one state
        of this scan was just appended to their lists and counted (:meth:`_count`): a
        counter they still have describes them, and their last state holds their row of
        ``latest``."""
        plan = self._deletion_plan()
        if plan is None:
            deleter = self.deleter
            return deleter.delete_tracks(tracks,
                                         **context_kwargs(detections, deleter.delete_tracks))
        tracks = list(tracks)
        counters = None
        if plan.counted:
            known = self._counters
            counters = []
            for track in tracks:
                counter = known.get(track)
                if counter is None or (track not in counted_now
                                       and counter.length != _track_length(track)):
                    counter = self._read_counter(track, plan)
                counters.append(counter)
        members = [_asking(kind, member, k, tracks, counters, latest, counted_now)
                   for kind, member, k in plan.members]
        verdicts = composite_verdicts(plan.intersect, members, len(tracks))
        deleted = {track for track, says in zip(tracks, verdicts) if says}
        for track in deleted:
            self._counters.pop(track, None)
        return deleted


def _asking(kind, member, k, tracks, counters, latest, counted_now):
    """A member of the plan as :func:`composite_verdicts` asks it: a function from the
    numbers of ``tracks`` to their verdicts, from the counters (slot ``k``), the scan's
    posteriors, or (a time window that is not a ``timedelta``) the deleter itself."""
    if kind == "steps":
        return lambda rows: [time_steps_verdict(member, len(counters[r].values[k]))
                             for r in rows]
    if kind == "expected":
        deletes_after = member.deletes_after
        return lambda rows: [deletes_after(reversed(counters[r].values[k])) for r in rows]
    if kind == "time":
        if type(member.time_since_update) is not datetime.timedelta:
            # (times that are not datetimes: the deleter's own arithmetic)
            return lambda rows: [member.check_for_deletion(tracks[r]) for r in rows]
        return lambda rows: [
            update_time_verdict(member, counters[r].values[k], _last_state(tracks[r]).timestamp)
            for r in rows]
    if kind == "pairwise":
        says = _pairwise_verdicts(member, tracks, latest)
        return lambda rows: [tracks[r] in says for r in rows]
    return lambda rows: _covariance_verdicts(member, [tracks[r] for r in rows], latest,
                                             counted_now)


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


def _covariance_verdicts(member, tracks, latest, counted_now) -> list:
    """:func:`~ctxmodels.stonesoup.jpda.deleter.covariance_verdict` of ``tracks``' last
    covariances: for the scan's tracks in ``counted_now``, whose last state holds their row
    of the scan's posterior covariances (``latest``: the same numbers), on all those rows at
    once; for any other track, on its last state's covariance."""
    if latest is None or not counted_now:
        return [covariance_verdict(member, _last_state(track).covar) for track in tracks]
    scan = dict(zip(latest[0], covariance_verdict(member, latest[2]).tolist()))
    return [scan[track] if track in counted_now
            else covariance_verdict(member, _last_state(track).covar) for track in tracks]


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
            return (bool(deleter.intersect), tuple(map(id, deleter.deleters)))
        return None

    def still_describes(self, deleter) -> bool:
        return self._signature(deleter) == self._seen


__all__ = ["ArrayDeletion"]
