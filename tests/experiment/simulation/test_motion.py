"""Tests of the simulated vessels' motion: truth velocities are continuous, because turn
rates ramp over TURN_RATE_RAMP_TIME at the joins of a path's legs and turns; they agree
with the positions; and the paths sailed keep the designed routes."""

import math

import numpy as np
import pytest
from scipy.integrate import cumulative_simpson

from ctxmodels.experiment.scenarios import (
    EPOCH,
    SIMULATED_SCENARIOS as SCENARIOS,
    FormationMotion,
    PathBuilder,
    PathMotion,
    WeaveMotion,
    make_scenario,
)
from ctxmodels.experiment.simulation.motion import TURN_RATE_RAMP_TIME

# About 0.15 g: more than the scenarios' 3–5.5 m/s craft need in their tightest turn
# (0.83 m/s² on the loop vessel's 30 m circle), well within what a small craft can do.
# Velocity jumps read as far more: 0.01 m/s between samples 2 ms apart is 5 m/s².
MAX_ACCELERATION = 1.5
SLACK = 1e-9


def check_continuity(vessel, seconds, positions, velocities):
    """The three properties of a physical track, between consecutive samples:
    velocity changes no faster than MAX_ACCELERATION; the mean velocity over the
    interval (the finite difference of positions) is within MAX_ACCELERATION·Δt/4 of
    the mean of the end velocities (true of any velocity whose rate of change is
    bounded by it; a jump of Δv next to a sample shows as Δv/2); and positions move no
    further than that speed allows."""
    dt = np.diff(seconds)
    bound = MAX_ACCELERATION * dt
    change = np.hypot(*np.diff(velocities, axis=0).T)
    assert np.all(change <= bound + SLACK), (vessel, change.max(), seconds[np.argmax(change)])
    mean_velocity = np.diff(positions, axis=0) / dt[:, None]
    error = np.hypot(*(mean_velocity - 0.5 * (velocities[1:] + velocities[:-1])).T)
    assert np.all(error <= bound / 4 + SLACK), (vessel, error.max(), seconds[np.argmax(error)])
    speed = np.maximum(np.hypot(*velocities[1:].T), np.hypot(*velocities[:-1].T))
    step = np.hypot(*np.diff(positions, axis=0).T)
    assert np.all(step <= (speed + bound / 2) * dt + SLACK), vessel


# ---------------------------------------------------------------- every scenario, every vessel


@pytest.fixture(scope="module", params=list(SCENARIOS))
def full_run(request):
    return make_scenario(request.param, seed=0)  # the whole 480 s


def test_truth_states_are_continuous_for_every_vessel(full_run):
    """On the GroundTruthStates the trackers are scored against, at every radar and lidar
    timestamp, and on the ego's navigation track."""
    ego = full_run.ego
    seconds = np.array([(t - EPOCH).total_seconds() for t in ego.timestamps])
    check_continuity("ego", seconds, ego.positions, ego.velocities)
    assert len(full_run.truths) >= 3
    for truth in sorted(full_run.truths, key=lambda path: path.id):
        states = np.array([np.asarray(s.state_vector, dtype=float).ravel()
                           for s in truth.states])
        seconds = np.array([(s.timestamp - EPOCH).total_seconds() for s in truth.states])
        assert len(states) > 1000
        check_continuity(truth.id, seconds, states[:, [0, 2]], states[:, [1, 3]])


@pytest.mark.parametrize("name", list(SCENARIOS))
def test_motions_are_continuous_between_samples_2_ms_apart(name):
    # Finer than any scan, so a jump of a few mm/s anywhere in the 480 s shows.
    layout = SCENARIOS[name].layout()
    times = np.arange(0.0, layout.default_duration, 0.002)
    for vessel, motion in [("ego", layout.ego)] + [(t.id, t.motion) for t in layout.targets]:
        sample = motion.sample(times)
        assert sample.exists.any()
        exists = sample.exists
        check_continuity(vessel, times[exists], sample.positions[exists],
                         sample.velocities[exists])


def test_sailing_the_designed_paths_exactly_would_fail_these_checks():
    """The defect the turn-rate ramps remove: with turn_rate_ramp=0 the formation
    partner's and the follower's velocities jump at the route's joins."""
    layout = SCENARIOS["formation"].layout()
    motions = {target.id: target.motion for target in layout.targets}
    exact_leader = PathMotion(layout.ego.path, layout.ego.speed, layout.ego.start_time, 0.0)
    partner = FormationMotion(exact_leader, motions["cooperating-usv"].body_offset)
    follower = motions["follower"]
    follower = WeaveMotion(follower.path, follower.speed, follower.amplitude, follower.period,
                           follower.start_time, turn_rate_ramp=0.0)
    times = np.arange(0.0, layout.default_duration, 0.002)
    for motion in (partner, follower):
        jumps = np.hypot(*np.diff(motion.sample(times).velocities, axis=0).T)
        assert jumps.max() > 0.1
        with pytest.raises(AssertionError):
            check_continuity("exact", times, motion.sample(times).positions,
                             motion.sample(times).velocities)


