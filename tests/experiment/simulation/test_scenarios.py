"""Tests of the seeded radar–lidar scenario simulator (the experiment's ground truth)."""

import datetime
import math

import numpy as np
import pytest
import shapely
from stonesoup.types.detection import Clutter, TrueDetection
from stonesoup.types.state import State

from ctxmodels.experiment.scenarios import (
    EPOCH,
    SIMULATED_SCENARIOS as SCENARIOS,
    DriftMotion,
    FormationMotion,
    LidarConfig,
    PathBuilder,
    PathMotion,
    RadarConfig,
    SceneLayout,
    SensorPose,
    StaticObject,
    TargetSpec,
    WeaveMotion,
    make_scenario,
    simulate,
)

HALF_BLIND = math.radians(65.0) / 2


def wrap(angle):
    return (np.asarray(angle) + np.pi) % (2 * np.pi) - np.pi


@pytest.fixture(scope="module")
def mixed_range():
    # Long enough for the loop vessel's 30 m loop (it arrives after ~215 s).
    return make_scenario("mixed-range", seed=11, duration=260.0)


@pytest.fixture(scope="module")
def formation():
    return make_scenario("formation", seed=12, duration=120.0)


@pytest.fixture(scope="module")
def islands():
    return make_scenario("islands", seed=13, duration=120.0)


@pytest.fixture(scope="module")
def runs(mixed_range, formation, islands):
    return [mixed_range, formation, islands]


def truth_table(run):
    """{truth_id: {timestamp: state vector (4,)}}."""
    return {
        truth.id: {
            state.timestamp: np.asarray(state.state_vector, dtype=float).ravel()
            for state in truth.states
        }
        for truth in run.truths
    }


def ego_table(run):
    return {
        t: (run.ego.positions[i], run.ego.headings[i]) for i, t in enumerate(run.ego.timestamps)
    }


def signature(run):
    """A canonical, order-free description of every detection of a run."""
    rows = []
    for sensor, scan in run.scans():
        for detection in scan.detections:
            metadata = detection.metadata
            rows.append(
                (
                    sensor,
                    scan.timestamp,
                    metadata["source"],
                    metadata.get("truth_id", metadata.get("static_id", "")),
                    tuple(float(v) for v in np.asarray(detection.state_vector).ravel()),
                    metadata.get("area", -1.0),
                )
            )
    return sorted(rows)


def polar_from_ego(position, ego_position, ego_heading):
    offset = np.asarray(position) - ego_position
    return math.hypot(*offset), float(wrap(math.atan2(offset[1], offset[0]) - ego_heading))


def target_detections(run, sensor):
    scans = run.radar_scans if sensor == "radar" else run.lidar_scans
    for scan in scans:
        for detection in scan.detections:
            if detection.metadata["source"] == "target":
                yield scan, detection


def detection_rate(runs, sensor, range_low, range_high):
    """Detected / opportunities for vessels and static objects in a true range band
    (line of sight ignored: only used on land-free scenarios)."""
    opportunities = detected = 0
    for run in runs:
        truths = truth_table(run)
        ego = ego_table(run)
        scans = run.radar_scans if sensor == "radar" else run.lidar_scans
        for scan in scans:
            ego_position, ego_heading = ego[scan.timestamp]
            seen = {
                d.metadata.get("truth_id", d.metadata.get("static_id"))
                for d in scan.detections
                if d.metadata["source"] in ("target", "static")
            }
            objects = [
                (truth_id, states[scan.timestamp][[0, 2]])
                for truth_id, states in truths.items()
                if scan.timestamp in states
            ]
            objects += [(obj.id, np.array(obj.position)) for obj in run.static_objects]
            for object_id, position in objects:
                range_, bearing = polar_from_ego(position, ego_position, ego_heading)
                if not range_low < range_ < range_high:
                    continue
                if sensor == "radar" and abs(wrap(bearing - np.pi)) < HALF_BLIND:
                    continue
                opportunities += 1
                detected += object_id in seen
    return detected, opportunities


def assert_binomial(detected, opportunities, prob, sigmas=4.5):
    assert opportunities > 100
    rate = detected / opportunities
    tolerance = sigmas * math.sqrt(prob * (1 - prob) / opportunities)
    assert abs(rate - prob) <= tolerance, (rate, prob, opportunities)


# ---------------------------------------------------------------- determinism, registry


