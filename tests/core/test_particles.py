"""``DetectorContext.prob_detection_particles``: P_D, log P_D and log(1 - P_D) at (D, N)
particle columns read in place, held bit for bit against the row path it replaces in the
particle updaters, ``np.log(context.prob_detection_array(particles.T))``."""
from __future__ import annotations

import math

import numpy as np
import pytest
from stonesoup.types.array import StateVectors

from ctxmodels import (AngularSector, ClutterDensityModel, DetectionProbabilityModel, LandMask,
                       LineOfSight, Pose, RangeBands, SensorModel)

ISLAND = np.array([[300.0, -200.0], [600.0, -200.0], [600.0, 200.0], [300.0, 200.0]])
LAND = LandMask(polygons=[ISLAND])


def context(factors, position_mapping=(0, 2), pose=(-20.0, 15.0, 0.4)):
    model = SensorModel(detection=DetectionProbabilityModel(factors=factors),
                        clutter=ClutterDensityModel(factors=[1e-3]),
                        position_mapping=position_mapping)
    return model.context(Pose(*pose))


#: name -> (factors, whether P_D is 0 somewhere among the particles)
MODELS = {
    "radar": ([RangeBands(edges=(50, 1612), values=(0, 0.4, 0), upper_owns=(False, True)),
               AngularSector.blind(math.pi, math.radians(65))], True),
    "lidar": ([RangeBands(edges=(50, 80), values=(0.95, 0.2, 0.0))], True),
    "island": ([0.9, LAND, LineOfSight(land=LAND)], True),
    # NumPy's AVX-512 log and libm's log disagree in the last bit at 0.917 and 1 - 0.917.
    "constant 0.917": ([0.917], False),
    "certain": ([1.0], False),  # log(1 - P_D) = -inf everywhere
    "blind": ([0.0], True),
    # 20 range bands x 15 disjoint sectors (and outside them): 320 distinct products, past
    # the core's 256-value table, so NumPy takes the log of every value.
    "many values": ([RangeBands(edges=tuple(np.linspace(10, 1200, 19)),
                                values=tuple(np.linspace(0.3, 0.99, 20)))]
                    + [AngularSector(centre=math.radians(-170 + 24 * i), width=math.radians(20),
                                     inside=0.5 + 0.03 * i, outside=1.0) for i in range(15)],
                    False),
}


def particles(n=3000, ndim=4, seed=0):
    rng = np.random.default_rng(seed)
    return StateVectors(rng.uniform(-1200, 1200, (ndim, n)))


def reference(ctx, columns):
    """The row path the updaters used: P_D of the transposed particles, NumPy's log."""
    pd = ctx.prob_detection_array(np.asarray(columns, dtype=np.float64).T)
    with np.errstate(divide="ignore"):
        return pd, np.log(pd), np.log(1 - pd)


def assert_bits(got, want):
    assert got.dtype == np.float64 and got.shape == want.shape
    assert got.tobytes() == want.tobytes()


@pytest.mark.parametrize("name", MODELS)
@pytest.mark.parametrize("n", [1, 3000, 70_001], ids=["1", "3000", "70001"])
def test_matches_the_row_path_and_numpys_log_bit_for_bit(name, n):
    factors, has_zero = MODELS[name]
    ctx = context(factors)
    columns = particles(n)
    pd, log_pd, log_missed = reference(ctx, columns)
    with np.errstate(all="raise"):  # log 0 must not warn
        assert_bits(ctx.prob_detection_particles(columns), pd)
        assert_bits(ctx.prob_detection_particles(columns, log=True), log_pd)
        both = ctx.prob_detection_particles(columns, log=True, missed=True)
        plain = ctx.prob_detection_particles(columns, missed=True)
    assert isinstance(both, tuple) and len(both) == 2
    assert_bits(both[0], log_pd)
    assert_bits(both[1], log_missed)
    assert_bits(plain[0], pd)
    assert_bits(plain[1], 1 - pd)
    if n > 1 and has_zero:
        assert np.isneginf(log_pd).any() and np.isfinite(log_pd).any() or name == "blind"
        assert np.all(np.isneginf(log_pd) == (pd == 0))
    if name == "many values" and n > 1:
        assert len(np.unique(pd)) > 256


def test_a_six_dimensional_state_with_its_own_position_rows():
    ctx = context(MODELS["radar"][0], position_mapping=(3, 1))
    columns = particles(5000, ndim=6)
    pd, log_pd, _ = reference(ctx, columns)
    assert_bits(ctx.prob_detection_particles(columns, log=True), log_pd)
    assert (pd == 0.4).any() and (pd == 0).any()
    # Rows (0, 2) would be a different answer: the mapping is read.
    other = context(MODELS["radar"][0], position_mapping=(0, 2))
    assert not np.array_equal(other.prob_detection_particles(columns), pd)


