r"""The plain NumPy form the metrics read: :class:`EvaluationFrame` (truth ids and positions,
track ids and positions at one evaluation time), and :func:`frames_from_stonesoup`, which makes
them from Stone Soup :class:`~stonesoup.types.groundtruth.GroundTruthPath` /
:class:`~stonesoup.types.track.Track` objects.

Which objects exist at an evaluation time
-----------------------------------------
A truth or track exists at :math:`t` exactly when it has a state whose
timestamp equals :math:`t` (the last such state is used if there are several,
as Stone Soup's metric generators do). Stone Soup trackers append a state to
every live track at every scan they process, so a track that is alive at a
radar scan has a state at that radar timestamp. A ground-truth path that spans
:math:`t` but has no state at :math:`t` means the truth was sampled on another
time grid; that would silently turn every target into a miss, so it raises
:class:`ValueError` instead.
"""
from __future__ import annotations

import datetime
import operator
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from stonesoup.types.state import StateMutableSequence


def id_array(value, name: str) -> np.ndarray:
    ids = np.asarray(value)
    if ids.size == 0:
        return np.zeros(0, dtype=np.int64)
    if ids.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional, got shape {ids.shape}")
    if not np.issubdtype(ids.dtype, np.integer):
        raise TypeError(f"{name} must hold integers, got dtype {ids.dtype}")
    if np.unique(ids).size != ids.size:
        raise ValueError(f"{name} must not repeat an id within one time")
    return ids.astype(np.int64, copy=False)


def _position_array(value, name: str, count: int, ids_name: str) -> np.ndarray:
    try:
        positions = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as error:
        raise TypeError(f"{name} must be an array of numbers: {error}") from None
    if positions.size == 0 and count == 0:
        dim = positions.shape[-1] if positions.ndim == 2 else 0
        return positions.reshape(0, dim)
    if positions.ndim != 2:
        raise ValueError(f"{name} must have shape (n, dim), got shape {positions.shape}")
    if positions.shape[0] != count:
        raise ValueError(f"{name} has {positions.shape[0]} rows but {ids_name} has {count} ids")
    if not np.all(np.isfinite(positions)):
        raise ValueError(f"{name} must be finite")
    return positions


def frame_list(frames, name: str) -> list[EvaluationFrame]:
    if isinstance(frames, EvaluationFrame):
        raise TypeError(f"{name} must be a sequence of EvaluationFrame, got a single frame")
    frames = list(frames)
    if not frames:
        raise ValueError(f"{name} must contain at least one evaluation time")
    for index, frame in enumerate(frames):
        if not isinstance(frame, EvaluationFrame):
            raise TypeError(
                f"{name}[{index}] must be an EvaluationFrame, got {type(frame).__name__}")
    return frames


@dataclass(frozen=True, eq=False)
class EvaluationFrame:
    """Truths and tracks that exist at one evaluation time.

    Ids are integers, unique within the frame and stable across frames (the
    same object keeps its id); their values are otherwise arbitrary. Positions
    are arrays of shape ``(n, dim)`` in metres; an empty side may be given as
    any empty array.
    """
    truth_ids: np.ndarray
    truth_positions: np.ndarray
    track_ids: np.ndarray
    track_positions: np.ndarray

    def __post_init__(self):
        truth_ids = id_array(self.truth_ids, "truth_ids")
        track_ids = id_array(self.track_ids, "track_ids")
        truth_positions = _position_array(
            self.truth_positions, "truth_positions", truth_ids.size, "truth_ids")
        track_positions = _position_array(
            self.track_positions, "track_positions", track_ids.size, "track_ids")
        if (truth_ids.size and track_ids.size
                and truth_positions.shape[1] != track_positions.shape[1]):
            raise ValueError(
                f"truth_positions have dimension {truth_positions.shape[1]} but "
                f"track_positions have dimension {track_positions.shape[1]}")
        for field, value in (("truth_ids", truth_ids), ("truth_positions", truth_positions),
                             ("track_ids", track_ids), ("track_positions", track_positions)):
            value.setflags(write=False)
            object.__setattr__(self, field, value)


def pairwise_distances(truth_positions: np.ndarray, track_positions: np.ndarray) -> np.ndarray:
    difference = truth_positions[:, np.newaxis, :] - track_positions[np.newaxis, :, :]
    return np.sqrt(np.sum(difference * difference, axis=-1))