def test_same_seed_gives_identical_runs():
    first = make_scenario("formation", seed=5, duration=30.0)
    second = make_scenario("formation", seed=5, duration=30.0)
    assert signature(first) == signature(second)
    assert truth_table(first).keys() == truth_table(second).keys()
    for truth_id, states in truth_table(first).items():
        other = truth_table(second)[truth_id]
        assert all(np.array_equal(states[t], other[t]) for t in states)
    np.testing.assert_array_equal(first.ego.positions, second.ego.positions)


def test_different_seeds_differ_but_share_the_truth():
    first = make_scenario("islands", seed=1, duration=20.0)
    second = make_scenario("islands", seed=2, duration=20.0)
    assert signature(first) != signature(second)
    assert {k: list(map(tuple, v.values())) for k, v in truth_table(first).items()} == {
        k: list(map(tuple, v.values())) for k, v in truth_table(second).items()
    }


def test_scenario_numbers_alias_names_and_unknown_names_fail():
    assert set(SCENARIOS) == {"mixed-range", "formation", "islands"}
    assert [SCENARIOS[name].number for name in ("mixed-range", "formation", "islands")] == [1, 2, 3]
    assert signature(make_scenario(3, seed=4, duration=5.0)) == signature(
        make_scenario("islands", seed=4, duration=5.0)
    )
    with pytest.raises(KeyError):
        make_scenario("harbour", seed=0, duration=5.0)
    with pytest.raises(KeyError):
        make_scenario(4, seed=0, duration=5.0)


def test_lidar_settings_do_not_change_radar_draws():
    default = make_scenario("mixed-range", seed=9, duration=20.0)
    noisy_lidar = make_scenario(
        "mixed-range",
        seed=9,
        duration=20.0,
        lidar=LidarConfig(clutter_per_scan=20.0, position_std=2.0),
    )
    radar_rows = [row for row in signature(default) if row[0] == "radar"]
    assert radar_rows == [row for row in signature(noisy_lidar) if row[0] == "radar"]
    assert signature(default) != signature(noisy_lidar)


def test_default_duration_is_480_s():
    assert all(spec.layout().default_duration == 480.0 for spec in SCENARIOS.values())


# ---------------------------------------------------------------- timing


def test_scan_rates_and_asynchronous_timestamps(runs):
    for run in runs:
        radar_times, lidar_times = run.radar_times, run.lidar_times
        assert len(radar_times) == math.ceil(run.duration * 0.8)
        assert abs(len(lidar_times) - run.duration * 10) <= 1
        assert radar_times[0] == EPOCH and lidar_times[0] > EPOCH
        assert set(np.diff(radar_times)) == {datetime.timedelta(seconds=1.25)}
        assert set(np.diff(lidar_times)) == {datetime.timedelta(seconds=0.1)}
        assert not set(radar_times) & set(lidar_times)
        assert run.ego.timestamps == sorted(set(radar_times) | set(lidar_times))
        merged = [scan.timestamp for _, scan in run.scans()]
        assert merged == sorted(merged) and len(merged) == len(radar_times) + len(lidar_times)


def test_truth_has_a_state_at_every_scan_time_and_consistent_velocity(runs):
    for run in runs:
        assert run.truths and all(isinstance(truth.id, str) for truth in run.truths)
        for truth_id, states in truth_table(run).items():
            assert list(states) == run.ego.timestamps, truth_id
            vectors = np.array(list(states.values()))
            # Mid-point velocity predicts the lidar-to-lidar displacement.
            lidar = np.array([states[t] for t in run.lidar_times])
            displacement = np.diff(lidar[:, [0, 2]], axis=0) / 0.1
            mean_velocity = 0.5 * (lidar[1:, [1, 3]] + lidar[:-1, [1, 3]])
            assert np.max(np.abs(displacement - mean_velocity)) < 0.5, truth_id
            assert np.all(np.hypot(vectors[:, 1], vectors[:, 3]) < 8.0)


def test_scan_poses_match_navigation_and_interpolate(formation):
    ego = ego_table(formation)
    for scan in formation.radar_scans[:10] + formation.lidar_scans[:10]:
        position, heading = ego[scan.timestamp]
        assert scan.sensor_pose == SensorPose(position[0], position[1], heading)
        assert formation.ego.pose_at(scan.timestamp) == scan.sensor_pose
    before, after = formation.lidar_scans[5].sensor_pose, formation.lidar_scans[6].sensor_pose
    halfway = formation.lidar_times[5] + datetime.timedelta(seconds=0.05)
    interpolated = formation.ego.pose_at(halfway)
    np.testing.assert_allclose(
        interpolated.position, (before.position + after.position) / 2, atol=1e-6
    )


