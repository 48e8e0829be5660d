"""The array kernels' two builds (AVX2, chosen at run time, and portable) give the same
bits: the same evaluations run in a process on the CPU's build and in one forced onto the
portable build (``CTXMODELS_SIMD=portable``), and their outputs are compared byte for byte.
(On a CPU without AVX2 both processes run the portable build; the Rust tests compare the
builds lane by lane where AVX2 exists.)"""
import json
import os
import platform
import subprocess
import sys

import pytest

import ctxmodels._core as core

SCRIPT = r'''
import hashlib, json, math
import numpy as np
import ctxmodels._core as core
from ctxmodels import (AngularSector, ClutterDensityModel, DetectionProbabilityModel,
                       ElevationSector, LandMask, LineOfSight, MetadataThreshold, RadarHorizon,
                       RangeBands, SensorModel)

rng = np.random.default_rng(20261123)
island = [[300.0, -200.0], [600.0, -200.0], [600.0, 200.0], [300.0, 200.0]]
land = LandMask(polygons=[island])
models = {
    "radar": [RangeBands(edges=(50.0, 1612.0), values=(0.0, 0.4, 0.0), upper_owns=(False, True)),
              AngularSector.blind(math.pi, math.radians(65))],
    "wide_and_many_bands": [0.9, AngularSector(centre=1.0, width=math.radians(300), inside=0.7,
                                               outside=0.1),
                            RangeBands(edges=(100, 200, 300, 400, 500, 600),
                                       values=(0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3))],
    "land_and_sight": [0.9, land, RangeBands(edges=(700.0,), values=(0.93, 0.11)),
                       LineOfSight(land=land)],
}
n = 40_003  # above the parallel threshold, with a ragged last block
states = rng.uniform(-1800, 1800, size=(n, 4))
states[:300, 0] = 50.0  # exactly on the radar's first edge
states[:300, 2] = 0.0
wide = rng.uniform(-1800, 1800, size=(n, 6))
covars = np.zeros((n, 4, 4))
sx, sy, rho = rng.uniform(1, 80, n), rng.uniform(1, 80, n), rng.uniform(-0.9, 0.9, n)
covars[:, 0, 0], covars[:, 2, 2] = sx * sx, sy * sy
covars[:, 0, 2] = covars[:, 2, 0] = rho * sx * sy
digests = {"backend": core.simd_backend()}
for name, factors in models.items():
    detection = DetectionProbabilityModel(factors=factors)
    for rule in ("mean", "cubature", "gauss-hermite"):
        sensor = SensorModel(detection=detection, clutter=ClutterDensityModel(factors=[1e-3]),
                             pd_evaluation=rule)
        context = sensor.context((1.0, 2.0, 0.3))
        values = [context.prob_detection_array(states), context.prob_detection_array(states, covars),
                  context.prob_detection_particles(states.T.copy()),
                  detection.evaluate(context.pose, wide, (4, 1))]
        digests[f"{name}/{rule}"] = hashlib.sha256(b"".join(v.tobytes() for v in values)).hexdigest()
# states with heights: slant range, an elevation beam, the horizon at each target's height
spatial = DetectionProbabilityModel(factors=[
    0.9, RangeBands(edges=(700.0,), values=(0.93, 0.11)), ElevationSector(lower=-0.05, upper=0.5),
    RadarHorizon(antenna_height=30.0, target_height=None, earth_radius=20_000.0),
    AngularSector.blind(math.pi, 1.0), land, LineOfSight(land=land)])
states3 = rng.uniform(-1800, 1800, size=(n, 6))
states3[:, 4] = rng.uniform(-100, 900, n)
covars3 = np.zeros((n, 6, 6))
covars3[:, [0, 2, 4], [0, 2, 4]] = rng.uniform(1, 80, (n, 3)) ** 2
for rule in ("mean", "cubature", "gauss-hermite"):
    sensor = SensorModel(detection=spatial, clutter=ClutterDensityModel(factors=[1e-3]),
                         position_mapping=(0, 2, 4), pd_evaluation=rule)
    context = sensor.context((1.0, 2.0, 0.3, 25.0))
    values = [context.prob_detection_array(states3), context.prob_detection_array(states3, covars3),
              context.prob_detection_particles(states3.T.copy())]
    digests[f"3d/{rule}"] = hashlib.sha256(b"".join(v.tobytes() for v in values)).hexdigest()
clutter = ClutterDensityModel(factors=[
    0.7, RangeBands(edges=(100.0, 1000.0), values=(1e-3, 1e-2, 3e-2), upper_owns=(True, False)),
    MetadataThreshold(key="area", threshold=10.0, below=1e-1, at_or_above=1e-3, missing=1e-2)])
context = SensorModel(detection=DetectionProbabilityModel(factors=[0.9]), clutter=clutter).context(
    (1.0, 2.0, 0.3))
positions = rng.uniform(-2500, 2500, (n, 2))
area = rng.uniform(0, 40, (n, 1))
area[rng.random(n) < 0.1] = np.nan
ranges = np.where(rng.random(n) < 0.3, 1000.0, np.nan)
values = [context.clutter_spatial_density_array(positions, area),
          context.clutter_spatial_density_array(positions, area, ranges=ranges)]
digests["clutter"] = hashlib.sha256(b"".join(v.tobytes() for v in values)).hexdigest()

# Bad input: the same error (argument, row, reason) from every build.
radar = SensorModel(detection=DetectionProbabilityModel(factors=models["radar"]),
                    clutter=clutter, pd_evaluation="cubature").context((1.0, 2.0, 0.3))
def error(call):
    try:
        call()
    except ValueError as e:
        return str(e)
    return None
nan_row = states.copy(); nan_row[33_333, 2] = np.nan; nan_row[39_000, 0] = np.inf
skew = covars.copy(); skew[1_234, 0, 2] += 10.0
inf_area = area.copy(); inf_area[20_001, 0] = np.inf
digests["errors"] = [
    error(lambda: radar.prob_detection_array(nan_row)),
    error(lambda: radar.prob_detection_array(nan_row, covars)),
    error(lambda: radar.prob_detection_array(states, skew)),
    error(lambda: radar.prob_detection_particles(nan_row.T.copy())),
    error(lambda: context.clutter_spatial_density_array(positions, inf_area)),
]
print(json.dumps(digests))
'''


