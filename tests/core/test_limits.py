"""Hardening III, the Rust core: user-sized allocations fail as MemoryError (never an
abort), non-finite positions and negative ranges are refused naming the argument, a
subnormal clutter product is refused like an overflowing one, a trial of weight 0 is no
evidence, and the learned state stays finite at the edges of the accepted parameters."""
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from ctxmodels import (ClutterDensityModel, ClutterMap, CoastalClutter, DetectionEstimate,
                       LandMask, Pose)

POSE = Pose(x=0.0, y=0.0, heading=0.0)


def names_argument(call, exception, argument):
    with pytest.raises(exception) as info:
        call()
    assert str(info.value).startswith(f"{argument}:"), str(info.value)
    return info.value


def run_limited(body: str) -> subprocess.CompletedProcess:
    """Runs `body` in a child whose address space is limited to about 1.5 GB (set after the
    imports), printing the name and message of what it raises."""
    script = textwrap.dedent("""
        import resource
        import numpy as np
        import ctxmodels
        resource.setrlimit(resource.RLIMIT_AS, (1_500_000_000, 1_500_000_000))
        try:
        {body}
        except BaseException as err:
            print(type(err).__name__, err, flush=True)
        else:
            print("no error", flush=True)
        """).format(body=textwrap.indent(textwrap.dedent(body), "    "))
    return subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=300)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="RLIMIT_AS is Linux's")
@pytest.mark.parametrize("edges", [6001, 8001])
def test_a_grid_too_large_for_memory_is_a_memory_error_not_an_abort(edges):
    # 6000² cells aborted the process ("memory allocation of 288000000 bytes failed"); it
    # now fits in 1.5 GB (three grids of 288 MB), or fails as a MemoryError. 8000² cells
    # (three grids of 512 MB) cannot fit.
    done = run_limited(f"""
        ctxmodels.ClutterMap(space="world-xy", edges=(np.linspace(0, 6000, {edges}),) * 2,
                             prior_intensity=1e-3, pooling="grid", pooling_scans=None)
    """)
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    if edges == 6001 and done.stdout == "no error\n":
        return
    assert done.stdout.startswith("MemoryError edges: needs "), done.stdout + done.stderr[-2000:]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="RLIMIT_AS is Linux's")
def test_a_land_mask_too_large_for_memory_is_a_memory_error_not_an_abort():
    # 20 million vertices (320 MB as an array): the mask's edges, trees and index need
    # several times that in Rust
    done = run_limited("""
        angles = np.linspace(0.0, 2.0 * np.pi, 20_000_000, endpoint=False)
        ring = np.column_stack([np.cos(angles), np.sin(angles)]) * 1e5
        del angles
        ctxmodels.LandMask(polygons=[ring])
    """)
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    # (raised by the Rust core, naming the argument: not by NumPy on the Python side)
    assert done.stdout.startswith("MemoryError polygons: needs "), done.stdout + done.stderr[-2000:]


def test_a_zero_weight_hit_is_no_evidence():
    estimate = DetectionEstimate(edges=[0, 10], prior_probability=0.5)
    estimate.update((0, 0, 0), [[5, 0]], [1], [0.0])
    assert estimate.probabilities()[0] == 0.5
    for _ in range(10):
        estimate.update((0, 0, 0), [[5, 0]], [1], [0.0])
    assert estimate.probabilities()[0] == 0.5
    assert estimate.hits[0] == 0.0 and estimate.trials[0] == 0.0
    # a trial with weight counts its hit, as before
    estimate.update((0, 0, 0), [[5, 0]], [1], [1.0])
    assert estimate.probabilities()[0] == (0.5 * 5 + 1) / (5 + 1)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_a_map_refuses_a_position_that_is_not_finite(bad):
    learned = ClutterMap(space="world-xy", edges=([0, 1], [0, 1]), prior_intensity=1.0)
    err = names_argument(lambda: learned.intensity((0, 0, 0), [[0.5, 0.5], [bad, 0.5]]),
                         ValueError, "positions")
    assert "row 1" in str(err)
    names_argument(lambda: learned.intensity((0, 0, 0), [[0.5, 0.5]], ranges=[-1.0]),
                   ValueError, "ranges")
    assert learned.intensity((0, 0, 0), [[0.5, 0.5]], ranges=[np.nan]) == [1.0]


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_the_coast_refuses_a_position_that_is_not_finite(bad):
    square = np.array([[1000.0, -50.0], [1100.0, -50.0], [1100.0, 50.0], [1000.0, 50.0]])
    coast = CoastalClutter(land=LandMask(polygons=[square]), width=20.0, inside=7.0)
    assert list(coast.evaluate(POSE, [[980.0, 0.0]])) == [7.0]
    err = names_argument(lambda: coast.evaluate(POSE, [[980.0, 0.0], [bad, 0.0]]), ValueError,
                         "positions")
    assert "row 1" in str(err)


