"""Tests of the HOTA and GOSPA evaluation metrics.

Hand-computed cases pin the maths; random scenarios hold HOTA against the
reference implementation in TrackEval and GOSPA against Stone Soup's
GOSPAMetric.
"""
import datetime
import math

import numpy as np
import pytest
from scipy.spatial.distance import cdist
from stonesoup.measures import Euclidean
from stonesoup.metricgenerator.ospametric import GOSPAMetric
from stonesoup.types.groundtruth import GroundTruthPath, GroundTruthState
from stonesoup.types.state import State
from stonesoup.types.track import Track

# TrackEval 1.3.0 imports cleanly on numpy 2 (its HOTA code uses no removed
# numpy aliases), so no shim is needed.
import trackeval

from ctxmodels.experiment.metrics import (
    HOTA_ALPHAS,
    EvaluationFrame,
    GOSPAResult,
    HOTAResult,
    combine_gospa,
    combine_hota,
    frames_from_stonesoup,
    gospa,
    gospa_from_frames,
    hota,
    hota_from_frames,
    hota_from_similarity,
    position_similarity,
)

C = 30.0
P = 2.0
START = datetime.datetime(2024, 1, 1)
TOLERANCE = 1e-9


def frame(truths: dict, tracks: dict) -> EvaluationFrame:
    """Frame from {id: (x, y)} dicts."""
    return EvaluationFrame(
        truth_ids=np.array(list(truths), dtype=int),
        truth_positions=np.array(list(truths.values()), dtype=float).reshape(-1, 2),
        track_ids=np.array(list(tracks), dtype=int),
        track_positions=np.array(list(tracks.values()), dtype=float).reshape(-1, 2))


# ---------------------------------------------------------------------------
# Hand-computed HOTA
# ---------------------------------------------------------------------------

def test_similarity_is_one_within_5m_and_falls_linearly_to_zero_at_30m():
    truth = np.array([[0.0, 0.0]])
    tracks = np.array([[3.0, 4.0], [10.0, 0.0], [0.0, 17.5], [30.0, 0.0], [0.0, -45.0]])
    similarity = position_similarity(truth, tracks)
    assert similarity.shape == (1, 5)
    np.testing.assert_allclose(similarity[0], [1.0, 0.8, 0.5, 0.0, 0.0], atol=1e-15)


def test_hota_alphas_are_the_19_trackeval_thresholds():
    np.testing.assert_array_equal(HOTA_ALPHAS, trackeval.metrics.HOTA().array_labels)
    assert HOTA_ALPHAS.size == 19


def test_perfect_tracking_scores_one():
    frames = [frame({1: (0, 0), 2: (100, 0)}, {7: (0, 0), 9: (100, 0)}),
              frame({1: (1, 0), 2: (100, 1)}, {7: (1, 0), 9: (100, 1)}),
              frame({2: (100, 2)}, {9: (101, 2)})]
    result = hota_from_frames(frames)
    assert result.hota == pytest.approx(1.0, abs=1e-15)
    assert result.deta == pytest.approx(1.0, abs=1e-15)
    assert result.assa == pytest.approx(1.0, abs=1e-15)
    assert result.loca == pytest.approx(1.0, abs=1e-15)
    np.testing.assert_array_equal(result.true_positives, np.full(19, 5))
    np.testing.assert_array_equal(result.false_positives, np.zeros(19))
    np.testing.assert_array_equal(result.false_negatives, np.zeros(19))


def test_track_at_10m_has_similarity_08_and_matches_up_to_alpha_08():
    result = hota_from_frames([frame({0: (0, 0)}, {0: (0, 10)})])
    matched = np.arange(19) < 16  # alpha = 0.05 .. 0.80 inclusive
    np.testing.assert_array_equal(result.true_positives, matched.astype(int))
    np.testing.assert_array_equal(result.false_negatives, (~matched).astype(int))
    np.testing.assert_array_equal(result.false_positives, (~matched).astype(int))
    assert result.hota == pytest.approx(16 / 19, abs=1e-15)
    # LocA is 0.8 where matched and 1 (TrackEval's convention) where not.
    np.testing.assert_allclose(result.loca_per_alpha, np.where(matched, 0.8, 1.0), atol=1e-15)


