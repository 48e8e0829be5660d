"""The P_D of each track's states since its last detection-backed one: what the
hypothesiser records as it predicts and the deleter records from a scan's context, and what
an expected-misses deleter sums.

Tracks are keyed weakly (a track the tracker drops drops its record) and by identity; only
the states after the last detection-backed one are kept. A pickle holds the record as plain
``(track, {index: (timestamp, P_D)})`` pairs.
"""
from __future__ import annotations

import weakref


class PDRecord:
    """P_D per (track, state index), each entry valid only while the state at that index
    still has the timestamp it was recorded with."""

    __slots__ = ("_by_track",)

    def __init__(self, pairs=()):
        self._by_track = weakref.WeakKeyDictionary(pairs)

    def record(self, track, index: int, timestamp, prob_detect: float, restart: bool) -> None:
        """Records ``prob_detect`` for the state at ``index`` of ``track`` (at
        ``timestamp``); ``restart``: the state before it is detection-backed, so the
        earlier entries no longer matter."""
        entries = self._by_track.get(track)
        if entries is None or restart:
            entries = self._by_track[track] = {}
        entries[index] = (timestamp, prob_detect)

    def get(self, track, index: int, timestamp) -> float | None:
        """The P_D recorded for the state at ``index`` of ``track`` if it was recorded at
        ``timestamp``, else None."""
        entry = self._by_track.get(track, {}).get(index)
        return None if entry is None or entry[0] != timestamp else entry[1]

    def __len__(self) -> int:
        return len(self._by_track)

    def __reduce__(self):
        return type(self), (list(self._by_track.items()),)


__all__ = ["PDRecord"]