def layouts(columns):
    """The same (D, N) values in the layouts Stone Soup and callers produce."""
    base = np.asarray(columns, dtype=np.float64)
    unaligned = np.frombuffer(b"\0" + base.tobytes(), dtype=np.float64, offset=1).reshape(base.shape)
    wide = np.zeros((base.shape[0], 2 * base.shape[1]))
    wide[:, ::2] = base
    return {
        "C": base,
        "StateVectors": StateVectors(base),
        # What resampling gives: state_vector[:, indices] is Fortran-ordered.
        "Fortran (resampled)": StateVectors(base)[:, np.arange(base.shape[1])],
        "Fortran": np.asfortranarray(base),
        "strided view": wide[:, ::2],
        "reversed": base[:, ::-1][:, ::-1],
        "float32 values": base.astype(np.float32).astype(np.float64),
        "unaligned": unaligned,
        "list": base.tolist(),
    }


@pytest.mark.parametrize("layout", list(layouts(particles(4))))
def test_every_layout_gives_the_same_bits(layout):
    ctx = context(MODELS["radar"][0])
    columns = particles(2000)
    given = layouts(columns)[layout]
    _, log_pd, log_missed = reference(ctx, columns)
    got = ctx.prob_detection_particles(given, log=True, missed=True)
    assert_bits(got[0], log_pd)
    assert_bits(got[1], log_missed)
    if layout == "Fortran (resampled)":
        assert given.flags.f_contiguous and not given.flags.c_contiguous


def test_float32_particles_are_read_as_their_float64_values():
    ctx = context(MODELS["lidar"][0])
    columns = np.asarray(particles(2000), dtype=np.float32) / 10
    _, log_pd, _ = reference(ctx, columns.astype(np.float64))
    assert_bits(ctx.prob_detection_particles(columns, log=True), log_pd)
    assert_bits(ctx.prob_detection_particles(np.asfortranarray(columns), log=True), log_pd)


def test_no_particles():
    ctx = context(MODELS["radar"][0])
    empty = np.empty((4, 0))
    assert ctx.prob_detection_particles(empty, log=True).shape == (0,)
    log_pd, log_missed = ctx.prob_detection_particles(empty, log=True, missed=True)
    assert log_pd.shape == log_missed.shape == (0,)


@pytest.mark.parametrize("bad, message", [
    (np.zeros(4), "particles: must be a \\(D, N\\) array"),
    (np.zeros((4, 3, 2)), "particles: must be a \\(D, N\\) array"),
    (np.zeros((2, 10)), "particles: has 2 rows"),  # position_mapping (0, 2) reads row 2
    (np.zeros((0, 10)), "particles: has 0 rows"),
])
def test_wrong_shapes_name_particles(bad, message):
    ctx = context(MODELS["radar"][0])
    with pytest.raises(ValueError, match=message):
        ctx.prob_detection_particles(bad)
    with pytest.raises(ValueError, match=message):
        ctx.prob_detection_particles(bad, log=True, missed=True)


@pytest.mark.parametrize("row, value", [(0, np.nan), (2, np.inf), (2, -np.inf)])
@pytest.mark.parametrize("order", ["C", "F"])
def test_non_finite_positions_are_rejected_like_the_row_path(row, value, order):
    ctx = context(MODELS["radar"][0])
    columns = np.array(particles(50_000), order=order)
    columns[row, 41_234] = value
    columns[row, 45_000] = value
    with pytest.raises(ValueError, match="means: row 41234 is not finite"):
        ctx.prob_detection_array(columns.T)  # the path it replaces rejects it too
    with pytest.raises(ValueError, match=r"particles: particle 41234 \(column 41234\) has a NaN"):
        ctx.prob_detection_particles(columns, log=True)


def test_non_finite_velocities_are_not_read():
    ctx = context(MODELS["radar"][0])
    columns = np.array(particles(100))
    columns[1, 7] = np.nan
    columns[3, 9] = np.inf
    pd, log_pd, _ = reference(ctx, columns)
    assert_bits(ctx.prob_detection_particles(columns, log=True), log_pd)


@pytest.mark.parametrize("bad, error", [
    (np.array([["a", "b"], ["c", "d"], ["e", "f"]]), TypeError),
    (np.zeros((4, 3), dtype=complex), TypeError),
])
def test_non_numeric_particles_name_the_argument(bad, error):
    with pytest.raises(error, match="particles"):
        context(MODELS["radar"][0]).prob_detection_particles(bad)


def test_the_binding_rejects_what_the_python_layer_would_convert():
    """The core binding reads memory as given: a non-contiguous view must be refused by it
    (the Python layer copies such views first), never read as if it were contiguous."""
    ctx = context(MODELS["radar"][0])
    compiled = ctx.sensor_model.detection._compiled()
    columns = np.asarray(particles(100))
    with pytest.raises(ValueError, match="particles: must be C- or Fortran-contiguous"):
        compiled.evaluate_particles(ctx.pose.as_tuple(), columns[:, ::2])
    with pytest.raises(ValueError, match="position_mapping"):
        compiled.evaluate_particles(ctx.pose.as_tuple(), columns, (0, 0))
    got = compiled.evaluate_particles(ctx.pose.as_tuple(), np.asfortranarray(columns), (0, 2), True)
    assert_bits(got, reference(ctx, columns)[1])