def test_a_negative_measured_range_is_refused():
    from ctxmodels import RangeBands
    model = ClutterDensityModel(factors=[RangeBands(edges=[500.0], values=[1e-3, 1e-2])])
    assert model.evaluate(POSE, [[600.0, 0.0]], ranges=[np.nan])[0] == 1e-2
    err = names_argument(lambda: model.evaluate(POSE, [[600.0, 0.0]], ranges=[-1.0]),
                         ValueError, "ranges")
    assert "row 0" in str(err)


def test_a_clutter_product_that_underflows_to_a_subnormal_is_refused():
    model = ClutterDensityModel(factors=[1e-160, 1e-160])
    names_argument(lambda: model.evaluate(POSE, np.zeros((1, 2))), ValueError, "factors")
    # a subnormal factor on its own is refused when the model is built
    names_argument(lambda: ClutterDensityModel(factors=[1e-320]).evaluate(POSE, np.zeros((1, 2))),
                   ValueError, "factors")
    assert ClutterDensityModel(factors=[1e-150, 1e-150]).evaluate(POSE, np.zeros((1, 2)))[0] > 0


@pytest.mark.parametrize("settings, updates", [
    (dict(forgetting=1e-150), 6),
    (dict(forgetting=5e-324), 3),
    (dict(prior_intensity=1e300, prior_scans=1e10), 3),
    (dict(prior_scans=1e308, pooling="grid"), 3),
    (dict(prior_scans=1e308, pooling="grid", pooling_scans=None), 3),
    (dict(prior_intensity=2.5e-308, prior_scans=1e-300, forgetting=1.0), 3),
])
def test_the_learned_map_stays_finite_at_the_edges_of_its_parameters(settings, updates):
    settings = dict(dict(space="world-xy", edges=([0, 10, 20], [0, 10]), prior_intensity=1e-3),
                    **settings)
    learned = ClutterMap(**settings)
    for k in range(updates):
        points = [[5.0, 5.0]] * (k % 2) + [[15.0, 5.0]] * k
        learned.update((0, 0, 0), np.array(points).reshape(-1, 2))
        grid = learned.intensity_grid()
        assert np.all(np.isfinite(grid)) and np.all(grid >= np.finfo(float).tiny), grid
        assert np.all(np.isfinite(learned.counts)) and np.all(np.isfinite(learned.deficit))
        assert np.isfinite(learned.exposure) and 0 < learned.scale < np.inf
    # and its state restores to the same map, bit for bit
    restored = ClutterMap(**settings, counts=learned.counts, deficit=learned.deficit,
                          exposure=learned.exposure, scale=learned.scale)
    assert restored.intensity_grid().tobytes() == learned.intensity_grid().tobytes()


def test_a_prior_intensity_below_the_normal_doubles_is_refused():
    names_argument(lambda: ClutterMap(space="world-xy", edges=([0, 1], [0, 1]),
                                      prior_intensity=1e-310), ValueError, "prior_intensity")


def test_a_grid_too_large_for_the_pools_sums_is_refused():
    names_argument(lambda: ClutterMap(space="world-xy", edges=([0, 1e150], [0, 1e150]),
                                      prior_intensity=1.0), ValueError, "edges")
