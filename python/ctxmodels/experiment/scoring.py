"""Scoring one run: the tracks a tracker reported, against the vessels, at radar times.

Ground truth is the moving vessels (the paper's RTK-logged targets). Static objects — sea
markers and islets, detected by both sensors — are *distractors*, handled as MOTChallenge
evaluations handle them (TrackEval removes tracker outputs matched to distractor ground
truth before scoring): at each evaluation time, track positions are assigned jointly to
vessels and static objects (Hungarian, HOTA similarity), and positions assigned to a static
object with similarity ≥ 0.5 are dropped. A track on a charted marker is then neither a hit
nor a false track; without this, the paper's scores (HOTA ≈ 90 % on Scenario 1 with several
markers and islets in view) would be impossible.

The reported tracks are converted once to :class:`~.metrics.EvaluationFrame` s (one per
radar time); distractors are dropped from the frames, and HOTA, GOSPA and the
track-management metrics (:mod:`~.track_management`, at the radar times in seconds from the
first) are computed from the same frames.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from . import metrics
from .track_management import TrackManagement, track_management

#: Similarity at or above which a track position assigned to a static object is dropped.
DISTRACTOR_SIMILARITY = 0.5


@dataclass(frozen=True)
class RunScore:
    hota: metrics.HOTAResult
    gospa: metrics.GOSPAResult
    #: Tracks with at least one state left once the distractor positions are dropped.
    track_count: int
    #: Tracks and vessels present at each evaluation time, distractors dropped.
    tracks_per_time: tuple[int, ...]
    truths_per_time: tuple[int, ...]
    #: False tracks, ID switches, fragmentations, time to track (GOSPA's matching).
    management: TrackManagement


def drop_distractors(frames: list[metrics.EvaluationFrame],
                     static_positions: np.ndarray) -> tuple[list[metrics.EvaluationFrame], np.ndarray]:
    """The frames without the track positions that lie on static objects (see the module
    docs), and the ids of the dropped positions' tracks (one entry per dropped position)."""
    statics = np.asarray(static_positions, dtype=float).reshape(-1, 2)
    if not len(statics):
        return list(frames), np.zeros(0, dtype=np.int64)
    kept_frames, dropped = [], []
    for frame in frames:
        if not frame.track_ids.size:
            kept_frames.append(frame)
            continue
        objects = np.vstack([frame.truth_positions.reshape(-1, 2), statics])
        n_vessels = len(objects) - len(statics)
        similarity = metrics.position_similarity(objects, frame.track_positions)
        rows, cols = linear_sum_assignment(-similarity)
        on_static = cols[(rows >= n_vessels) & (similarity[rows, cols] >= DISTRACTOR_SIMILARITY)]
        if not on_static.size:
            kept_frames.append(frame)
            continue
        keep = np.ones(frame.track_ids.size, dtype=bool)
        keep[on_static] = False
        dropped.append(frame.track_ids[on_static])
        kept_frames.append(metrics.EvaluationFrame(
            frame.truth_ids, frame.truth_positions, frame.track_ids[keep],
            frame.track_positions[keep]))
    return kept_frames, (np.concatenate(dropped) if dropped else np.zeros(0, dtype=np.int64))


def score_run(run, tracks: list, static_distractors: bool = True,
              mapping=(0, 2)) -> RunScore:
    """HOTA, GOSPA and the track-management metrics of ``tracks`` (in a fixed order) against
    ``run``'s vessels at its radar times, static objects as distractors unless
    ``static_distractors`` is false.

    The distances (HOTA's full and zero similarity, 5 m and 30 m; GOSPA's cut-off c = 30 m)
    are the paper's for its 1.6 km radar, times ``run.distance_scale`` where a run has one
    (a scene whose radars reach farther, where their bearing errors span more metres)."""
    truths = list(run.truth_by_id.values())  # by id, not set (address) order
    frames = metrics.frames_from_stonesoup(truths, tracks, run.radar_times,
                                           position_mapping=mapping)
    track_count = len(tracks)
    if static_distractors:
        frames, dropped = drop_distractors(frames, run.static_positions)
        if dropped.size:
            # A track disappears only when every one of its states was a dropped position.
            dropped_per_track = np.bincount(dropped, minlength=len(tracks))
            lengths = np.array([len(track.states) for track in tracks])
            track_count -= int(np.count_nonzero(dropped_per_track == lengths))
    start = run.radar_times[0]
    seconds = [(time - start).total_seconds() for time in run.radar_times]
    scale = getattr(run, "distance_scale", 1.0)
    c = metrics.GOSPA_C * scale
    hota = metrics.hota_from_frames(
        frames, full_similarity_distance=metrics.FULL_SIMILARITY_DISTANCE * scale,
        zero_similarity_distance=metrics.ZERO_SIMILARITY_DISTANCE * scale)
    return RunScore(hota, metrics.gospa_from_frames(frames, c=c),
                    track_count, tuple(int(frame.track_ids.size) for frame in frames),
                    tuple(int(frame.truth_ids.size) for frame in frames),
                    track_management(frames, seconds, c=c))


def tracks_digest(tracks) -> str:
    """SHA-256 over the tracks' states (timestamp, state vector, covariance bytes) in the
    given order: equal digests mean bit-identical tracks."""
    digest = hashlib.sha256()
    for track in tracks:
        digest.update(b"track")
        states = track.states
        digest.update("|".join(str(s.timestamp) for s in states).encode())
        if states:
            digest.update(np.stack([np.asarray(s.state_vector, dtype=np.float64).ravel()
                                    for s in states]).tobytes())
            covars = [getattr(s, "covar", None) for s in states]
            if all(c is not None for c in covars):
                digest.update(np.stack([np.asarray(c, dtype=np.float64) for c in covars]).tobytes())
    return digest.hexdigest()
