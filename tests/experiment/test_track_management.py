"""Track-management metrics: hand-built runs with known answers, a brute-force reference
over random small runs, pooling, GOSPA's split and bad input."""
import itertools
import math

import numpy as np
import pytest

from ctxmodels.experiment import metrics
from ctxmodels.experiment.track_management import TrackManagement, combine, track_management

FAR = 1000.0  # metres from any truth: never matched


def frame(truths=(), tracks=()):
    """A frame from ``{id: (x, y)}`` dicts of truths and tracks."""
    truths, tracks = dict(truths), dict(tracks)
    return metrics.EvaluationFrame(
        np.array(list(truths), dtype=np.int64), np.array(list(truths.values()), dtype=float),
        np.array(list(tracks), dtype=np.int64), np.array(list(tracks.values()), dtype=float))


def test_an_identity_switch_counts_once():
    frames = [frame({0: (0, 0)}, {10: (1, 0)}), frame({0: (0, 0)}, {10: (1, 0)}),
              frame({0: (0, 0)}, {11: (1, 0)}), frame({0: (0, 0)}, {11: (1, 0)})]
    result = track_management(frames, [0, 1, 2, 3])
    assert (result.id_switches, result.fragmentations) == (1, 0)
    assert (result.tracked_fraction, result.time_to_track, result.never_tracked) == (1.0, 0.0, 0)
    assert (result.false_tracks, result.false_tracks_per_scan) == (0, 0.0)
    assert (result.truths, result.tracks, result.frames) == (1, 2, 4)


def test_each_resumed_interruption_is_a_fragmentation():
    on = {10: (2, 0)}
    # matched, matched, missed, matched, missed, matched, missed (never resumed)
    tracks = [on, on, {}, on, {10: (FAR, 0)}, on, {}]
    frames = [frame({0: (0, 0)}, t) for t in tracks]
    result = track_management(frames, range(7))
    assert (result.fragmentations, result.id_switches) == (2, 0)
    assert result.matched_truth_frames == 4 and result.truth_frames == 7
    assert result.tracked_fraction == pytest.approx(4 / 7)
    assert result.unmatched_track_frames == 1  # the far position of track 10
    assert result.false_tracks == 0  # matched elsewhere: not a false track


def test_a_switch_across_a_gap_is_a_switch_and_a_fragmentation():
    frames = [frame({0: (0, 0)}, {10: (0, 0)}), frame({0: (0, 0)}),
              frame({0: (0, 0)}, {11: (0, 0)})]
    result = track_management(frames, [0, 1, 2])
    assert (result.id_switches, result.fragmentations) == (1, 1)


def test_a_truth_absent_in_between_is_not_interrupted():
    frames = [frame({0: (0, 0)}, {10: (0, 0)}), frame({}, {10: (50, 50)}),
              frame({0: (0, 0)}, {10: (0, 0)})]
    result = track_management(frames, [0, 1, 2])
    assert (result.fragmentations, result.truth_frames, result.tracked_fraction) == (0, 2, 1.0)


def test_false_track_lifetime_is_last_minus_first_presence():
    times = [0.0, 1.0, 2.5, 4.0, 7.0]
    truth = {0: (0, 0)}
    # track 20: false, present at t=0, 2.5 and 7 (absent in between): lives 7 s;
    # track 21: false, one frame: lives 0 s; track 10: on the truth, never false.
    tracks = [{10: (0, 0), 20: (FAR, 0)}, {10: (0, 0)}, {10: (0, 0), 20: (FAR, 0), 21: (0, FAR)},
              {10: (0, 0)}, {20: (FAR, 0)}]
    result = track_management([frame(truth, t) for t in tracks], times)
    assert result.false_tracks == 2
    assert result.false_track_seconds == 7.0
    assert result.false_track_lifetime == 3.5
    assert result.false_tracks_per_scan == pytest.approx(4 / 5)  # track 20 three times, 21 once


def test_time_to_track_and_never_tracked():
    times = [0.0, 2.0, 5.0, 9.0]
    # truth 0 present throughout, matched from t=5: 5 s; truth 1 from t=2, never: 7 s.
    frames = [frame({0: (0, 0)}), frame({0: (0, 0), 1: (500, 0)}),
              frame({0: (0, 0), 1: (500, 0)}, {10: (3, 4)}),
              frame({0: (0, 0), 1: (500, 0)}, {10: (3, 4)})]
    result = track_management(frames, times)
    assert (result.never_tracked, result.truths) == (1, 2)
    assert result.time_to_track_seconds == 12.0 and result.time_to_track == 6.0