# ---------------------------------------------------------------- sensing geometry


def test_radar_target_detections_only_from_coverage(runs):
    count = 0
    for run in runs:
        truths, ego = truth_table(run), ego_table(run)
        for scan, detection in target_detections(run, "radar"):
            assert isinstance(detection, TrueDetection)
            assert detection.groundtruth_path.id == detection.metadata["truth_id"]
            state = truths[detection.metadata["truth_id"]][scan.timestamp]
            range_, bearing = polar_from_ego(state[[0, 2]], *ego[scan.timestamp])
            assert 50.0 < range_ < 1612.0
            assert abs(wrap(bearing - np.pi)) >= HALF_BLIND
            measured_bearing, measured_range = np.asarray(
                detection.state_vector, dtype=float
            ).ravel()
            assert abs(wrap(measured_bearing - bearing)) < 6 * run.radar.bearing_std
            assert abs(measured_range - range_) < 6 * run.radar.range_std
            count += 1
    assert count > 300


def test_lidar_target_detections_only_within_80_m(runs):
    count = 0
    for run in runs:
        truths, ego = truth_table(run), ego_table(run)
        for scan, detection in target_detections(run, "lidar"):
            state = truths[detection.metadata["truth_id"]][scan.timestamp]
            range_, _ = polar_from_ego(state[[0, 2]], *ego[scan.timestamp])
            assert range_ < 80.0
            assert (
                np.hypot(*(np.asarray(detection.state_vector, dtype=float).ravel() - state[[0, 2]]))
                < 3.0
            )
            count += 1
    assert count > 1000


def test_detection_rates_match_truth_models(mixed_range, formation):
    land_free = [mixed_range, formation]
    assert_binomial(*detection_rate(land_free, "lidar", 0.0, 50.0), 0.95)
    assert_binomial(*detection_rate(land_free, "lidar", 50.0, 80.0), 0.2)
    assert_binomial(*detection_rate(land_free, "radar", 50.0, 1612.0), RadarConfig().prob_detection)
    # Nothing beyond coverage.
    assert detection_rate(land_free, "lidar", 80.0, 1e9)[0] == 0
    assert detection_rate(land_free, "radar", 1612.0, 1e9)[0] == 0


def test_truth_detection_probabilities_are_configurable():
    run = make_scenario(
        "formation",
        seed=3,
        duration=40.0,
        radar=RadarConfig(prob_detection=1.0, clutter_per_scan_near=0, clutter_per_scan_far=0),
        lidar=LidarConfig(range_bands=((50.0, 1.0),), clutter_per_scan=0),
    )
    assert_binomial(*detection_rate([run], "lidar", 0.0, 50.0), 1.0)
    assert_binomial(*detection_rate([run], "radar", 50.0, 1612.0), 1.0)
    assert detection_rate([run], "lidar", 50.0, 1e9)[0] == 0
    assert all(
        d.metadata["source"] != "clutter" for _, scan in run.scans() for d in scan.detections
    )


def test_bearing_range_model_inverts_to_the_true_position(runs):
    for run in runs:
        truths = truth_table(run)
        for scan, detection in list(target_detections(run, "radar"))[:200]:
            model = detection.measurement_model
            assert np.allclose(
                np.asarray(model.translation_offset, dtype=float).ravel(), scan.sensor_pose.position
            )
            state = truths[detection.metadata["truth_id"]][scan.timestamp]
            inverted = np.asarray(model.inverse_function(detection), dtype=float).ravel()[[0, 2]]
            range_ = float(detection.state_vector[1, 0])
            tolerance = 5 * math.hypot(run.radar.range_std, range_ * run.radar.bearing_std)
            assert np.hypot(*(inverted - state[[0, 2]])) < tolerance
            noise_free = np.asarray(model.function(State(state.reshape(4, 1))), dtype=float).ravel()
            assert (
                abs(wrap(noise_free[0] - float(detection.state_vector[0, 0])))
                < 6 * run.radar.bearing_std
            )


