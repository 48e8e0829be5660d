"""benches/compare.py in its quick mode: it runs, its agreement checks hold and its JSON has
the promised shape. No timing is asserted (times depend on the machine)."""
from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest
import shapely

COMPARE = Path(__file__).resolve().parents[1] / "benches" / "compare.py"


@pytest.fixture(scope="module")
def compare():
    spec = importlib.util.spec_from_file_location("bench_compare", COMPARE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def quick_results(compare, tmp_path_factory):
    path = tmp_path_factory.mktemp("bench") / "compare.json"
    assert compare.main(["--quick", "--repeats", "1", "--json", str(path)]) == 0
    return json.loads(path.read_text())


def test_quick_run_writes_agreeing_results(quick_results):
    machine = quick_results["machine"]
    assert machine["cpu_count"] >= 1 and machine["quick"] is True
    assert quick_results["agree"] is True
    names = {r["benchmark"] for r in quick_results["results"]}
    assert names == {"pd_radar", "expected_pd_cubature", "clutter_metadata", "land_contains_smooth",
                     "land_contains_jagged", "line_of_sight_smooth", "line_of_sight_jagged",
                     "pd_radar_land_sight", "pd_call_array (per call)",
                     "pd_call_scalar (per call)", "pd_radar_equation_swerling1",
                     "pd_radar_equation_swerling0_10", "pd_radar_horizon", "pd_elevation_sector",
                     "pd_3d_beam_horizon", "pd_range_rate_notch", "clutter_elevation_slant"}
    assert {r["size"] for r in quick_results["results"]
            if r["benchmark"] == "pd_call_array (per call)"} == {1, 10, 100}
    for r in quick_results["results"]:
        a = r["agreement"]
        assert a["n"] > 0 and a["differ_far_from_boundary"] == 0, r
        assert set(r["speedup"]) == set(r["ns_per_item"]) - {"ctxmodels"}
        for k, v in r["ns_per_item"].items():
            assert v > 0 and np.isfinite(v), (r["benchmark"], k)
            if k != "ctxmodels":
                assert r["speedup"][k] == pytest.approx(v / r["ns_per_item"]["ctxmodels"])
    sight = [r for r in quick_results["results"] if r["benchmark"].startswith("line_of_sight")]
    assert all(r["targets"]["shapely"] <= r["targets"]["ctxmodels"] for r in sight)


def test_numpy_radar_is_the_papers_radar(compare):
    """The NumPy formulation (squared ranges, squared dot product) against a plain one with
    square roots and angles, including the edges' owners and the sector's boundary."""
    sx, sy = compare.SENSOR
    heading = compare.HEADING
    rng = np.random.default_rng(0)
    bearing = rng.uniform(-np.pi, np.pi, 5000)
    r = np.concatenate([rng.uniform(0, 2000, 4990), [50.0, 1612.0, 49.9, 50.1, 1611.9, 1612.1, 0, 0, 0, 0]])
    # Exactly on the edges: place points so the computed range is the edge value.
    x = sx + r * np.cos(heading + bearing)
    y = sy + r * np.sin(heading + bearing)
    radar = compare.NumpyRadar(len(x))
    got = radar(x, y).copy()
    dist = np.hypot(x - sx, y - sy)
    body = np.angle(np.exp(1j * (np.arctan2(y - sy, x - sx) - heading)))
    blind = np.abs(np.angle(np.exp(1j * (body - np.pi)))) <= np.radians(65) / 2
    want = np.where((dist > 50) & (dist < 1612) & ~blind, 0.4, 0.0)
    near = radar.near_boundary(x, y)
    assert np.array_equal(got[~near], want[~near])
    assert 0 < (got > 0).sum() < len(x) and blind.sum() > 100
    # the plain Python function of the per-call benchmark: the same radar, point by point
    from stonesoup.types.hypothesis import SingleHypothesis
    from stonesoup.types.prediction import GaussianStatePrediction
    python_radar = compare.PythonRadar()
    scalar = np.array([python_radar(SingleHypothesis(GaussianStatePrediction(
        np.array([[a], [0.0], [b], [0.0]]), np.eye(4)), None)) for a, b in zip(x, y)])
    assert np.array_equal(scalar[~near], want[~near])


def test_agreement_check_catches_a_wrong_answer(compare):
    ring = compare.coastline(200, jagged=True)
    polygon = shapely.Polygon(ring)
    assert polygon.is_valid  # the jagged generator gives a simple polygon
    ours = np.array([True, False, True])
    check = compare.agreement(ours, np.array([True, True, True]), near=np.zeros(3, bool))
    assert check["differ_far_from_boundary"] == 1
    check = compare.agreement(ours, np.array([True, True, True]), near=np.array([False, True, False]))
    assert check["differ_far_from_boundary"] == 0 and check["differ"] == 1


def test_tracking_benchmark_times_a_gmphd_tracker_on_both_paths(tmp_path):
    """benches/bench_tracking.py with a GM-PHD tracker and repeats: both paths see every scan
    and report the same tracks; a bad tracker name is a usage error (no timing asserted)."""
    path = Path(__file__).resolve().parents[1] / "benches" / "bench_tracking.py"
    spec = importlib.util.spec_from_file_location("bench_tracking", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    out = tmp_path / "gmphd.json"
    assert module.main(["--tracker", "gmphd-context", "--duration", "5", "--repeats", "2",
                        "--json", str(out)]) == 0
    results = json.loads(out.read_text())
    assert results["array"]["scans"] == results["component"]["scans"] > 40
    assert results["array"]["tracks"] == results["component"]["tracks"]
    with pytest.raises(SystemExit) as exit_info:
        module.main(["--tracker", "no-such-tracker"])
    assert exit_info.value.code == 2
    # --models: per-scan vs per-detection model objects, both on the array path, same tracks
    out = tmp_path / "models.json"
    assert module.main(["--tracker", "gmphd-context", "--duration", "5", "--models",
                        "--json", str(out)]) == 0
    results = json.loads(out.read_text())
    shared, own = results["array"], results["per-detection models"]
    assert shared["scans"] == own["scans"] > 40 and shared["tracks"] == own["tracks"]
    assert own["component_scans"] == 0  # still the array path
    assert results["models_ratio"] > 0