def test_matching_needs_a_distance_below_c():
    frames = [frame({0: (0, 0)}, {10: (30, 0)})]
    assert track_management(frames, [0], c=30.0).matched_truth_frames == 0
    assert track_management(frames, [0], c=30.5).matched_truth_frames == 1


def test_empty_frames_give_neutral_values_not_nan():
    result = track_management([frame(), frame()], [0, 1])
    assert (result.false_tracks_per_scan, result.false_track_lifetime, result.tracked_fraction,
            result.time_to_track) == (0.0, 0.0, 1.0, 0.0)
    assert all(not (isinstance(v, float) and math.isnan(v)) for v in result.as_dict().values())


# ---------------------------------------------------------------------------
# Brute-force reference
# ---------------------------------------------------------------------------

def _partial_assignments(n_truths, n_tracks):
    """Every injective map from truths to (track or None), as tuples."""
    choices = list(range(n_tracks)) + [None] * n_truths
    return set(itertools.permutations(choices, n_truths))


def brute_force_pairs(truth_positions, track_positions, c):
    """GOSPA (p = 2) by enumeration: the minimum-cost partial assignment, only pairs
    closer than c allowed; each unassigned object costs c**2 / 2."""
    best, best_pairs = math.inf, []
    for assignment in _partial_assignments(len(truth_positions), len(track_positions)):
        cost, pairs, allowed = 0.0, [], True
        for i, j in enumerate(assignment):
            if j is None:
                continue
            d = math.dist(truth_positions[i], track_positions[j])
            if d >= c:
                allowed = False
                break
            cost += d * d
            pairs.append((i, j))
        if not allowed:
            continue
        cost += c * c / 2 * (len(truth_positions) + len(track_positions) - 2 * len(pairs))
        if cost < best:
            best, best_pairs = cost, pairs
    return best_pairs


def brute_force(frames, times, c):
    """The definitions as plain per-object timelines."""
    truth_line, track_line = {}, {}  # id -> [(time, matched partner or None)]
    for f, t in zip(frames, times):
        pairs = brute_force_pairs(f.truth_positions.tolist(), f.track_positions.tolist(), c)
        truth_partner = {int(f.truth_ids[i]): int(f.track_ids[j]) for i, j in pairs}
        track_partner = {v: k for k, v in truth_partner.items()}
        for truth in f.truth_ids.tolist():
            truth_line.setdefault(truth, []).append((t, truth_partner.get(truth)))
        for track in f.track_ids.tolist():
            track_line.setdefault(track, []).append((t, track_partner.get(track)))
    switches = fragments = never = 0
    waits = []
    for line in truth_line.values():
        partners = [k for _, k in line if k is not None]
        switches += sum(1 for a, b in zip(partners, partners[1:]) if a != b)
        runs = [matched for matched, _ in itertools.groupby(k is not None for _, k in line)]
        # a missed run with a matched run before and after it
        fragments += sum(1 for r in range(1, len(runs) - 1) if not runs[r])
        matched_times = [t for t, k in line if k is not None]
        if matched_times:
            waits.append(matched_times[0] - line[0][0])
        else:
            never += 1
            waits.append(line[-1][0] - line[0][0])
    lifetimes = [line[-1][0] - line[0][0] for line in track_line.values()
                 if all(k is None for _, k in line)]
    truth_frames = sum(len(line) for line in truth_line.values())
    matched = sum(k is not None for line in truth_line.values() for _, k in line)
    unmatched_tracks = sum(k is None for line in track_line.values() for _, k in line)
    return {"id_switches": switches, "fragmentations": fragments, "never_tracked": never,
            "false_tracks": len(lifetimes),
            "false_track_lifetime": sum(lifetimes) / len(lifetimes) if lifetimes else 0.0,
            "time_to_track": sum(waits) / len(waits) if waits else 0.0,
            "tracked_fraction": matched / truth_frames if truth_frames else 1.0,
            "false_tracks_per_scan": unmatched_tracks / len(frames)}