def test_bearing_is_relative_to_the_ego_heading():
    # Ego heading north; a vessel due north is dead ahead (bearing 0), one due west is
    # on the port beam (+π/2), one due south is in the blind sector.
    ego = DriftMotion(origin=(100.0, -50.0), mean_heading=math.pi / 2)

    def parked(x, y):
        return PathMotion(PathBuilder((x, y), heading=0.0).straight(1e-3).build(), speed=1e-9)

    layout = SceneLayout(
        ego=ego,
        targets=(
            TargetSpec("ahead", parked(100.0, 450.0)),
            TargetSpec("port", parked(-300.0, -50.0)),
            TargetSpec("astern", parked(100.0, -450.0)),
        ),
        default_duration=10.0,
    )
    run = simulate(
        layout,
        seed=0,
        radar=RadarConfig(
            prob_detection=1.0,
            bearing_std=1e-6,
            range_std=1e-6,
            clutter_per_scan_near=0,
            clutter_per_scan_far=0,
        ),
    )
    for scan in run.radar_scans:
        by_id = {
            d.metadata["truth_id"]: np.asarray(d.state_vector, dtype=float).ravel()
            for d in scan.detections
        }
        assert set(by_id) == {"ahead", "port"}
        np.testing.assert_allclose(by_id["ahead"], [0.0, 500.0], atol=1e-3)
        np.testing.assert_allclose(by_id["port"], [math.pi / 2, 400.0], atol=1e-3)


# ---------------------------------------------------------------- clutter


def test_radar_clutter_is_uniform_in_coverage_and_heavier_beyond_1000_m(runs):
    config = RadarConfig()
    near = far = 0
    scans = 0
    for run in runs:
        for scan in run.radar_scans:
            scans += 1
            for detection in scan.detections:
                if detection.metadata["source"] != "clutter":
                    continue
                assert isinstance(detection, Clutter)
                bearing, range_ = np.asarray(detection.state_vector, dtype=float).ravel()
                assert 50.0 <= range_ <= 1612.0 and abs(wrap(bearing - np.pi)) >= HALF_BLIND
                near += range_ < 1000.0
                far += range_ >= 1000.0
    arc = 2 * np.pi - 2 * HALF_BLIND
    near_density, far_density = near / (scans * arc * 950.0), far / (scans * arc * 612.0)
    assert far_density > 2 * near_density
    np.testing.assert_allclose(near_density, config.clutter_density_near, rtol=0.15)
    np.testing.assert_allclose(far_density, config.clutter_density_far, rtol=0.1)
    # the calibrated densities (docs/calibration.md), per rad·m
    np.testing.assert_allclose(config.clutter_density_near, 1.0e-3, rtol=1e-12)
    np.testing.assert_allclose(config.clutter_density_far, 3.0e-3, rtol=1e-12)


def test_lidar_clutter_is_small_and_vessels_are_large(runs):
    clutter_areas, vessel_areas, static_areas = [], [], []
    for run in runs:
        ego = ego_table(run)
        for scan in run.lidar_scans:
            for detection in scan.detections:
                source = detection.metadata["source"]
                area = detection.metadata["area"]
                if source == "clutter":
                    position = np.asarray(detection.state_vector, dtype=float).ravel()
                    assert np.hypot(*(position - ego[scan.timestamp][0])) < 80.0
                    clutter_areas.append(area)
                elif source == "target":
                    vessel_areas.append(area)
                else:
                    static_areas.append(area)
    assert len(clutter_areas) > 1000
    assert 0.9 < np.mean(np.array(clutter_areas) < 10.0) < 1.0
    assert min(vessel_areas) >= 10.0
    assert static_areas and np.median(static_areas) < 10.0  # buoys look like clutter


def test_static_objects_are_detected_but_not_ground_truth(mixed_range):
    static_ids = {obj.id for obj in mixed_range.static_objects}
    assert static_ids and not static_ids & {truth.id for truth in mixed_range.truths}
    seen = {
        (sensor, d.metadata["static_id"])
        for sensor, scan in mixed_range.scans()
        for d in scan.detections
        if d.metadata["source"] == "static"
    }
    assert ("lidar", "marker-near") in seen and ("radar", "islet-east") in seen
    assert all(
        isinstance(d, Clutter)
        for _, scan in mixed_range.scans()
        for d in scan.detections
        if d.metadata["source"] == "static"
    )


# ---------------------------------------------------------------- scenario contents


def test_mixed_range_has_a_vessel_looping_at_30_m(mixed_range):
    ego = ego_table(mixed_range)
    minimum_ranges = {
        truth_id: min(polar_from_ego(s[[0, 2]], *ego[t])[0] for t, s in states.items())
        for truth_id, states in truth_table(mixed_range).items()
    }
    assert len(minimum_ranges) == 3
    closest = min(minimum_ranges, key=minimum_ranges.get)
    assert 25.0 < minimum_ranges[closest] < 35.0
    # The two others stay at medium range.
    assert all(200.0 < r < 400.0 for truth_id, r in minimum_ranges.items() if truth_id != closest)
    drift = np.hypot(*(mixed_range.ego.positions[-1] - mixed_range.ego.positions[0]))
    assert drift < 20.0 and np.ptp(mixed_range.ego.headings) < math.radians(10)


