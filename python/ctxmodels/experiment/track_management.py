r"""Track management: false tracks, identity switches, fragmentation and time to track.

HOTA and GOSPA fold track management into one number each; a tracking engineer also asks
how many false tracks a tracker carries and for how long, how often a vessel's track
changes identity or breaks up, and how long a vessel waits for its first track. These are
computed from the same :class:`~.metrics.EvaluationFrame` s as HOTA and GOSPA (in the
study: at the radar times, tracks on static objects already dropped), with the frames'
times :math:`t_1 < \dots < t_T` in seconds.

Matching
--------
At frame :math:`f`, truths and tracks are matched by GOSPA's optimal assignment with
cut-off :math:`c` (and exponent :math:`p`): a truth and a track are *matched* when the
assignment pairs them at a distance below :math:`c`. These are exactly the pairs whose
distances make up GOSPA's localisation term (:func:`~.metrics.gospa_from_frames` with the
same :math:`c` and :math:`p`), so an unmatched truth is one of GOSPA's missed targets and
an unmatched track one of its false tracks. A truth (track) is *present* at the frames
that hold its id.

Per run
-------
``false_tracks_per_scan``
    :math:`\frac{1}{T}\sum_f (\text{unmatched tracks at } f)`: GOSPA's false-track count,
    averaged over frames.
``false_tracks``, ``false_track_lifetime``
    A *false track* is a track id matched at none of the frames it is present at. Its
    lifetime is :math:`t_\text{last} - t_\text{first}` over the frames it is present at
    (0 for a track present at one frame; frames in between where it is absent still
    count). ``false_track_lifetime`` is the mean lifetime of the false tracks, 0.0 when
    there are none (``false_tracks`` then says so).
``id_switches``
    Per truth, over the frames where it is matched, in order: the number of times its
    track differs from the one it was last matched to (an unmatched frame in between
    does not reset that memory: CLEAR-MOT's IDSW). Summed over truths.
``fragmentations``
    Per truth, over the frames where it is present: the number of times it goes from
    matched to unmatched and is matched again later (each resumed interruption counts
    once; one still unresumed at its last frame does not). Frames where the truth is
    absent are skipped, neither interrupting nor resuming. Summed over truths.
``tracked_fraction``
    Matched truth-frames over present truth-frames (:math:`1 -` GOSPA's missed count over
    the truth count); 1.0 when no truth is present at any frame (nothing was missed).
``time_to_track``, ``never_tracked``
    Per truth, the time from its first presence to its first match; a truth never
    matched counts the whole time it was present (last minus first presence) and is
    counted in ``never_tracked``. ``time_to_track`` is the mean over truths, 0.0 when
    there are none. A truth present from the first frame counts from that frame.

Pooling
-------
:class:`TrackManagement` stores only additive totals (counts, summed seconds, frames);
the rates are properties formed from them. :func:`combine` adds the totals of several
runs, so a pooled rate is a ratio of sums (a run weighs in by its frames, truths or false
tracks), not a mean of per-run rates, as :func:`~.metrics.combine_hota` and
:func:`~.metrics.combine_gospa` pool. Pooled runs equal one run over the concatenated
frames whenever no truth or track id is shared between runs.
"""
from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, fields

import numpy as np

from .metrics.frames import EvaluationFrame, frame_list
from .metrics.gospa import GOSPA_C, GOSPA_P, check_gospa_parameters, gospa_assignment

__all__ = ["TrackManagement", "track_management", "combine"]

#: The totals that add up when runs are pooled (every field but c and p).
_TOTALS = ("frames", "truths", "tracks", "truth_frames", "matched_truth_frames",
           "unmatched_track_frames", "false_tracks", "false_track_seconds", "id_switches",
           "fragmentations", "never_tracked", "time_to_track_seconds")


@dataclass(frozen=True)
class TrackManagement:
    """The track-management totals of one run (or several pooled by :func:`combine`) and
    the rates formed from them; see the module docs for the definitions."""
    c: float
    p: float
    frames: int
    #: Distinct truth and track ids present at some frame.
    truths: int
    tracks: int
    #: Truth presences over all frames, and those matched.
    truth_frames: int
    matched_truth_frames: int
    #: Track presences over all frames that are not matched.
    unmatched_track_frames: int
    false_tracks: int
    #: Summed lifetimes of the false tracks.
    false_track_seconds: float
    id_switches: int
    fragmentations: int
    never_tracked: int
    #: Summed time to track over all truths (never-tracked ones count their presence).
    time_to_track_seconds: float

    @property
    def false_tracks_per_scan(self) -> float:
        return self.unmatched_track_frames / max(1, self.frames)

    @property
    def false_track_lifetime(self) -> float:
        return self.false_track_seconds / max(1, self.false_tracks)

    @property
    def tracked_fraction(self) -> float:
        if self.truth_frames == 0:
            return 1.0
        return self.matched_truth_frames / self.truth_frames

    @property
    def time_to_track(self) -> float:
        return self.time_to_track_seconds / max(1, self.truths)

    def as_dict(self) -> dict:
        """Totals and rates, plain Python numbers."""
        values = {field.name: getattr(self, field.name) for field in fields(self)}
        values.update(false_tracks_per_scan=self.false_tracks_per_scan,
                      false_track_lifetime=self.false_track_lifetime,
                      tracked_fraction=self.tracked_fraction,
                      time_to_track=self.time_to_track)
        return values