def test_similarity_equal_to_a_threshold_counts_as_a_match():
    # At 15 m the similarity is 0.6, which TrackEval's threshold 0.6000000000000001
    # exceeds by one ulp; like TrackEval, the pair still matches at alpha = 0.6.
    frames = [frame({0: (0, 0)}, {0: (15, 0)})]
    result = hota_from_frames(frames)
    matched = np.arange(19) < 12  # alpha = 0.05 .. 0.60 inclusive
    np.testing.assert_array_equal(result.true_positives, matched.astype(int))
    assert result.hota == pytest.approx(12 / 19, abs=1e-15)
    reference = trackeval.metrics.HOTA().eval_sequence(trackeval_data(frames))
    assert_matches_trackeval(result, reference)


def test_id_switch_halves_assa_in_two_frames():
    # The track that follows truth 0 changes id from 5 to 6 between frames.
    switched = hota_from_frames([frame({0: (0, 0)}, {5: (0, 0)}),
                                 frame({0: (10, 0)}, {6: (10, 0)})])
    kept = hota_from_frames([frame({0: (0, 0)}, {5: (0, 0)}),
                             frame({0: (10, 0)}, {5: (10, 0)})])
    assert kept.assa == pytest.approx(1.0, abs=1e-15)
    assert switched.assa == pytest.approx(0.5, abs=1e-15)
    assert switched.deta == pytest.approx(1.0, abs=1e-15)
    assert switched.hota == pytest.approx(math.sqrt(0.5), abs=1e-15)


def test_missed_target_and_false_track_lower_deta():
    # Frame: truths 0 and 1, one correct track and one false track far away.
    result = hota_from_frames([frame({0: (0, 0), 1: (500, 0)}, {3: (0, 0), 4: (-500, 0)})])
    # TP = 1, FN = 1, FP = 1 at every alpha.
    assert result.deta == pytest.approx(1 / 3, abs=1e-15)
    assert result.detre == pytest.approx(1 / 2, abs=1e-15)
    assert result.detpr == pytest.approx(1 / 2, abs=1e-15)
    assert result.assa == pytest.approx(1.0, abs=1e-15)
    assert result.hota == pytest.approx(math.sqrt(1 / 3), abs=1e-15)


def test_no_tracks_and_no_truths_score_zero_without_nan():
    no_tracks = hota_from_frames([frame({0: (0, 0)}, {}), frame({0: (1, 0)}, {})])
    no_truths = hota_from_frames([frame({}, {2: (0, 0)})])
    nothing = hota_from_frames([frame({}, {})])
    for result in (no_tracks, no_truths, nothing):
        values = np.array(list(result.summary().values()))
        assert not np.any(np.isnan(values))
        assert result.hota == 0.0
    np.testing.assert_array_equal(no_tracks.false_negatives, np.full(19, 2))
    np.testing.assert_array_equal(no_truths.false_positives, np.full(19, 1))


def test_hota_ignores_id_values_and_frame_order():
    frames = [frame({1: (0, 0), 2: (40, 0)}, {7: (3, 0), 8: (40, 12)}),
              frame({1: (1, 0), 2: (41, 0)}, {8: (1, 4), 9: (44, 1)}),
              frame({2: (42, 0)}, {7: (42, 6)})]
    relabelled = [EvaluationFrame(f.truth_ids * 13 + 1000, f.truth_positions,
                                  f.track_ids * -3, f.track_positions) for f in frames]
    base = hota_from_frames(frames)
    for other in (hota_from_frames(relabelled), hota_from_frames(frames[::-1])):
        for field in ("true_positives", "false_negatives", "false_positives",
                      "association_sum", "localisation_sum"):
            np.testing.assert_allclose(getattr(other, field), getattr(base, field),
                                       rtol=0, atol=1e-12)