def test_formation_partner_stays_30_m_away_and_only_the_lidar_sees_it(formation):
    ego = ego_table(formation)
    states = truth_table(formation)["cooperating-usv"]
    ranges = [polar_from_ego(s[[0, 2]], *ego[t])[0] for t, s in states.items()]
    assert 28.0 < min(ranges) and max(ranges) < 32.0
    ego_speed = np.hypot(*formation.ego.velocities.T)
    assert np.all(ego_speed > 2.0)
    lidar_hits = [
        d
        for _, d in target_detections(formation, "lidar")
        if d.metadata["truth_id"] == "cooperating-usv"
    ]
    radar_hits = [
        d
        for _, d in target_detections(formation, "radar")
        if d.metadata["truth_id"] == "cooperating-usv"
    ]
    assert len(lidar_hits) > 0.9 * len(formation.lidar_scans) and not radar_hits


def test_formation_vessels_cross_the_blind_sector():
    # The full 480 s truth, straight from the layout (no detections needed).
    layout = SCENARIOS["formation"].layout()
    times = np.arange(0.0, layout.default_duration, 1.25)
    ego = layout.ego.sample(times)
    switches = {}
    for target in layout.targets:
        sample = target.motion.sample(times)
        assert sample.exists.all()
        offset = sample.positions - ego.positions
        bearing = wrap(np.arctan2(offset[:, 1], offset[:, 0]) - ego.headings)
        blind = np.abs(wrap(bearing - np.pi)) < HALF_BLIND
        switches[target.id] = int(np.count_nonzero(np.diff(blind)))
    assert switches["cooperating-usv"] == 0
    assert switches["follower"] >= 4 and switches["crosser"] >= 3


def test_islands_cast_radar_shadows(islands):
    land = shapely.union_all([shapely.Polygon(poly) for poly in islands.land])
    assert len(islands.land) == 3
    truths, ego = truth_table(islands), ego_table(islands)
    for states in truths.values():
        points = np.array([s[[0, 2]] for s in states.values()])
        assert not shapely.contains_xy(land, points[:, 0], points[:, 1]).any()
    shadowed_steps = 0
    for scan in islands.radar_scans:
        detected = {
            d.metadata["truth_id"] for d in scan.detections if d.metadata["source"] == "target"
        }
        for truth_id, states in truths.items():
            sight = shapely.LineString([ego[scan.timestamp][0], states[scan.timestamp][[0, 2]]])
            if sight.intersects(land):
                shadowed_steps += 1
                assert truth_id not in detected
    assert shadowed_steps > 50
    # Land returns sit on the radar-facing coast.
    land_returns = [
        d for scan in islands.radar_scans for d in scan.detections if d.metadata["source"] == "land"
    ]
    assert len(land_returns) > 100
    for detection in land_returns[:300]:
        x, _, y, _ = np.asarray(
            detection.measurement_model.inverse_function(detection), dtype=float
        ).ravel()
        assert shapely.distance(land.boundary, shapely.Point(x, y)) < 60.0


def test_a_layout_with_a_target_on_land_is_rejected():
    island = np.array([[100.0, -50.0], [200.0, -50.0], [200.0, 50.0], [100.0, 50.0]])
    crossing = PathMotion(PathBuilder((0.0, 0.0), heading=0.0).straight(400.0).build(), speed=5.0)
    layout = SceneLayout(
        ego=DriftMotion(origin=(0.0, -300.0)),
        targets=(TargetSpec("runs-aground", crossing),),
        land=(island,),
        default_duration=60.0,
    )
    with pytest.raises(ValueError, match="land"):
        simulate(layout, seed=0)


# ---------------------------------------------------------------- motion building blocks