def random_run(rng, n_frames, id_offset=0):
    frames = []
    for _ in range(n_frames):
        truth_ids = rng.choice(4, size=rng.integers(0, 5), replace=False) + id_offset
        track_ids = rng.choice(5, size=rng.integers(0, 5), replace=False) + id_offset
        frames.append(metrics.EvaluationFrame(
            truth_ids, rng.uniform(0, 60, (truth_ids.size, 2)),
            track_ids, rng.uniform(0, 60, (track_ids.size, 2))))
    times = np.cumsum(rng.uniform(0.1, 3.0, n_frames)).tolist()
    return frames, times


def test_matches_a_brute_force_reference_on_random_runs():
    rng = np.random.default_rng(20240611)
    switched = fragmented = 0
    for _ in range(300):
        frames, times = random_run(rng, int(rng.integers(1, 7)))
        c = float(rng.choice([10.0, 30.0, 60.0]))
        result = track_management(frames, times, c=c)
        expected = brute_force(frames, times, c)
        for name, value in expected.items():
            assert getattr(result, name) == pytest.approx(value, abs=1e-12), name
        # the matched pairs are GOSPA's: its missed and false counts agree
        gospa = metrics.gospa_from_frames(frames, c=c)
        assert result.unmatched_track_frames == int(gospa.num_false.sum())
        assert result.truth_frames - result.matched_truth_frames == int(gospa.num_missed.sum())
        switched += result.id_switches > 0
        fragmented += result.fragmentations > 0
    assert switched > 20 and fragmented > 20  # the random runs exercise both


def test_combine_equals_the_concatenated_runs():
    rng = np.random.default_rng(7)
    for _ in range(50):
        runs, all_frames, all_times, start = [], [], [], 0.0
        for r in range(int(rng.integers(1, 4))):
            frames, times = random_run(rng, int(rng.integers(1, 6)), id_offset=100 * r)
            runs.append(track_management(frames, times))
            # the same frames later in one long run, ids kept apart per run
            all_frames += frames
            all_times += [start + t for t in times]
            start = all_times[-1] + 1.0
        pooled, whole = combine(runs), track_management(all_frames, all_times)
        for name, value in whole.as_dict().items():
            assert getattr(pooled, name) == pytest.approx(value, rel=1e-12, abs=1e-12), name


def test_combine_is_a_ratio_of_sums():
    a = track_management([frame({0: (0, 0)}, {10: (0, 0)})] * 3, [0, 1, 2])
    b = track_management([frame({0: (0, 0)})], [0])
    pooled = combine([a, b])
    assert pooled.tracked_fraction == 3 / 4  # not (1 + 0) / 2
    assert pooled.frames == 4 and isinstance(pooled, TrackManagement)


def test_gospa_split_sums_to_the_mean_squared_gospa():
    rng = np.random.default_rng(3)
    frames, _ = random_run(rng, 20)
    gospa = metrics.gospa_from_frames(frames)
    localisation, missed, false = metrics.gospa_split(gospa)
    assert localisation + missed + false == pytest.approx(gospa.rms ** 2, rel=1e-12)
    assert missed == pytest.approx(30.0 ** 2 / 2 * gospa.num_missed.mean())
    with pytest.raises(TypeError, match="result"):
        metrics.gospa_split(frames)


# ---------------------------------------------------------------------------
# Bad input
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("times, c, match", [
    ([0.0], 30.0, "times"), ([0.0, 1.0, 2.0], 30.0, "times"),
    ([1.0, 1.0], 30.0, "times"), ([2.0, 1.0], 30.0, "times"), ([0.0, math.nan], 30.0, "times"),
    ([0.0, 1.0], 0.0, "c"), ([0.0, 1.0], -5.0, "c"), ([0.0, 1.0], math.inf, "c")])
def test_bad_input_names_the_argument(times, c, match):
    with pytest.raises(ValueError, match=match):
        track_management([frame(), frame()], times, c=c)


def test_bad_frames_and_results_are_refused():
    with pytest.raises(ValueError, match="frames"):
        track_management([], [])
    with pytest.raises(TypeError, match="times"):
        track_management([frame()], ["soon"])
    with pytest.raises(ValueError, match="results"):
        combine([])
    one = track_management([frame()], [0])
    with pytest.raises(ValueError, match="same c"):
        combine([one, track_management([frame()], [0], c=10.0)])
    with pytest.raises(TypeError, match=r"results\[1\]"):
        combine([one, "two"])