# ---------------------------------------------------------------------------
# Hand-computed GOSPA
# ---------------------------------------------------------------------------

@pytest.mark.parametrize(("truths", "tracks", "expected"), [
    ({0: (0, 0), 1: (50, 50)}, {4: (0, 0), 5: (50, 50)}, 0.0),
    ({0: (0, 0)}, {}, math.sqrt(C ** 2 / 2)),  # one missed target
    ({}, {0: (0, 0)}, math.sqrt(C ** 2 / 2)),  # one false track
    ({0: (0, 0)}, {0: (10, 0)}, 10.0),
    ({0: (0, 0)}, {0: (40, 0)}, C),  # beyond c: a miss plus a false track
    ({0: (0, 0), 1: (100, 0)}, {0: (3, 4)}, math.sqrt(25 + C ** 2 / 2)),
    ({}, {}, 0.0),
])
def test_gospa_hand_computed(truths, tracks, expected):
    result = gospa_from_frames([frame(truths, tracks)], c=C, p=P)
    assert result.distance[0] == pytest.approx(expected, abs=1e-12)
    terms = result.localisation + result.missed + result.false
    assert result.distance[0] ** P == pytest.approx(terms[0], abs=1e-9)


def test_gospa_decomposition_counts_missed_and_false():
    result = gospa_from_frames([frame({0: (0, 0), 1: (100, 0), 2: (200, 0)},
                                      {0: (3, 4), 1: (-300, 0)})])
    assert result.localisation[0] == pytest.approx(25.0)
    assert result.num_missed[0] == 2 and result.num_false[0] == 1
    assert result.missed[0] == pytest.approx(2 * C ** 2 / 2)
    assert result.false[0] == pytest.approx(C ** 2 / 2)


def test_gospa_rms_over_time_and_pooled_combination():
    first = gospa_from_frames([frame({0: (0, 0)}, {0: (0, 0)}), frame({0: (0, 0)}, {})])
    second = gospa_from_frames([frame({0: (0, 0)}, {0: (10, 0)})])
    assert first.rms == pytest.approx(math.sqrt((0 + C ** 2 / 2) / 2))
    assert first.mean == pytest.approx(math.sqrt(C ** 2 / 2) / 2)
    combined = combine_gospa([first, second])
    assert combined.distance.size == 3
    assert combined.rms == pytest.approx(math.sqrt((0 + C ** 2 / 2 + 100) / 3))


def test_gospa_swapping_truths_and_tracks_swaps_missed_and_false():
    rng = np.random.default_rng(3)
    for _ in range(20):
        truths = {i: tuple(rng.uniform(-50, 50, 2)) for i in range(rng.integers(0, 6))}
        tracks = {i: tuple(rng.uniform(-50, 50, 2)) for i in range(rng.integers(0, 6))}
        forward = gospa_from_frames([frame(truths, tracks)])
        backward = gospa_from_frames([frame(tracks, truths)])
        assert forward.distance[0] == pytest.approx(backward.distance[0], abs=1e-12)
        assert forward.num_missed[0] == backward.num_false[0]
        assert forward.num_false[0] == backward.num_missed[0]


# ---------------------------------------------------------------------------
# Random scenarios
# ---------------------------------------------------------------------------