def test_path_builder_turns_and_heads_to_points():
    path = PathBuilder((0.0, 0.0), heading=0.0).straight(100.0).turn(50.0, math.pi / 2).build()
    positions, tangents, curvatures = path.sample([0.0, 100.0, path.length])
    np.testing.assert_allclose(positions[-1], [150.0, 50.0], atol=1e-9)
    np.testing.assert_allclose(tangents[-1], [0.0, 1.0], atol=1e-9)
    assert path.length == pytest.approx(100.0 + 25.0 * math.pi)
    assert curvatures[-1] == pytest.approx(1 / 50.0)

    for target in [(300.0, -400.0), (-200.0, 50.0), (10.0, 500.0)]:
        builder = PathBuilder((0.0, 0.0), heading=math.pi / 4).head_to(target, 60.0)
        np.testing.assert_allclose(builder.position, target, atol=1e-6)
        end_positions, end_tangents, _ = builder.build().sample(
            np.linspace(0, builder.build().length, 2000)
        )
        # C¹: no kinks anywhere along the path.
        assert np.max(np.abs(np.diff(end_tangents, axis=0))) < 0.05


def test_formation_and_weave_velocities_are_derivatives_of_positions():
    route = (
        PathBuilder((0.0, 0.0), heading=0.0)
        .straight(200.0)
        .turn(150.0, math.pi / 2)
        .straight(200.0)
        .build()
    )
    leader = PathMotion(route, speed=3.0)
    times = np.arange(0.0, 200.0, 0.05)
    for motion in (FormationMotion(leader, (-6.0, -29.4)), WeaveMotion(route, 3.0, 40.0, 120.0)):
        sample = motion.sample(times)
        finite_difference = np.diff(sample.positions, axis=0) / 0.05
        mean_velocity = 0.5 * (sample.velocities[1:] + sample.velocities[:-1])
        errors = np.nan_to_num(np.abs(finite_difference - mean_velocity))
        # The turn rate ramps at the route's two curvature jumps, so nowhere does the
        # velocity jump (sailing the designed route exactly, it did at those instants).
        assert errors.max() < 0.01
    formation = FormationMotion(leader, (-6.0, -29.4)).sample(times)
    np.testing.assert_allclose(
        np.hypot(*(formation.positions - leader.sample(times).positions).T), math.hypot(6.0, 29.4)
    )


def test_static_object_positions_and_custom_layouts():
    layout = SceneLayout(
        ego=DriftMotion(origin=(0.0, 0.0)),
        targets=(),
        static_objects=(StaticObject("buoy", (20.0, 0.0)),),
        default_duration=5.0,
    )
    run = simulate(layout, seed=1, lidar=LidarConfig(clutter_per_scan=0))
    np.testing.assert_allclose(run.static_positions, [[20.0, 0.0]])
    assert run.truths == set() and run.land == []
    hits = [d for scan in run.lidar_scans for d in scan.detections]
    assert len(hits) > 30 and all(
        d.metadata == {"source": "static", "static_id": "buoy", "area": d.metadata["area"]}
        for d in hits
    )


# ---------------------------------------------------------------- independence


def test_the_simulator_imports_nothing_it_is_used_to_judge():
    # The truth must not share code with the context models or the Rust core; the only
    # ctxmodels imports allowed outside the simulation package are the radar's Stone Soup
    # measurement model (its exact Jacobian) and, for the Solent's truth (its scene, radars
    # and run), the real data's readers: the shoreline, the AIS log and the plane they are
    # mapped to (the trackers' land is the same chart; nothing of a model is shared).
    import ast
    import pathlib

    import ctxmodels.experiment.simulation as simulation

    allowed = {"ctxmodels.stonesoup.models", "ctxmodels.geo.ais", "ctxmodels.geo.plane",
               "ctxmodels.geo.shorelines", "ctxmodels.experiment.solent",
               "ctxmodels.experiment.solent.run", "ctxmodels.experiment.solent.scene",
               "ctxmodels.experiment.solent.radars"}
    package = pathlib.Path(simulation.__file__).parent
    solent = package.parent / "solent"
    modules = sorted(package.glob("*.py")) + [package.parent / "scenarios.py"] + [
        solent / f"{name}.py" for name in ("scene", "radars", "run")]
    assert len(modules) > 5
    for module in modules:
        inside = {package: "ctxmodels.experiment.simulation",
                  solent: "ctxmodels.experiment.solent"}.get(module.parent, "ctxmodels.experiment")
        for node in ast.walk(ast.parse(module.read_text())):
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = inside.rsplit(".", node.level - 1)[0] if node.level > 1 else inside
                    name = f"{base}.{node.module}" if node.module else base
                else:
                    name = node.module
                names = [name]
            elif isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            else:
                continue
            for name in names:
                if name.startswith("ctxmodels"):
                    assert name.startswith("ctxmodels.experiment.simulation") or name in allowed, (
                        module.name, name)
