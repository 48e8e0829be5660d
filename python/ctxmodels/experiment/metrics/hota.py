r"""HOTA, the Higher Order Tracking Accuracy, on positions.

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
"""
from __future__ import annotations

import datetime
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from .frames import (EvaluationFrame, frame_list, frames_from_stonesoup, id_array,
                     pairwise_distances)


#: The 19 HOTA thresholds, the same floating-point values TrackEval uses.
HOTA_ALPHAS: np.ndarray = np.arange(0.05, 0.99, 0.05)
HOTA_ALPHAS.setflags(write=False)

# A similarity that equals a threshold in exact arithmetic may land one ulp
# below it; TrackEval counts such pairs as matched, so do we.
_EPS = np.finfo(float).eps

FULL_SIMILARITY_DISTANCE = 5.0
ZERO_SIMILARITY_DISTANCE = 30.0


def _check_similarity_distances(full_similarity_distance, zero_similarity_distance):
    full = float(full_similarity_distance)
    zero = float(zero_similarity_distance)
    if not (np.isfinite(full) and np.isfinite(zero) and 0 <= full < zero):
        raise ValueError(
            "need 0 <= full_similarity_distance < zero_similarity_distance (both finite), got "
            f"full_similarity_distance={full_similarity_distance!r}, "
            f"zero_similarity_distance={zero_similarity_distance!r}")
    return full, zero


def position_similarity(truth_positions, track_positions, *,
                        full_similarity_distance: float = FULL_SIMILARITY_DISTANCE,
                        zero_similarity_distance: float = ZERO_SIMILARITY_DISTANCE,
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
    distance = pairwise_distances(truth_positions, track_positions)
    return np.clip((zero - distance) / (zero - full), 0.0, 1.0)


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
    #: sum over TP of c_gk / (n_g + n_k - c_gk), i.e. AssA times the number of TP
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
    truth_ids = [id_array(ids, f"truth_ids_per_frame[{t}]")
                 for t, ids in enumerate(truth_ids_per_frame)]
    track_ids = [id_array(ids, f"track_ids_per_frame[{t}]")
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
                     full_similarity_distance: float = FULL_SIMILARITY_DISTANCE,
                     zero_similarity_distance: float = ZERO_SIMILARITY_DISTANCE,
                     ) -> HOTAResult:
    """HOTA of one sequence with the Euclidean position similarity."""
    frames = frame_list(frames, "frames")
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


def hota(truths: Iterable, tracks: Iterable, timestamps: Iterable[datetime.datetime], *,
         position_mapping: Sequence[int] = (0, 2),
         full_similarity_distance: float = FULL_SIMILARITY_DISTANCE,
         zero_similarity_distance: float = ZERO_SIMILARITY_DISTANCE) -> HOTAResult:
    """HOTA of Stone Soup truths and tracks at the given evaluation timestamps."""
    return hota_from_frames(
        frames_from_stonesoup(truths, tracks, timestamps, position_mapping=position_mapping),
        full_similarity_distance=full_similarity_distance,
        zero_similarity_distance=zero_similarity_distance)