def random_scenario(seed: int) -> list[EvaluationFrame]:
    """Truths with noisy tracks, fragmentation, identity swaps, misses, false tracks.

    Ids are deliberately non-contiguous. Every third seed is crowded (targets
    within a few tens of metres), where several tracks compete for a truth and
    the global alignment score decides the matching.
    """
    rng = np.random.default_rng(seed)
    n_frames = int(rng.integers(8, 40))
    n_truths = int(rng.integers(1, 7))
    truth_ids = rng.choice(10_000, size=n_truths, replace=False)
    births = rng.integers(0, n_frames, size=n_truths)
    deaths = np.minimum(births + rng.integers(1, n_frames + 1, size=n_truths), n_frames)
    spread = 25.0 if seed % 3 == 0 else 150.0
    starts = rng.uniform(-spread, spread, size=(n_truths, 2))
    velocities = rng.normal(0, 4, size=(n_truths, 2))
    noise = rng.choice([0.5, 3.0, 8.0, 15.0, 30.0], size=n_truths)

    next_track_id = 20_000
    label = {}  # truth index -> current track id
    false_tracks = []  # (birth, death, start, velocity, id)
    for _ in range(int(rng.integers(0, 7))):
        birth = int(rng.integers(0, n_frames))
        anchor = starts[rng.integers(n_truths)]
        false_tracks.append((birth, int(min(n_frames, birth + rng.integers(1, 10))),
                             anchor + rng.normal(0, 25, 2), rng.normal(0, 4, 2),
                             next_track_id))
        next_track_id += 7

    frames = []
    for t in range(n_frames):
        alive = [i for i in range(n_truths) if births[i] <= t < deaths[i]]
        truth_positions = {truth_ids[i]: starts[i] + velocities[i] * (t - births[i])
                           for i in alive}
        for i in alive:
            if i not in label or rng.random() < 0.08:  # new track / fragmentation
                label[i] = next_track_id
                next_track_id += 3
        if len(alive) >= 2 and rng.random() < 0.1:  # identity swap
            a, b = rng.choice(alive, size=2, replace=False)
            label[a], label[b] = label[b], label[a]
        track_positions = {}
        for i in alive:
            if rng.random() < 0.15:  # missed target at this time
                continue
            track_positions[label[i]] = truth_positions[truth_ids[i]] + rng.normal(0, noise[i], 2)
        for birth, death, start, velocity, track_id in false_tracks:
            if birth <= t < death:
                track_positions[track_id] = start + velocity * (t - birth)
        frames.append(frame(truth_positions, track_positions))
    return frames


def trackeval_data(frames: list[EvaluationFrame]) -> dict:
    """The data dict TrackEval's HOTA.eval_sequence expects (contiguous ids)."""
    all_truth = np.unique(np.concatenate([f.truth_ids for f in frames]))
    all_track = np.unique(np.concatenate([f.track_ids for f in frames]))
    similarity = []
    for f in frames:
        if f.truth_ids.size and f.track_ids.size:
            distance = cdist(f.truth_positions, f.track_positions)
            similarity.append(np.clip((30.0 - distance) / 25.0, 0.0, 1.0))
        else:
            similarity.append(np.zeros((f.truth_ids.size, f.track_ids.size)))
    return {
        "gt_ids": [np.searchsorted(all_truth, f.truth_ids) for f in frames],
        "tracker_ids": [np.searchsorted(all_track, f.track_ids) for f in frames],
        "similarity_scores": similarity,
        "num_gt_dets": sum(f.truth_ids.size for f in frames),
        "num_tracker_dets": sum(f.track_ids.size for f in frames),
        "num_gt_ids": all_truth.size,
        "num_tracker_ids": all_track.size,
        "num_timesteps": len(frames),
    }


FIELD_PAIRS = [("HOTA", "hota_per_alpha"), ("DetA", "deta_per_alpha"),
               ("AssA", "assa_per_alpha"), ("LocA", "loca_per_alpha"),
               ("DetRe", "detre_per_alpha"), ("DetPr", "detpr_per_alpha"),
               ("AssRe", "assre_per_alpha"), ("AssPr", "asspr_per_alpha"),
               ("HOTA_TP", "true_positives"), ("HOTA_FN", "false_negatives"),
               ("HOTA_FP", "false_positives")]


def assert_matches_trackeval(ours: HOTAResult, reference: dict):
    for reference_field, our_field in FIELD_PAIRS:
        np.testing.assert_allclose(getattr(ours, our_field), reference[reference_field],
                                   rtol=0, atol=TOLERANCE, err_msg=reference_field)


