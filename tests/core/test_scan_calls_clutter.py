"""The detector context's thin λ call (``clutter_spatial_density_array`` through
``ScanCalls.clutter_at_pose``): float64 arrays go straight to the core, anything else
through the clutter model's general path, with the same bits and the same errors; the
range bands read the squared range (no square root) and still decide as the range does."""
import math

import numpy as np
import pytest

from ctxmodels import (ClutterDensityModel, DetectionProbabilityModel, MetadataThreshold,
                       RangeBands, SensorModel)

POSE = (10.0, -20.0, 0.3)
EDGES = (100.0, 1000.0)


def _clutter():
    return ClutterDensityModel(factors=[
        RangeBands(edges=EDGES, values=(1e-3, 1e-2, 3e-2), upper_owns=(True, False)),
        MetadataThreshold(key="area", threshold=10.0, below=1e-1, at_or_above=1e-3, missing=1e-2),
        0.5,
    ])


def _context(clutter=None):
    model = SensorModel(detection=DetectionProbabilityModel(factors=[0.9]),
                        clutter=clutter or _clutter())
    return model.context(POSE)


def _detections(n, seed=0):
    rng = np.random.default_rng(seed)
    positions = rng.uniform(-1500, 1500, size=(n, 2))
    area = rng.uniform(0, 20, size=(n, 1))
    area[rng.random(n) < 0.1] = np.nan
    return positions, area


def _numpy_reference(positions, area):
    """λ written out in NumPy with the range as √(dx² + dy²), edge by edge."""
    dx, dy = positions[:, 0] - POSE[0], positions[:, 1] - POSE[1]
    r = np.sqrt(dx * dx + dy * dy)
    bands = np.where(r > EDGES[1], 3e-2, np.where(r >= EDGES[0], 1e-2, 1e-3))
    a = area[:, 0]
    rule = np.where(np.isnan(a), 1e-2, np.where(a < 10.0, 1e-1, 1e-3))
    return 1.0 * bands * rule * 0.5


@pytest.mark.parametrize("n", [0, 1, 7, 5000])  # 5000: past the rows that keep the GIL
def test_thin_call_has_the_general_paths_and_numpys_bits(n):
    context = _context()
    positions, area = _detections(n)
    general = context.sensor_model.clutter.evaluate(context.pose, positions, area)
    thin = context.clutter_spatial_density_array(positions, area)
    assert np.array_equal(thin.view(np.uint64), general.view(np.uint64))
    assert np.array_equal(thin.view(np.uint64), _numpy_reference(positions, area).view(np.uint64))
    out = np.full(n, np.nan)
    assert context.clutter_spatial_density_array(positions, area, out=out) is out
    assert np.array_equal(out, general)
    if n >= 1000:
        assert len(set(thin.tolist())) >= 6  # every band and rule outcome took part


def test_band_edges_decide_as_the_computed_range_does():
    """Detections whose computed range lands exactly on an edge, and whose squared range is
    one float either side of the edge's square: the squared-range thresholds must give
    what comparing √(dx² + dy²) with the edge gives."""
    positions = []
    for edge in EDGES:
        for bearing in np.linspace(0.0, 2 * math.pi, 97):
            for scale in (1.0, np.nextafter(1.0, 0.0), np.nextafter(1.0, 2.0)):
                r = edge * scale
                positions.append((POSE[0] + r * math.cos(bearing), POSE[1] + r * math.sin(bearing)))
        positions.append((POSE[0] + edge, POSE[1]))  # exactly on the edge
    positions = np.array(positions)
    area = np.full((len(positions), 1), 3.0)
    lam = _context().clutter_spatial_density_array(positions, area)
    assert np.array_equal(lam.view(np.uint64), _numpy_reference(positions, area).view(np.uint64))
    on_edge = np.hypot(positions[:, 0] - POSE[0], positions[:, 1] - POSE[1])
    assert np.any(np.isin(on_edge, EDGES))  # some computed ranges sit on an edge exactly


def test_other_inputs_take_the_general_path_with_the_same_values():
    context = _context()
    positions, area = _detections(50)
    expected = context.clutter_spatial_density_array(positions, area)
    mappings = [{} if np.isnan(a) else {"area": float(a)} for a in area[:, 0]]
    for given_positions, given_metadata in [
        (positions.tolist(), area), (np.asfortranarray(positions), area),
        (positions.astype(np.float32).astype(np.float64), area), (positions, mappings),
        (positions, area.tolist()), (np.repeat(positions, 2, axis=0)[::2], area),
    ]:
        lam = context.clutter_spatial_density_array(given_positions, given_metadata)
        reference = context.sensor_model.clutter.evaluate(
            context.pose, np.asarray(given_positions, dtype=np.float64), given_metadata)
        assert np.array_equal(lam, reference)
    assert np.array_equal(context.clutter_spatial_density_array(positions, mappings), expected)
    # No metadata for a model that reads some: every detection's metadata is missing.
    missing = context.clutter_spatial_density_array(positions)
    assert np.array_equal(missing, context.clutter_spatial_density_array(
        positions, np.full((50, 1), np.nan)))
    # Measured ranges are read by the general path.
    ranges = np.full(50, np.nan)
    ranges[0] = 999.0
    with_ranges = context.clutter_spatial_density_array(positions, area, ranges=ranges)
    a = area[0, 0]
    rule = 1e-2 if np.isnan(a) else 1e-1 if a < 10.0 else 1e-3
    assert with_ranges[0] == 1.0 * 1e-2 * rule * 0.5  # the 100–1000 m band, whatever its position
    assert np.array_equal(with_ranges[1:], expected[1:])


def test_a_model_without_metadata_takes_no_metadata_array():
    context = _context(ClutterDensityModel(factors=[
        RangeBands(edges=(500.0,), values=(1e-3, 2e-3), upper_owns=(True,))]))
    positions, _ = _detections(40)
    lam = context.clutter_spatial_density_array(positions)
    r = np.sqrt((positions[:, 0] - POSE[0]) ** 2 + (positions[:, 1] - POSE[1]) ** 2)
    assert np.array_equal(lam, np.where(r >= 500.0, 2e-3, 1e-3))


def _error(call):
    with pytest.raises((ValueError, TypeError)) as caught:
        call()
    return type(caught.value), str(caught.value)


@pytest.mark.parametrize("fault", ["nan position", "inf metadata", "short metadata",
                                   "bad out", "overlapping out", "read-only out"])
def test_errors_are_the_general_paths_and_name_the_argument(fault):
    context = _context()
    clutter, pose = context.sensor_model.clutter, context.pose
    positions, area = _detections(6)
    out = None
    if fault == "nan position":
        positions[4, 1] = np.nan
    elif fault == "inf metadata":
        area[2, 0] = np.inf
    elif fault == "short metadata":
        area = area[:5]
    elif fault == "bad out":
        out = np.empty(5)
    elif fault == "overlapping out":
        positions = np.zeros((6, 2))
        out = positions.reshape(-1)[:6]
    else:
        out = np.empty(6)
        out.setflags(write=False)
    thin = _error(lambda: context.clutter_spatial_density_array(positions, area, out=out))
    general = _error(lambda: clutter.evaluate(pose, positions, area, out=out))
    assert thin == general
    argument = {"nan position": "positions", "inf metadata": "metadata",
                "short metadata": "metadata"}.get(fault, "out")
    assert thin[1].startswith(argument), thin
