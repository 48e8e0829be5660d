r"""Evaluation metrics of the paper's experiment: HOTA and GOSPA on positions.

Both metrics are evaluated only at caller-given timestamps (the experiment uses
the radar timestamps, so the extra tracker outputs a multi-sensor tracker makes
between radar scans do not count). Everything is built on a plain NumPy form,
:class:`EvaluationFrame` (truth ids and positions, track ids and positions at
one evaluation time); :func:`frames_from_stonesoup` converts Stone Soup
:class:`~stonesoup.types.groundtruth.GroundTruthPath` /
:class:`~stonesoup.types.track.Track` objects to it, and :func:`hota` /
:func:`gospa` do both steps at once.

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

HOTA
----
Luiten et al., "HOTA: A Higher Order Metric for Evaluating Multi-object
Tracking", IJCV 2021, computed the way TrackEval computes it. The similarity of
truth :math:`i` and track :math:`j` at one time is a function of the Euclidean
distance :math:`d_{ij}` of their positions,

.. math::
    S_{ij} = \operatorname{clip}\left(
        \frac{d_0 - d_{ij}}{d_0 - d_1}, 0, 1\right),
    \qquad d_1 = 5\,\mathrm{m},\; d_0 = 30\,\mathrm{m},

(full similarity up to :math:`d_1`, zero from :math:`d_0` on). Over the whole
sequence, each truth id :math:`g` and track id :math:`k` get a global alignment
score from the per-time soft Jaccard overlaps

.. math::
    J^t_{ij} = \frac{S_{ij}}{\sum_{j'} S_{ij'} + \sum_{i'} S_{i'j} - S_{ij}},
    \qquad
    P_{gk} = \sum_t J^t_{gk},
    \qquad
    A_{gk} = \frac{P_{gk}}{n_g + n_k - P_{gk}},

with :math:`n_g`, :math:`n_k` the number of evaluation times at which id
:math:`g` (:math:`k`) exists. At each time a Hungarian assignment maximises
:math:`\sum A_{gk} S_{ij}` over truth–track pairs. For each threshold
:math:`\alpha \in \{0.05, 0.10, \dots, 0.95\}` the assigned pairs with
:math:`S_{ij} \ge \alpha` are the true positives (TP); the other truths are
false negatives (FN), the other tracks false positives (FP). With
:math:`c_{gk}` the number of TP pairs between ids :math:`g` and :math:`k`,

.. math::
    \mathrm{DetA}_\alpha = \frac{|TP|}{|TP| + |FN| + |FP|},\quad
    \mathrm{AssA}_\alpha = \frac{1}{|TP|} \sum_{g,k}
        c_{gk}\,\frac{c_{gk}}{n_g + n_k - c_{gk}},\quad
    \mathrm{LocA}_\alpha = \frac{1}{|TP|} \sum_{TP} S_{ij},

.. math::
    \mathrm{HOTA}_\alpha = \sqrt{\mathrm{DetA}_\alpha \, \mathrm{AssA}_\alpha},
    \qquad \mathrm{HOTA} = \frac{1}{19} \sum_\alpha \mathrm{HOTA}_\alpha .

DetRe/DetPr and AssRe/AssPr replace the denominators by :math:`|TP|+|FN|`,
:math:`|TP|+|FP|`, :math:`n_g` and :math:`n_k`. TrackEval's conventions for
empty cases are kept: a ratio whose denominator count is 0 is 0, except LocA,
which is 1 when there is no TP. Several sequences (scenarios, seeds) are
combined as TrackEval's ``combine_sequences`` does, by adding TP/FN/FP and the
TP-weighted association and localisation sums before forming the ratios
(:func:`combine_hota`); this is the paper's "TrackEval multi-sequence
aggregation".

GOSPA
-----
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
import operator
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment
from stonesoup.types.state import StateMutableSequence

__all__ = [
    "HOTA_ALPHAS",
    "EvaluationFrame",
    "HOTAResult",
    "GOSPAResult",
    "position_similarity",
    "hota_from_similarity",
    "hota_from_frames",
    "combine_hota",
    "gospa_from_frames",
    "combine_gospa",
    "gospa_split",
    "frames_from_stonesoup",
    "hota",
    "gospa",
]

#: The 19 HOTA thresholds, the same floating-point values TrackEval uses.
HOTA_ALPHAS: np.ndarray = np.arange(0.05, 0.99, 0.05)
HOTA_ALPHAS.setflags(write=False)

# A similarity that equals a threshold in exact arithmetic may land one ulp
# below it; TrackEval counts such pairs as matched, so do we.
_EPS = np.finfo(float).eps

_DEFAULT_FULL_SIMILARITY_DISTANCE = 5.0
_DEFAULT_ZERO_SIMILARITY_DISTANCE = 30.0
_DEFAULT_GOSPA_C = 30.0
_DEFAULT_GOSPA_P = 2.0


# ---------------------------------------------------------------------------
# Input checking
# ---------------------------------------------------------------------------

def _id_array(value, name: str) -> np.ndarray:
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


def _positive_finite(value, name: str) -> float:
    number = float(value)
    if not np.isfinite(number) or number <= 0:
        raise ValueError(f"{name} must be a positive finite number, got {value!r}")
    return number


def _check_similarity_distances(full_similarity_distance, zero_similarity_distance):
    full = float(full_similarity_distance)
    zero = float(zero_similarity_distance)
    if not (np.isfinite(full) and np.isfinite(zero) and 0 <= full < zero):
        raise ValueError(
            "need 0 <= full_similarity_distance < zero_similarity_distance (both finite), got "
            f"full_similarity_distance={full_similarity_distance!r}, "
            f"zero_similarity_distance={zero_similarity_distance!r}")
    return full, zero


def _check_gospa_parameters(c, p):
    c = _positive_finite(c, "c")
    p = float(p)
    if not (np.isfinite(p) and p >= 1):
        raise ValueError(f"p must be a finite number >= 1, got {p!r}")
    return c, p


def _frame_list(frames, name: str) -> list[EvaluationFrame]:
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


# ---------------------------------------------------------------------------
# Plain NumPy form
# ---------------------------------------------------------------------------

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
        truth_ids = _id_array(self.truth_ids, "truth_ids")
        track_ids = _id_array(self.track_ids, "track_ids")
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


def _distances(truth_positions: np.ndarray, track_positions: np.ndarray) -> np.ndarray:
    difference = truth_positions[:, np.newaxis, :] - track_positions[np.newaxis, :, :]
    return np.sqrt(np.sum(difference * difference, axis=-1))


def position_similarity(truth_positions, track_positions, *,
                        full_similarity_distance: float = _DEFAULT_FULL_SIMILARITY_DISTANCE,
                        zero_similarity_distance: float = _DEFAULT_ZERO_SIMILARITY_DISTANCE,
                        ) -> np.ndarray:
    """HOTA similarity matrix ``(n_truths, n_tracks)`` from Euclidean distance.

    1 up to ``full_similarity_distance``, falling linearly to 0 at
    ``zero_similarity_distance`` and beyond.
    """
    full, zero = _check_similarity_distances(full_similarity_distance, zero_similarity_distance)
    truth_positions = np.asarray(truth_positions, dtype=float)
    track_positions = np.asarray(track_positions, dtype=float)
    for name, positions in (("truth_positions", truth_positions),
                            ("track_positions", track_positions)):
        if positions.ndim != 2:
            raise ValueError(f"{name} must have shape (n, dim), got shape {positions.shape}")
        if not np.all(np.isfinite(positions)):
            raise ValueError(f"{name} must be finite")
    if truth_positions.shape[0] == 0 or track_positions.shape[0] == 0:
        return np.zeros((truth_positions.shape[0], track_positions.shape[0]))
    if truth_positions.shape[1] != track_positions.shape[1]:
        raise ValueError(
            f"truth_positions have dimension {truth_positions.shape[1]} but "
            f"track_positions have dimension {track_positions.shape[1]}")
    distance = _distances(truth_positions, track_positions)
    return np.clip((zero - distance) / (zero - full), 0.0, 1.0)


# ---------------------------------------------------------------------------
# HOTA
# ---------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class HOTAResult:
    """HOTA counts and sums per threshold in :data:`HOTA_ALPHAS`.

    Only additive quantities are stored, so sequences combine by addition
    (:func:`combine_hota`); the scores are derived properties. The
    ``*_per_alpha`` properties are arrays over the 19 thresholds; the plain
    ones (``hota``, ``deta``, ...) are their means, which is what TrackEval
    and the paper report (as fractions here, not percent).
    """
    true_positives: np.ndarray
    false_negatives: np.ndarray
    false_positives: np.ndarray
    #: sum over TP of c_gk / (n_g + n_k - c_gk), i.e. AssA times |TP|
    association_sum: np.ndarray
    #: sum over TP of c_gk / n_g
    association_recall_sum: np.ndarray
    #: sum over TP of c_gk / n_k
    association_precision_sum: np.ndarray
    #: sum of similarity over TP
    localisation_sum: np.ndarray

    @property
    def alphas(self) -> np.ndarray:
        return HOTA_ALPHAS

    def _per_tp(self, total: np.ndarray) -> np.ndarray:
        return total / np.maximum(1, self.true_positives)

    @property
    def detre_per_alpha(self) -> np.ndarray:
        return self.true_positives / np.maximum(1, self.true_positives + self.false_negatives)

    @property
    def detpr_per_alpha(self) -> np.ndarray:
        return self.true_positives / np.maximum(1, self.true_positives + self.false_positives)

    @property
    def deta_per_alpha(self) -> np.ndarray:
        return self.true_positives / np.maximum(
            1, self.true_positives + self.false_negatives + self.false_positives)

    @property
    def assa_per_alpha(self) -> np.ndarray:
        return self._per_tp(self.association_sum)

    @property
    def assre_per_alpha(self) -> np.ndarray:
        return self._per_tp(self.association_recall_sum)

    @property
    def asspr_per_alpha(self) -> np.ndarray:
        return self._per_tp(self.association_precision_sum)

    @property
    def loca_per_alpha(self) -> np.ndarray:
        # TrackEval's convention: LocA is 1 where nothing was matched.
        return np.where(self.true_positives > 0,
                        self.localisation_sum / np.maximum(1, self.true_positives), 1.0)

    @property
    def hota_per_alpha(self) -> np.ndarray:
        return np.sqrt(self.deta_per_alpha * self.assa_per_alpha)

    @property
    def hota(self) -> float:
        return float(np.mean(self.hota_per_alpha))

    @property
    def deta(self) -> float:
        return float(np.mean(self.deta_per_alpha))

    @property
    def assa(self) -> float:
        return float(np.mean(self.assa_per_alpha))

    @property
    def loca(self) -> float:
        return float(np.mean(self.loca_per_alpha))

    @property
    def detre(self) -> float:
        return float(np.mean(self.detre_per_alpha))

    @property
    def detpr(self) -> float:
        return float(np.mean(self.detpr_per_alpha))

    @property
    def assre(self) -> float:
        return float(np.mean(self.assre_per_alpha))

    @property
    def asspr(self) -> float:
        return float(np.mean(self.asspr_per_alpha))

    def summary(self) -> dict[str, float]:
        """Scores averaged over the thresholds, keyed by their usual names."""
        return {"HOTA": self.hota, "DetA": self.deta, "AssA": self.assa, "LocA": self.loca,
                "DetRe": self.detre, "DetPr": self.detpr,
                "AssRe": self.assre, "AssPr": self.asspr}


_HOTA_SUM_FIELDS = ("true_positives", "false_negatives", "false_positives", "association_sum",
                    "association_recall_sum", "association_precision_sum", "localisation_sum")


def _dense_index(ids_per_frame: list[np.ndarray]) -> tuple[list[np.ndarray], int]:
    """Map arbitrary ids to 0..n-1 over the ids that actually occur."""
    occurring = np.unique(np.concatenate(ids_per_frame)) if ids_per_frame else np.zeros(0)
    return [np.searchsorted(occurring, ids) for ids in ids_per_frame], int(occurring.size)


def hota_from_similarity(truth_ids_per_frame: Sequence, track_ids_per_frame: Sequence,
                         similarity_per_frame: Sequence) -> HOTAResult:
    """HOTA of one sequence from per-time ids and similarity matrices.

    ``similarity_per_frame[t]`` has shape ``(len(truth_ids_per_frame[t]),
    len(track_ids_per_frame[t]))`` with values in [0, 1]. This is the metric
    core; :func:`hota_from_frames` builds the similarities from positions.
    """
    n_frames = len(similarity_per_frame)
    if len(truth_ids_per_frame) != n_frames or len(track_ids_per_frame) != n_frames:
        raise ValueError(
            "truth_ids_per_frame, track_ids_per_frame and similarity_per_frame must have the "
            f"same length, got {len(truth_ids_per_frame)}, {len(track_ids_per_frame)}, "
            f"{n_frames}")
    if n_frames == 0:
        raise ValueError("similarity_per_frame must contain at least one evaluation time")
    truth_ids = [_id_array(ids, f"truth_ids_per_frame[{t}]")
                 for t, ids in enumerate(truth_ids_per_frame)]
    track_ids = [_id_array(ids, f"track_ids_per_frame[{t}]")
                 for t, ids in enumerate(track_ids_per_frame)]
    similarities = []
    for t, similarity in enumerate(similarity_per_frame):
        similarity = np.asarray(similarity, dtype=float)
        expected_shape = (truth_ids[t].size, track_ids[t].size)
        if similarity.size == 0 and 0 in expected_shape:
            similarity = similarity.reshape(expected_shape)
        if similarity.shape != expected_shape:
            raise ValueError(f"similarity_per_frame[{t}] has shape {similarity.shape}, "
                             f"expected {expected_shape} from the ids")
        if not np.all((similarity >= 0) & (similarity <= 1)):  # also rejects NaN
            raise ValueError(f"similarity_per_frame[{t}] must lie in [0, 1]")
        similarities.append(similarity)

    truth_index, n_truths = _dense_index(truth_ids)
    track_index, n_tracks = _dense_index(track_ids)
    n_alphas = HOTA_ALPHAS.size

    # Pass 1: how often each id exists and how strongly each id pair overlaps.
    truth_count = np.zeros(n_truths)
    track_count = np.zeros(n_tracks)
    overlap = np.zeros((n_truths, n_tracks))
    for rows, cols, similarity in zip(truth_index, track_index, similarities):
        truth_count[rows] += 1  # ids are unique per frame, so no repeated indices
        track_count[cols] += 1
        if similarity.size == 0:
            continue
        union = similarity.sum(axis=0)[np.newaxis, :] + similarity.sum(axis=1)[:, np.newaxis] \
            - similarity
        jaccard = np.zeros_like(similarity)
        nonzero = union > _EPS
        jaccard[nonzero] = similarity[nonzero] / union[nonzero]
        overlap[np.ix_(rows, cols)] += jaccard
    # Every id occurs at least once and overlap <= min(counts), so the
    # denominator is >= 1.
    global_alignment = overlap / (truth_count[:, np.newaxis] + track_count[np.newaxis, :]
                                  - overlap)

    # Pass 2: per-time matching and detection counts.
    true_positives = np.zeros(n_alphas, dtype=np.int64)
    false_negatives = np.zeros(n_alphas, dtype=np.int64)
    false_positives = np.zeros(n_alphas, dtype=np.int64)
    localisation_sum = np.zeros(n_alphas)
    matched_truth, matched_track, matched_similarity = [], [], []
    thresholds = (HOTA_ALPHAS - _EPS)[:, np.newaxis]
    for rows, cols, similarity in zip(truth_index, track_index, similarities):
        n_truth_here, n_track_here = similarity.shape
        if n_truth_here == 0 or n_track_here == 0:
            false_negatives += n_truth_here
            false_positives += n_track_here
            continue
        score = global_alignment[np.ix_(rows, cols)] * similarity
        match_rows, match_cols = linear_sum_assignment(score, maximize=True)
        pair_similarity = similarity[match_rows, match_cols]
        is_match = pair_similarity[np.newaxis, :] >= thresholds  # (alphas, pairs)
        n_matched = is_match.sum(axis=1)
        true_positives += n_matched
        false_negatives += n_truth_here - n_matched
        false_positives += n_track_here - n_matched
        localisation_sum += (is_match * pair_similarity[np.newaxis, :]).sum(axis=1)
        matched_truth.append(rows[match_rows])
        matched_track.append(cols[match_cols])
        matched_similarity.append(pair_similarity)

    # Association: count TP pairs per (truth id, track id) for each threshold.
    association_sum = np.zeros(n_alphas)
    association_recall_sum = np.zeros(n_alphas)
    association_precision_sum = np.zeros(n_alphas)
    if matched_similarity:
        pair_key = np.concatenate(matched_truth) * n_tracks + np.concatenate(matched_track)
        pair_similarity = np.concatenate(matched_similarity)
        for a, threshold in enumerate(thresholds[:, 0]):
            keys, pair_count = np.unique(pair_key[pair_similarity >= threshold],
                                         return_counts=True)
            if keys.size == 0:
                continue
            truth_n = truth_count[keys // n_tracks]
            track_n = track_count[keys % n_tracks]
            # pair_count <= both id counts, so these denominators are >= 1.
            association_sum[a] = np.sum(pair_count * pair_count / (truth_n + track_n - pair_count))
            association_recall_sum[a] = np.sum(pair_count * pair_count / truth_n)
            association_precision_sum[a] = np.sum(pair_count * pair_count / track_n)

    return HOTAResult(true_positives=true_positives, false_negatives=false_negatives,
                      false_positives=false_positives, association_sum=association_sum,
                      association_recall_sum=association_recall_sum,
                      association_precision_sum=association_precision_sum,
                      localisation_sum=localisation_sum)


def hota_from_frames(frames: Iterable[EvaluationFrame], *,
                     full_similarity_distance: float = _DEFAULT_FULL_SIMILARITY_DISTANCE,
                     zero_similarity_distance: float = _DEFAULT_ZERO_SIMILARITY_DISTANCE,
                     ) -> HOTAResult:
    """HOTA of one sequence with the Euclidean position similarity."""
    frames = _frame_list(frames, "frames")
    similarities = [position_similarity(frame.truth_positions, frame.track_positions,
                                        full_similarity_distance=full_similarity_distance,
                                        zero_similarity_distance=zero_similarity_distance)
                    for frame in frames]
    return hota_from_similarity([frame.truth_ids for frame in frames],
                                [frame.track_ids for frame in frames], similarities)


def combine_hota(results: Iterable[HOTAResult]) -> HOTAResult:
    """Combine sequences as TrackEval's ``combine_sequences`` does.

    Counts and TP-weighted sums add up, so a sequence weighs in by its number
    of detections, not equally.
    """
    results = list(results)
    if not results:
        raise ValueError("results must contain at least one HOTAResult")
    for index, result in enumerate(results):
        if not isinstance(result, HOTAResult):
            raise TypeError(f"results[{index}] must be a HOTAResult, got {type(result).__name__}")
    return HOTAResult(**{field: sum(getattr(result, field) for result in results)
                         for field in _HOTA_SUM_FIELDS})


# ---------------------------------------------------------------------------
# GOSPA
# ---------------------------------------------------------------------------

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


def _gospa_assignment(truth_positions: np.ndarray, track_positions: np.ndarray, c: float,
                      p: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """GOSPA's optimal assignment at one time: the assigned pairs' truth rows, track rows
    and distances, only pairs closer than ``c`` (the track-management metrics match truths
    to tracks with exactly these pairs)."""
    if truth_positions.shape[0] == 0 or track_positions.shape[0] == 0:
        empty = np.zeros(0, dtype=np.intp)
        return empty, empty, np.zeros(0)
    distance = _distances(truth_positions, track_positions)
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
    _, _, pair_distance = _gospa_assignment(truth_positions, track_positions, c, p)
    n_assigned = pair_distance.size
    localisation = float(np.sum(pair_distance ** p))
    return (localisation, truth_positions.shape[0] - n_assigned,
            track_positions.shape[0] - n_assigned)


def gospa_from_frames(frames: Iterable[EvaluationFrame], *, c: float = _DEFAULT_GOSPA_C,
                      p: float = _DEFAULT_GOSPA_P) -> GOSPAResult:
    """GOSPA (alpha = 2) of the positions at each frame."""
    frames = _frame_list(frames, "frames")
    c, p = _check_gospa_parameters(c, p)
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


# ---------------------------------------------------------------------------
# Stone Soup adapter
# ---------------------------------------------------------------------------

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


def hota(truths: Iterable, tracks: Iterable, timestamps: Iterable[datetime.datetime], *,
         position_mapping: Sequence[int] = (0, 2),
         full_similarity_distance: float = _DEFAULT_FULL_SIMILARITY_DISTANCE,
         zero_similarity_distance: float = _DEFAULT_ZERO_SIMILARITY_DISTANCE) -> HOTAResult:
    """HOTA of Stone Soup truths and tracks at the given evaluation timestamps."""
    return hota_from_frames(
        frames_from_stonesoup(truths, tracks, timestamps, position_mapping=position_mapping),
        full_similarity_distance=full_similarity_distance,
        zero_similarity_distance=zero_similarity_distance)


def gospa(truths: Iterable, tracks: Iterable, timestamps: Iterable[datetime.datetime], *,
          position_mapping: Sequence[int] = (0, 2), c: float = _DEFAULT_GOSPA_C,
          p: float = _DEFAULT_GOSPA_P) -> GOSPAResult:
    """GOSPA (alpha = 2) of Stone Soup truths and tracks at the given timestamps."""
    return gospa_from_frames(
        frames_from_stonesoup(truths, tracks, timestamps, position_mapping=position_mapping),
        c=c, p=p)