SEEDS = list(range(40))


@pytest.mark.parametrize("seed", SEEDS)
def test_hota_matches_trackeval_on_random_scenarios(seed):
    frames = random_scenario(seed)
    reference = trackeval.metrics.HOTA().eval_sequence(trackeval_data(frames))
    ours = hota_from_frames(frames)
    assert_matches_trackeval(ours, reference)
    assert ours.hota == pytest.approx(float(np.mean(reference["HOTA"])), abs=TOLERANCE)


def test_random_scenarios_exercise_the_interesting_cases():
    # Guards the comparison above against a generator that went degenerate.
    results = [hota_from_frames(random_scenario(seed)) for seed in SEEDS]
    assert any(r.assa < 0.9 for r in results)  # association errors occur
    assert any(r.false_positives[0] > 0 for r in results)
    assert any(r.false_negatives[0] > 0 for r in results)
    assert any(0 < r.true_positives[-1] < r.true_positives[0] for r in results)
    assert len({round(r.hota, 6) for r in results}) > 30


def test_combined_hota_matches_trackeval_combine_sequences():
    metric = trackeval.metrics.HOTA()
    per_sequence = {f"seq{seed}": metric.eval_sequence(trackeval_data(random_scenario(seed)))
                    for seed in SEEDS[:12]}
    reference = metric.combine_sequences(per_sequence)
    ours = combine_hota(hota_from_frames(random_scenario(seed)) for seed in SEEDS[:12])
    assert_matches_trackeval(ours, reference)
    # Aggregation is not the mean of per-sequence scores.
    mean_of_scores = np.mean([np.mean(r["HOTA"]) for r in per_sequence.values()])
    assert abs(ours.hota - mean_of_scores) > 1e-6


def test_hota_from_similarity_matches_trackeval_with_its_own_data():
    data = trackeval_data(random_scenario(101))
    reference = trackeval.metrics.HOTA().eval_sequence(data)
    ours = hota_from_similarity(data["gt_ids"], data["tracker_ids"], data["similarity_scores"])
    assert_matches_trackeval(ours, reference)


# ---------------------------------------------------------------------------
# Stone Soup adapter and GOSPA against Stone Soup
# ---------------------------------------------------------------------------

def stonesoup_objects(frames: list[EvaluationFrame], times: list[datetime.datetime]):
    """GroundTruthPaths and Tracks with 4-D states [x, vx, y, vy] from frames."""
    truths, tracks = {}, {}
    for f, time in zip(frames, times):
        for ids, positions, paths, kind in ((f.truth_ids, f.truth_positions, truths, "truth"),
                                            (f.track_ids, f.track_positions, tracks, "track")):
            for object_id, (x, y) in zip(ids, positions):
                vector = np.array([[x], [1.0], [y], [-1.0]])
                if kind == "truth":
                    paths.setdefault(object_id, GroundTruthPath()).append(
                        GroundTruthState(vector, timestamp=time))
                else:
                    paths.setdefault(object_id, Track()).append(State(vector, timestamp=time))
    return set(truths.values()), set(tracks.values())


def times_for(frames):
    return [START + datetime.timedelta(seconds=2 * k) for k in range(len(frames))]


@pytest.mark.parametrize("seed", SEEDS[:10])
def test_stonesoup_adapter_gives_the_same_hota_as_frames(seed):
    frames = random_scenario(seed)
    times = times_for(frames)
    truths, tracks = stonesoup_objects(frames, times)
    reference = trackeval.metrics.HOTA().eval_sequence(trackeval_data(frames))
    assert_matches_trackeval(hota(truths, tracks, times), reference)