def _digests(**env):
    environment = {**os.environ, **env}
    result = subprocess.run([sys.executable, "-c", SCRIPT], env=environment, capture_output=True,
                            text=True, timeout=300, check=True)
    return json.loads(result.stdout)


def _cpu_has_avx2() -> bool | None:
    """From /proc/cpuinfo (Linux); None where that cannot be read."""
    try:
        with open("/proc/cpuinfo") as f:
            return any(line.startswith("flags") and " avx2" in line for line in f)
    except OSError:
        return None


def test_portable_build_gives_the_bits_of_the_dispatched_one():
    portable = _digests(CTXMODELS_SIMD="portable")
    dispatched = _digests(CTXMODELS_SIMD="")
    assert portable.pop("backend") == "portable"
    backend = dispatched.pop("backend")
    if platform.machine() in ("x86_64", "AMD64") and _cpu_has_avx2():
        assert backend == "avx2"  # else this test would compare the portable build with itself
    assert len(portable) == 14
    # every error names its argument and the first bad row
    assert [e.split(":")[0] for e in portable["errors"]] == [
        "means", "means", "covars", "particles", "metadata"], portable["errors"]
    assert "33333" in portable["errors"][0] and "1234" in portable["errors"][2]
    assert dispatched == portable


@pytest.mark.parametrize("value", ["portable", "PORTABLE"])
def test_the_environment_forces_the_portable_build(value):
    result = subprocess.run(
        [sys.executable, "-c", "import ctxmodels._core as c; print(c.simd_backend())"],
        env={**os.environ, "CTXMODELS_SIMD": value}, capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "portable"
    assert core.simd_backend() in ("avx2", "portable")