def test_the_sailed_routes_stay_within_a_metre_of_the_designed_ones():
    for spec in SCENARIOS.values():
        for target in spec.layout().targets:
            motion = getattr(target.motion, "leader", target.motion)
            if not hasattr(motion, "sailed_path"):
                continue
            s = np.linspace(0.0, motion.path.length, 20001)
            designed = motion.path.sample(s)[0]
            sailed = motion.sailed_path.sample(s)[0]
            assert motion.sailed_path.length == pytest.approx(motion.path.length, abs=1e-9)
            assert np.max(np.hypot(*(sailed - designed).T)) < 1.0, target.id


# ---------------------------------------------------------------- turn transitions


def test_turn_rate_ramps_linearly_over_the_ramp_time_centred_on_the_join():
    speed, radius = 4.0, 60.0
    path = PathBuilder((0.0, 0.0), heading=0.0).straight(200.0).turn(radius, math.pi).build()
    motion = PathMotion(path, speed)
    join, full = 200.0 / speed, speed / radius
    times = np.linspace(join - 5.0, join + 5.0, 1001)
    expected = full * np.clip((times - join) / TURN_RATE_RAMP_TIME + 0.5, 0.0, 1.0)
    np.testing.assert_allclose(motion.turn_rates(times), expected, atol=1e-12)
    # Back on the designed circle's heading once the ramp is over.
    after = np.array([join + TURN_RATE_RAMP_TIME / 2 + 1.0])
    heading = motion.sample(after).headings[0]
    assert heading == pytest.approx(full * (TURN_RATE_RAMP_TIME / 2 + 1.0), abs=1e-9)


def test_transitions_keep_headings_outside_them_and_integrate_the_tangent():
    path = (
        PathBuilder((10.0, -5.0), heading=0.3)
        .straight(100.0)
        .turn(50.0, math.pi / 2)
        .straight(8.0)  # shorter than a transition: two ramps overlap
        .turn(30.0, -math.pi)
        .turn(80.0, 0.5)
        .straight(40.0)
        .build()
    )
    length = 20.0
    sailed = path.with_turn_transitions(length)
    s = np.linspace(0.0, path.length, 200001)
    positions, tangents, curvatures = sailed.sample(s)
    designed_positions, designed_tangents, _ = path.sample(s)
    # Continuous curvature, changing no faster than the steepest ramps (the two that
    # overlap around the 8 m leg: 1/50 → 0 → -1/30 over 20 m each).
    steepest = (1 / 50 + 1 / 30) / length
    assert np.max(np.abs(np.diff(curvatures))) <= steepest * (s[1] - s[0]) * 1.001
    # Unit tangents whose integral is the position (the clothoid quadrature).
    np.testing.assert_allclose(np.hypot(*tangents.T), 1.0, atol=1e-12)
    integral = positions[0] + np.column_stack(
        [cumulative_simpson(tangents[:, i], x=s, initial=0.0) for i in (0, 1)]
    )
    np.testing.assert_allclose(positions, integral, atol=1e-8)
    # Far from the joins the heading is exactly the designed one.
    joins = np.cumsum([100.0, 25.0 * math.pi, 8.0, 30.0 * math.pi, 40.0])
    away = np.min(np.abs(s[:, None] - joins[None, :]), axis=1) > length / 2 + 1e-6
    cross = tangents[:, 0] * designed_tangents[:, 1] - tangents[:, 1] * designed_tangents[:, 0]
    assert away.sum() > 100000 and np.max(np.abs(cross[away])) < 1e-12
    assert np.max(np.abs(cross[~away])) > 1e-3  # and inside them it is not
    np.testing.assert_allclose(positions[0], designed_positions[0])
    assert np.max(np.hypot(*(positions - designed_positions).T)) < 2.0


def test_transitions_pass_the_waypoints_and_zero_length_is_the_designed_path():
    waypoints = [(310.0, 200.0), (290.0, -200.0), (1150.0, -950.0)]
    builder = PathBuilder((900.0, 1200.0), heading=math.atan2(-1000.0, -590.0))
    for waypoint in waypoints:
        builder.head_to(waypoint, 80.0)
    path = builder.build()
    motion = PathMotion(path, 5.5)
    points = motion.sailed_path.sample(np.linspace(0.0, path.length, 50001))[0]
    for waypoint in waypoints:
        assert np.min(np.hypot(*(points - waypoint).T)) < 0.5, waypoint
    assert path.with_turn_transitions(0.0) is path
    exact = PathMotion(path, 5.5, turn_rate_ramp=0.0).sample(np.arange(0.0, 300.0, 0.5))
    designed = path.sample(5.5 * np.arange(0.0, 300.0, 0.5))[0]
    np.testing.assert_array_equal(exact.positions, designed)
    with pytest.raises(ValueError):
        motion.sailed_path.with_turn_transitions(10.0)
    with pytest.raises(ValueError):
        path.with_turn_transitions(-1.0)


def test_a_transition_never_starts_before_the_path_does():
    # A turn 3 m after the start: its ramp shrinks to 6 m, so the path still starts
    # straight, at its designed point and heading.
    path = PathBuilder((0.0, 0.0), heading=1.0).straight(3.0).turn(40.0, 1.0).build()
    sailed = path.with_turn_transitions(20.0)
    positions, tangents, curvatures = sailed.sample([0.0, 6.0, 7.0])
    np.testing.assert_allclose(positions[0], [0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(tangents[0], [math.cos(1.0), math.sin(1.0)], atol=1e-15)
    assert curvatures[0] == 0.0
    assert curvatures[1] == pytest.approx(1 / 40.0) and curvatures[2] == pytest.approx(1 / 40.0)