def test_adapter_ignores_track_states_between_evaluation_times():
    frames = random_scenario(5)
    times = times_for(frames)
    truths, tracks = stonesoup_objects(frames, times)
    before = hota(truths, tracks, times)
    gospa_before = gospa(truths, tracks, times)
    # An extra (wildly wrong) track state one second after each evaluation
    # time, like a lidar update between radar scans.
    for track in tracks:
        for state in list(track.states):
            vector = np.array(state.state_vector) + 1000.0
            track.append(State(vector, timestamp=state.timestamp + datetime.timedelta(seconds=1)))
    for truth in truths:  # the truth is sampled at the intermediate times too
        for state in list(truth.states):
            later = state.timestamp + datetime.timedelta(seconds=1)
            truth.append(GroundTruthState(state.state_vector, timestamp=later))
    after = hota(truths, tracks, times)
    np.testing.assert_array_equal(after.true_positives, before.true_positives)
    assert after.hota == pytest.approx(before.hota, abs=1e-15)
    np.testing.assert_array_equal(gospa(truths, tracks, times).distance, gospa_before.distance)
    # Evaluating at the intermediate times too does see them.
    all_times = sorted(times + [t + datetime.timedelta(seconds=1) for t in times])
    with_intermediate = hota(truths, tracks, all_times)
    assert with_intermediate.false_positives[0] > before.false_positives[0]


def test_adapter_uses_position_mapping():
    truth = GroundTruthPath([GroundTruthState([[0.0], [9.0], [0.0], [9.0]], timestamp=START)])
    track = Track([State([[0.0], [0.0], [10.0], [0.0]], timestamp=START)])
    assert gospa([truth], [track], [START]).distance[0] == pytest.approx(10.0)
    # Mapping onto the velocities instead: (9, 9) vs (0, 0).
    assert gospa([truth], [track], [START], position_mapping=(1, 3)).distance[0] \
        == pytest.approx(math.hypot(9, 9))
    frames = frames_from_stonesoup([truth], [track], [START], position_mapping=[0, 1, 2])
    assert frames[0].truth_positions.shape == (1, 3)


def test_adapter_uses_the_last_state_at_a_repeated_timestamp():
    truth = GroundTruthPath([GroundTruthState([[0.0], [0.0], [0.0], [0.0]], timestamp=START)])
    track = Track([State([[50.0], [0.0], [0.0], [0.0]], timestamp=START),
                   State([[3.0], [0.0], [4.0], [0.0]], timestamp=START)])
    assert gospa([truth], [track], [START]).distance[0] == pytest.approx(5.0)


@pytest.mark.parametrize("seed", range(200))
def test_gospa_matches_stonesoup_per_time(seed):
    rng = np.random.default_rng(seed)
    n_truths, n_tracks = rng.integers(0, 9, size=2)
    if n_truths + n_tracks == 0:
        n_truths = 1  # Stone Soup cannot take a time at which nothing exists
    truth_xy = rng.uniform(-40, 40, size=(n_truths, 2))
    track_xy = rng.uniform(-40, 40, size=(n_tracks, 2))

    def states(xy):
        return [State([[x], [rng.normal()], [y], [rng.normal()]], timestamp=START)
                for x, y in xy]

    metric = GOSPAMetric(c=C, p=P, measure=Euclidean(mapping=(0, 2)))
    reference, _ = metric.compute_gospa_metric(states(track_xy), states(truth_xy))
    ours = gospa_from_frames([EvaluationFrame(np.arange(n_truths), truth_xy,
                                              np.arange(n_tracks), track_xy)], c=C, p=P)
    for field in ("distance", "localisation", "missed", "false"):
        assert getattr(ours, field)[0] == pytest.approx(reference.value[field], abs=TOLERANCE,
                                                        rel=0), field


@pytest.mark.parametrize("seed", SEEDS[:10])
def test_gospa_over_time_matches_stonesoup(seed):
    frames = random_scenario(seed)
    times = times_for(frames)
    truths, tracks = stonesoup_objects(frames, times)
    metric = GOSPAMetric(c=C, p=P, measure=Euclidean(mapping=(0, 2)))
    reference = metric.compute_over_time(*metric.extract_states(tracks, True),
                                         *metric.extract_states(truths, True))
    reference_by_time = {m.timestamp: m.value["distance"] for m in reference.value}
    ours = gospa(truths, tracks, times)
    assert len(reference_by_time) > 0
    for time, distance in zip(times, ours.distance):
        # Stone Soup skips times at which nothing exists; GOSPA is 0 there.
        assert distance == pytest.approx(reference_by_time.get(time, 0.0), abs=TOLERANCE, rel=0)
    assert ours.rms == pytest.approx(
        math.sqrt(sum(d ** 2 for d in reference_by_time.values()) / len(times)), abs=TOLERANCE)