def _paths(paths, name: str) -> list[StateMutableSequence]:
    if isinstance(paths, StateMutableSequence):
        raise TypeError(f"{name} must be a collection of paths/tracks, got a single "
                        f"{type(paths).__name__}; wrap it in a list")
    try:
        paths = list(paths)
    except TypeError:
        raise TypeError(f"{name} must be an iterable of paths/tracks, "
                        f"got {type(paths).__name__}") from None
    for index, path in enumerate(paths):
        if not isinstance(path, StateMutableSequence):
            raise TypeError(f"{name} must hold GroundTruthPath/Track objects, element {index} "
                            f"is a {type(path).__name__}")
    return paths


def _position_mapping(position_mapping) -> np.ndarray:
    mapping = np.asarray(position_mapping)
    if (mapping.ndim != 1 or mapping.size == 0 or not np.issubdtype(mapping.dtype, np.integer)
            or np.any(mapping < 0)):
        raise ValueError("position_mapping must be a non-empty sequence of non-negative "
                         f"integer indices, got {position_mapping!r}")
    return mapping


def _timestamps(timestamps) -> list[datetime.datetime]:
    timestamps = list(timestamps)
    if not timestamps:
        raise ValueError("timestamps must contain at least one evaluation time")
    for index, timestamp in enumerate(timestamps):
        if not isinstance(timestamp, datetime.datetime):
            raise TypeError(f"timestamps[{index}] must be a datetime, "
                            f"got {type(timestamp).__name__}")
    if len(set(timestamps)) != len(timestamps):
        raise ValueError("timestamps must not repeat a time")
    return timestamps


def _state_position(state, mapping: np.ndarray, name: str) -> np.ndarray:
    # Like Stone Soup's Euclidean measure: mixtures/particles expose `mean`.
    vector = np.asarray(getattr(state, "mean", state.state_vector), dtype=float).reshape(-1)
    if mapping.max() >= vector.size:
        raise ValueError(f"position_mapping {mapping.tolist()} does not fit the "
                         f"{vector.size}-dimensional state vectors of {name}")
    return vector[mapping]


_timestamp_of = operator.attrgetter("timestamp")


def _positions_at(paths, mapping, timestamps, name: str, require_inside_span: bool):
    """Per timestamp: indices of the paths with a state there, and positions."""
    wanted = set(timestamps)
    present: dict[datetime.datetime, tuple[list[int], list[np.ndarray]]] = {
        timestamp: ([], []) for timestamp in timestamps}
    for index, path in enumerate(paths):
        states = path.states
        stamps = list(map(_timestamp_of, states))
        # later states at the same time win
        state_at = {stamp: state for stamp, state in zip(stamps, states) if stamp in wanted}
        if require_inside_span and stamps:
            first, last = min(stamps), max(stamps)
            gaps = [t for t in timestamps if first <= t <= last and t not in state_at]
            if gaps:
                raise ValueError(
                    f"{name}[{index}] spans {first}..{last} but has no state at evaluation "
                    f"time {gaps[0]}; sample the ground truth at every evaluation time")
        for timestamp, state in state_at.items():
            present[timestamp][0].append(index)
            present[timestamp][1].append(_state_position(state, mapping, name))
    return present


def frames_from_stonesoup(truths: Iterable, tracks: Iterable,
                          timestamps: Iterable[datetime.datetime], *,
                          position_mapping: Sequence[int] = (0, 2)) -> list[EvaluationFrame]:
    """Convert Stone Soup truths and tracks to one :class:`EvaluationFrame` per timestamp.

    An object is present at a timestamp if it has a state at exactly that
    timestamp (see the module docstring). Ids are the objects' positions in
    ``truths`` / ``tracks`` as iterated once here. Raises ValueError if a
    ground-truth path spans an evaluation time without a state there.
    """
    truths = _paths(truths, "truths")
    tracks = _paths(tracks, "tracks")
    timestamps = _timestamps(timestamps)
    mapping = _position_mapping(position_mapping)
    truth_present = _positions_at(truths, mapping, timestamps, "truths", True)
    track_present = _positions_at(tracks, mapping, timestamps, "tracks", False)
    frames = []
    empty = np.zeros((0, mapping.size))
    for timestamp in timestamps:
        truth_ids, truth_positions = truth_present[timestamp]
        track_ids, track_positions = track_present[timestamp]
        frames.append(EvaluationFrame(
            truth_ids=np.array(truth_ids, dtype=np.int64),
            truth_positions=np.array(truth_positions) if truth_positions else empty,
            track_ids=np.array(track_ids, dtype=np.int64),
            track_positions=np.array(track_positions) if track_positions else empty))
    return frames