def _times(times, count: int) -> np.ndarray:
    try:
        seconds = np.asarray(times, dtype=float)
    except (TypeError, ValueError):
        raise TypeError("times must be numbers (seconds), "
                        f"got {type(times).__name__}") from None
    if seconds.ndim != 1:
        raise ValueError(f"times must be one-dimensional, got shape {seconds.shape}")
    if seconds.size != count:
        raise ValueError(f"times has {seconds.size} entries but frames has {count}")
    if not np.all(np.isfinite(seconds)):
        raise ValueError("times must be finite")
    if np.any(np.diff(seconds) <= 0):
        raise ValueError("times must be strictly increasing")
    return seconds


def track_management(frames: Iterable[EvaluationFrame], times: Sequence[float], *,
                     c: float = GOSPA_C,
                     p: float = GOSPA_P) -> TrackManagement:
    """Track-management totals of one run: ``frames`` at ``times`` (seconds, strictly
    increasing, one per frame), matched by GOSPA's assignment with cut-off ``c`` and
    exponent ``p`` (see the module docs)."""
    frames = frame_list(frames, "frames")
    seconds = _times(times, len(frames))
    c, p = check_gospa_parameters(c, p)

    truth_first: dict[int, float] = {}
    truth_last: dict[int, float] = {}
    first_match: dict[int, float] = {}
    last_track: dict[int, int] = {}  # the track each truth was last matched to
    interrupted: set[int] = set()  # matched before, unmatched since
    track_first: dict[int, float] = {}
    track_last: dict[int, float] = {}
    ever_matched: set[int] = set()
    truth_frames = matched_truth_frames = unmatched_track_frames = 0
    id_switches = fragmentations = 0

    for frame, t in zip(frames, seconds.tolist()):
        rows, cols, _ = gospa_assignment(frame.truth_positions, frame.track_positions, c, p)
        truth_ids, track_ids = frame.truth_ids.tolist(), frame.track_ids.tolist()
        match = {truth_ids[r]: track_ids[k] for r, k in zip(rows.tolist(), cols.tolist())}
        truth_frames += len(truth_ids)
        matched_truth_frames += len(match)
        unmatched_track_frames += len(track_ids) - len(match)
        ever_matched.update(match.values())
        for track in track_ids:
            track_first.setdefault(track, t)
            track_last[track] = t
        for truth in truth_ids:
            truth_first.setdefault(truth, t)
            truth_last[truth] = t
            track = match.get(truth)
            if track is None:
                if truth in last_track:
                    interrupted.add(truth)
                continue
            if truth in last_track and last_track[truth] != track:
                id_switches += 1
            last_track[truth] = track
            first_match.setdefault(truth, t)
            if truth in interrupted:
                fragmentations += 1
                interrupted.discard(truth)

    false_tracks = [track for track in track_first if track not in ever_matched]
    never_tracked = sum(1 for truth in truth_first if truth not in first_match)
    return TrackManagement(
        c=c, p=p, frames=len(frames), truths=len(truth_first), tracks=len(track_first),
        truth_frames=truth_frames, matched_truth_frames=matched_truth_frames,
        unmatched_track_frames=unmatched_track_frames, false_tracks=len(false_tracks),
        false_track_seconds=float(sum(track_last[k] - track_first[k] for k in false_tracks)),
        id_switches=id_switches, fragmentations=fragmentations, never_tracked=never_tracked,
        time_to_track_seconds=float(sum(
            first_match.get(truth, truth_last[truth]) - first for truth, first
            in truth_first.items())))


def combine(results: Iterable[TrackManagement]) -> TrackManagement:
    """Pool several runs: their totals add up, so every rate is a ratio of sums. The runs
    must use the same ``c`` and ``p``."""
    results = list(results)
    if not results:
        raise ValueError("results must contain at least one TrackManagement")
    for index, result in enumerate(results):
        if not isinstance(result, TrackManagement):
            raise TypeError(f"results[{index}] must be a TrackManagement, "
                            f"got {type(result).__name__}")
    if len({(result.c, result.p) for result in results}) != 1:
        raise ValueError("results must all use the same c and p")
    return TrackManagement(c=results[0].c, p=results[0].p,
                           **{name: sum(getattr(result, name) for result in results)
                              for name in _TOTALS})