# ---------------------------------------------------------------------------
# Bad input
# ---------------------------------------------------------------------------

def test_frame_rejects_bad_input_naming_the_argument():
    with pytest.raises(ValueError, match="truth_positions"):
        EvaluationFrame([1, 2], [[0, 0]], [], [])
    with pytest.raises(ValueError, match="track_ids"):
        EvaluationFrame([], [], [3, 3], [[0, 0], [1, 1]])
    with pytest.raises(TypeError, match="truth_ids"):
        EvaluationFrame([1.5], [[0, 0]], [], [])
    with pytest.raises(ValueError, match="track_positions"):
        EvaluationFrame([], [], [1], [[0, np.nan]])
    with pytest.raises(ValueError, match="dimension"):
        EvaluationFrame([1], [[0, 0]], [1], [[0, 0, 0]])


def test_metrics_reject_bad_arguments():
    good = [frame({0: (0, 0)}, {0: (0, 0)})]
    with pytest.raises(ValueError, match="frames"):
        hota_from_frames([])
    with pytest.raises(TypeError, match="frames"):
        gospa_from_frames(good[0])
    with pytest.raises(ValueError, match="zero_similarity_distance"):
        hota_from_frames(good, full_similarity_distance=30, zero_similarity_distance=5)
    with pytest.raises(ValueError, match="c must"):
        gospa_from_frames(good, c=0)
    with pytest.raises(ValueError, match="p must"):
        gospa_from_frames(good, p=0.5)
    with pytest.raises(ValueError, match="similarity_per_frame"):
        hota_from_similarity([[0]], [[0]], [[[1.5]]])
    with pytest.raises(ValueError, match="similarity_per_frame"):
        hota_from_similarity([[0]], [[0, 1]], [[[0.5]]])
    with pytest.raises(ValueError, match="results"):
        combine_hota([])
    first = gospa_from_frames(good, c=30)
    with pytest.raises(ValueError, match="same c and p"):
        combine_gospa([first, gospa_from_frames(good, c=20)])
    assert isinstance(first, GOSPAResult)


def test_adapter_rejects_bad_arguments():
    truth = GroundTruthPath([GroundTruthState([[0.0], [0.0], [0.0], [0.0]], timestamp=START),
                             GroundTruthState([[0.0], [0.0], [0.0], [0.0]],
                                              timestamp=START + datetime.timedelta(seconds=2))])
    track = Track([State([[0.0], [0.0], [0.0], [0.0]], timestamp=START)])
    with pytest.raises(TypeError, match="truths"):
        hota(truth, [track], [START])
    with pytest.raises(TypeError, match="tracks"):
        hota([truth], [track.states[0]], [START])
    with pytest.raises(ValueError, match="timestamps"):
        gospa([truth], [track], [START, START])
    with pytest.raises(ValueError, match="timestamps"):
        gospa([truth], [track], [])
    with pytest.raises(TypeError, match="timestamps"):
        gospa([truth], [track], [0.0])
    with pytest.raises(ValueError, match="position_mapping"):
        gospa([truth], [track], [START], position_mapping=(0, 7))
    with pytest.raises(ValueError, match="position_mapping"):
        gospa([truth], [track], [START], position_mapping=(0.0, 2.0))
    # The truth spans START+1s but has no state there: sampled on another grid.
    with pytest.raises(ValueError, match=r"truths\[0\].*no state"):
        gospa([truth], [track], [START + datetime.timedelta(seconds=1)])
