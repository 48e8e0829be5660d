r"""Deleters that judge tracks against each other, and a composite that can hold them.

Stone Soup's :class:`~stonesoup.deleter.base.Deleter` judges one track at a time
(``check_for_deletion``), and its :class:`~stonesoup.deleter.multi.CompositeDeleter` asks
each member about one track at a time. A rule such as "of two duplicate tracks, delete one"
needs the other tracks: a :class:`PairwiseDeleter` answers for a whole set
(:meth:`PairwiseDeleter.tracks_to_delete`) and refuses to judge a track alone, and
:class:`CompositeDeleter` — Stone Soup's, with the same Properties and the same verdicts for
per-track members — asks such members about the whole set once.
"""
from __future__ import annotations

from abc import abstractmethod

from stonesoup.deleter.base import Deleter
from stonesoup.deleter.multi import CompositeDeleter as _StockCompositeDeleter
from stonesoup.types.update import Update


def _refusal(deleter) -> TypeError:
    return TypeError(
        f"{type(deleter).__name__} compares tracks with each other, so it cannot judge one "
        "track alone (check_for_deletion): call delete_tracks(tracks), or make it a member "
        "of ctxmodels.stonesoup.CompositeDeleter (Stone Soup's CompositeDeleter asks its "
        "members one track at a time)")


def drop_last_predictions(tracks) -> None:
    """``delete_last_pred``: removes the last state of each of ``tracks`` (and its
    metadata) when it is not an :class:`~stonesoup.types.update.Update`."""
    for track in tracks:
        if not isinstance(track[-1], Update):
            del track[-1]
            del track.metadatas[-1]


def composite_verdicts(intersect: bool, members, count: int) -> list[bool]:
    r"""The verdicts of a composite of ``members`` on ``count`` tracks (numbered 0 to
    ``count`` − 1), by Stone Soup's :class:`~stonesoup.deleter.multi.CompositeDeleter` rule:

    .. math::
        \text{delete} \iff \bigwedge_j d_j \ \ (\text{intersect}), \qquad
        \text{delete} \iff \bigvee_j d_j \ \ (\text{union}),

    :math:`d_j` member :math:`j`'s verdict, the members asked in order until one decides: a
    member saying "keep" in an intersection, or "delete" in a union, decides, and the later
    members are not asked about that track. Each member is a function from a list of track
    numbers, those no earlier member decided, to their verdicts (aligned, truthy: delete);
    it is not called once every track is decided. The component path's composite and the
    array path's evaluation of one both come here; only the order of the calls differs
    from Stone Soup's (member by member, not track by track), not which are made."""
    verdicts = [intersect] * count
    undecided = list(range(count))
    for member in members:
        if not undecided:
            break
        says = member(undecided)
        decided = [k for k, s in zip(undecided, says) if not s] if intersect else \
            [k for k, s in zip(undecided, says) if s]
        if decided:
            for k in decided:
                verdicts[k] = not intersect
            undecided = [k for k, s in zip(undecided, says) if s] if intersect else \
                [k for k, s in zip(undecided, says) if not s]
    return verdicts


def compares_tracks(deleter) -> bool:
    """Whether ``deleter`` must be asked about a whole set of tracks at once."""
    return isinstance(deleter, (PairwiseDeleter, CompositeDeleter)) and deleter.compares_tracks


class PairwiseDeleter(Deleter):
    """A deleter whose verdict on a track depends on the other tracks (abstract): it
    implements :meth:`tracks_to_delete`; ``check_for_deletion`` raises a ``TypeError``."""

    compares_tracks = True

    @abstractmethod
    def tracks_to_delete(self, tracks, **kwargs) -> set:
        """The tracks of ``tracks`` (any iterable) to delete; nothing is changed."""

    def check_for_deletion(self, track, **kwargs) -> bool:
        raise _refusal(self)

    def delete_tracks(self, tracks, **kwargs) -> set:
        """:meth:`tracks_to_delete`, then ``delete_last_pred`` as Stone Soup's deleters
        apply it."""
        deleted = self.tracks_to_delete(tracks, **kwargs)
        if self.delete_last_pred:
            drop_last_predictions(deleted)
        return deleted


class CompositeDeleter(_StockCompositeDeleter):
    """:class:`stonesoup.deleter.multi.CompositeDeleter` that also takes members which
    compare tracks with each other (:class:`PairwiseDeleter`, or a composite holding one).
    Such a member is asked once about the whole set handed to :meth:`delete_tracks` and
    says "delete" for the tracks it returns; the others are asked about single tracks, as
    Stone Soup asks them. Per track, the rule is Stone Soup's (:func:`composite_verdicts`):
    delete when all members say so (``intersect``) or when any does, the members asked in
    order until one decides. With only per-track members the verdicts are Stone Soup's
    composite's.

    A pairwise member thus judges all the tracks, including those another member deletes
    in the same call (a union does not first remove them)."""

    @property
    def compares_tracks(self) -> bool:
        return any(compares_tracks(member) for member in self.deleters)

    def check_for_deletion(self, track, **kwargs) -> bool:
        if self.compares_tracks:
            raise _refusal(self)
        members = [_asking(member, [track], kwargs) for member in self.deleters]
        return composite_verdicts(bool(self.intersect), members, 1)[0]

    def tracks_to_delete(self, tracks, **kwargs) -> set:
        """The tracks of ``tracks`` to delete by the composite's rule
        (:func:`composite_verdicts`); nothing is changed."""
        tracks = list(tracks)
        members = []
        for member in self.deleters:
            if compares_tracks(member):  # asked about the whole set first, once
                says = member.tracks_to_delete(tracks, **kwargs)
                members.append(lambda rows, says=says: [tracks[k] in says for k in rows])
            else:
                members.append(_asking(member, tracks, kwargs))
        verdicts = composite_verdicts(bool(self.intersect), members, len(tracks))
        return {track for track, says in zip(tracks, verdicts) if says}

    def delete_tracks(self, tracks, **kwargs) -> set:
        deleted = self.tracks_to_delete(tracks, **kwargs)
        if self.delete_last_pred:
            drop_last_predictions(deleted)
        return deleted


def _asking(member, tracks, kwargs):
    """A per-track ``member`` as :func:`composite_verdicts` asks it about ``tracks``."""
    return lambda rows: [member.check_for_deletion(tracks[k], **kwargs) for k in rows]


__all__ = ["CompositeDeleter", "PairwiseDeleter", "compares_tracks", "composite_verdicts",
           "drop_last_predictions"]
