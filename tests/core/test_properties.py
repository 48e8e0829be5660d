"""Property tests: every array result of the Rust core held against an independent reference.

Each Hypothesis example draws a configuration (range bands, sectors, poses, rules, ...) and
a seed, then checks ≥ 10⁴ NumPy-generated points at once — big arrays per example keep the
example count, and the runtime, small. References: NumPy with arctan2 for range bands and
sectors, the closed-form Gaussian integral and Monte Carlo for expected P_D, NumPy for the
integration rules, clutter rules, navigation interpolation and mounting. Land and line of
sight are held against shapely in test_land.py.
"""
import datetime
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from numpy.polynomial.hermite_e import hermegauss

from ctxmodels import (AngularSector, ClutterDensityModel, DetectionProbabilityModel,
                       MetadataThreshold, Mounting, NavigationTrack, Pose, RangeBands,
                       SensorModel, _core, rule_points)


def examples(n: int) -> int:
    """`n` examples under the default profile, scaled with the loaded profile's budget."""
    return max(1, n * settings().max_examples // 100)


N_POINTS = 10_000
TWO_PI = 2 * math.pi
seeds = st.integers(0, 2**32 - 1)
unit = st.floats(0.0, 1.0)
angles = st.floats(-20.0, 20.0)
coords = st.floats(-1e4, 1e4)


# --- independent NumPy references ---------------------------------------------------------
def ref_bands(r, edges, values, upper_owns):
    """Band value by counting the edges a range has passed (r > e, or r == e when the
    upper band owns e)."""
    r = np.asarray(r, dtype=float)
    passed = np.zeros(r.shape, dtype=int)
    for e, upper in zip(edges, upper_owns):
        passed += (r > e) | ((r == e) & upper)
    return np.asarray(values, dtype=float)[passed]


def angle_off(bearing, centre):
    """|bearing - centre| wrapped to [0, π]."""
    return np.abs(np.remainder(np.asarray(bearing) - centre + np.pi, TWO_PI) - np.pi)


def ref_sector(dx, dy, heading, centre, width, inside, outside):
    off = angle_off(np.arctan2(dy, dx) - heading, centre)
    return np.where(off <= width / 2, inside, outside), np.abs(off - width / 2)


@st.composite
def band_specs(draw, max_edges=4, top=2000.0, probabilities=True):
    k = draw(st.integers(0, max_edges))
    edges = sorted(set(draw(st.lists(st.floats(0.0, top), min_size=k, max_size=k))))
    value = unit if probabilities else st.floats(1e-6, 10.0)
    values = draw(st.lists(value, min_size=len(edges) + 1, max_size=len(edges) + 1))
    owners = draw(st.lists(st.booleans(), min_size=len(edges), max_size=len(edges)))
    return tuple(edges), tuple(values), tuple(owners)


@st.composite
def sector_specs(draw):
    centre = draw(st.floats(-4 * math.pi, 4 * math.pi))
    width = draw(st.one_of(st.floats(1e-3, TWO_PI), st.sampled_from([TWO_PI, math.pi, 1.5 * math.pi,
                                                                      math.radians(65)])))
    return centre, width, draw(unit), draw(unit)


def positions_around(rng, sx, sy, scale, n=N_POINTS):
    """Points around the sensor on several scales, some exactly on the sensor's axes."""
    r = scale * rng.uniform(0, 1.3, n) ** 0.7
    t = rng.uniform(-np.pi, np.pi, n)
    xy = np.column_stack([sx + r * np.cos(t), sy + r * np.sin(t)])
    axis = rng.integers(0, 4, n // 10)
    xy[: n // 10] = np.column_stack([
        sx + np.where(axis == 0, r[: n // 10], np.where(axis == 1, -r[: n // 10], 0.0)),
        sy + np.where(axis == 2, r[: n // 10], np.where(axis == 3, -r[: n // 10], 0.0))])
    return xy


# --- range bands and sectors --------------------------------------------------------------
@settings(max_examples=examples(25))
@given(spec=band_specs(), seed=seeds)
def test_range_bands_match_reference_exactly_on_and_off_edges(spec, seed):
    edges, values, owners = spec
    rng = np.random.default_rng(seed)
    ranges = np.concatenate([rng.uniform(0, 2500, N_POINTS), np.asarray(edges, dtype=float),
                             np.nextafter(np.asarray(edges, dtype=float), -1),
                             np.nextafter(np.asarray(edges, dtype=float), np.inf), [0.0, 1e300]])
    expected = ref_bands(ranges, edges, values, owners)
    np.testing.assert_array_equal(RangeBands(edges=edges, values=values, upper_owns=owners)(ranges), expected)
    if all(owners) or not any(owners):  # one flag for all edges is the same as a per-edge list
        flag = RangeBands(edges=edges, values=values, upper_owns=bool(owners[0]) if owners else True)
        np.testing.assert_array_equal(flag(ranges), expected)


@settings(max_examples=examples(40))
@given(bands=st.lists(band_specs(), max_size=2), sectors=st.lists(sector_specs(), max_size=3),
       constant=st.one_of(st.none(), unit), x=coords, y=coords, heading=angles,
       ncols=st.integers(2, 6), data=st.data(), seed=seeds)
def test_detection_bands_times_sectors_match_numpy(bands, sectors, constant, x, y, heading,
                                                  ncols, data, seed):
    mapping = tuple(data.draw(st.permutations(range(ncols)))[:2])
    factors = [RangeBands(edges=e, values=v, upper_owns=o) for e, v, o in bands]
    factors += [AngularSector(centre=c, width=w, inside=i, outside=o) for c, w, i, o in sectors]
    if constant is not None:
        factors.append(constant)
    model = DetectionProbabilityModel(factors=factors)

    rng = np.random.default_rng(seed)
    xy = positions_around(rng, x, y, scale=max([2500.0] + [e[-1] * 1.2 for e, _, _ in bands if e]))
    states = rng.normal(0, 1e3, (N_POINTS, ncols))
    states[rng.random(states.shape) < 0.05] = np.nan  # only the position columns may matter
    states[:, mapping[0]], states[:, mapping[1]] = xy[:, 0], xy[:, 1]
    got = model.evaluate(Pose(x=x, y=y, heading=heading), states, mapping)

    # Reference: the same range formula (so band edges compare exactly), arctan2 bearings.
    dx, dy = xy[:, 0] - x, xy[:, 1] - y
    r = np.sqrt(dx * dx + dy * dy)
    expected = np.full(N_POINTS, 1.0 if constant is None else constant)
    comparable = r > 0
    for e, v, o in bands:
        expected *= ref_bands(r, e, v, o)
    for c, w, i, o in sectors:
        value, margin = ref_sector(dx, dy, heading, c, w, i, o)
        expected *= value
        comparable &= (margin > 1e-9) | (w >= TWO_PI)  # arctan2 and dot products round differently
    assert comparable.sum() > 0.85 * N_POINTS  # axis points sit on edges of right-angle sectors
    np.testing.assert_allclose(got[comparable], expected[comparable], rtol=1e-15, atol=0)
    assert np.all((got >= 0) & (got <= 1))


@pytest.mark.parametrize("centre, width", [(math.pi, math.radians(65)), (0.0, 0.1), (2.0, 5.0),
                                           (-1.0, TWO_PI)])
def test_sensor_position_itself_is_inside_every_sector(centre, width):
    """The one point without a bearing: the sector counts it as inside (documented)."""
    sector = AngularSector(centre=centre, width=width, inside=0.25, outside=0.5)
    model = DetectionProbabilityModel(factors=[sector])
    assert model.evaluate(Pose(x=3.0, y=-4.0, heading=1.0), np.array([[3.0, -4.0]]), (0, 1))[0] == 0.25


def test_full_circle_sector_is_inside_everywhere():
    rng = np.random.default_rng(3)
    xy = rng.normal(0, 100, (N_POINTS, 2))
    sector = AngularSector(centre=0.3, width=TWO_PI, inside=0.7, outside=0.1)
    model = DetectionProbabilityModel(factors=[sector])
    np.testing.assert_array_equal(model.evaluate(Pose(x=1.0, y=2.0, heading=-3.0), xy, (0, 1)), 0.7)


# --- expected P_D: integration rules -------------------------------------------------------
@pytest.mark.parametrize("order", range(1, 33))
def test_gauss_hermite_rule_is_the_tensor_of_hermegauss(order):
    points, weights = rule_points("gauss-hermite", order)
    x, w = hermegauss(order)
    w = w / w.sum()
    expected = {(a, b): wa * wb for a, wa in zip(x, w) for b, wb in zip(x, w)}
    assert len(points) == len(weights) == order**2
    got = sorted(zip(points, weights))
    want = sorted(expected.items())
    np.testing.assert_allclose([p for p, _ in got], [p for p, _ in want], atol=1e-12 * max(1, x.max()))
    np.testing.assert_allclose([w for _, w in got], [w for _, w in want], rtol=1e-9, atol=1e-15)
    assert math.isclose(sum(weights), 1.0, abs_tol=1e-13)


def test_cubature_unscented_and_mean_rules():
    s2, s3 = math.sqrt(2), math.sqrt(3)
    points, weights = rule_points("cubature")
    assert sorted(points) == sorted([(s2, 0.0), (-s2, 0.0), (0.0, s2), (0.0, -s2)])
    assert weights == [0.25] * 4
    points, weights = rule_points("unscented")
    assert sorted(zip(points, weights)) == sorted([((0.0, 0.0), 1 / 3)] + [
        (p, 1 / 6) for p in [(s3, 0.0), (-s3, 0.0), (0.0, s3), (0.0, -s3)]])
    assert rule_points("mean") == ([(0.0, 0.0)], [1.0])
    # Every rule reproduces the first two moments of the standard normal.
    for rule in ("cubature", "unscented", "gauss-hermite"):
        u, w = map(np.asarray, rule_points(rule, 4))
        np.testing.assert_allclose(w @ u, 0, atol=1e-14)
        np.testing.assert_allclose((u * w[:, None]).T @ u, np.eye(2), atol=1e-13)


def random_gaussians(rng, n, ncols, mapping, centre, spread):
    """Means near `centre` and covariances whose position blocks are full rank, rank one or
    zero (a point mass); the other blocks are arbitrary PSD."""
    means = rng.normal(0, 50, (n, ncols))
    means[:, mapping[0]] = centre[0] + rng.normal(0, spread, n)
    means[:, mapping[1]] = centre[1] + rng.normal(0, spread, n)
    a = rng.normal(0, 1, (n, ncols, ncols)) * rng.uniform(0.5, 30, (n, 1, 1))
    covars = a @ a.transpose(0, 2, 1)
    kind = rng.integers(0, 6, n)
    ix = np.ix_(mapping, mapping)
    for i in np.flatnonzero(kind == 0):  # rank-one position block
        v = rng.normal(0, 10, 2)
        block = np.outer(v, v)
        covars[i][ix] = block
    covars[kind == 1] = 0.0
    return means, covars


def numpy_rule_sum(model, pose, means, covars, mapping, rule, order):
    """E[P_D] re-implemented: the rule's points mapped through the Cholesky factor of each
    position block (closed form, as in the core), P_D at those points, weighted sum."""
    u, w = map(np.asarray, rule_points(rule, order))
    ix, iy = mapping
    a, b, c = covars[:, ix, ix], covars[:, ix, iy], covars[:, iy, iy]
    l11 = np.sqrt(np.maximum(a, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        l21 = np.where(l11 > 0, b / l11, 0.0)
    l22 = np.sqrt(np.maximum(c - l21 * l21, 0.0))
    mx, my = means[:, ix], means[:, iy]
    xs = mx[:, None] + l11[:, None] * u[None, :, 0]
    ys = my[:, None] + l21[:, None] * u[None, :, 0] + l22[:, None] * u[None, :, 1]
    pd = model.evaluate(pose, np.column_stack([xs.ravel(), ys.ravel()]), (0, 1)).reshape(xs.shape)
    return np.clip(pd @ w, 0.0, 1.0)


@settings(max_examples=examples(20))
@given(bands=band_specs(max_edges=3, top=300.0), sector=sector_specs(),
       rule=st.sampled_from(["mean", "cubature", "unscented", "gauss-hermite"]),
       order=st.integers(1, 12), ncols=st.integers(2, 6), data=st.data(), heading=angles, seed=seeds)
def test_expected_pd_equals_numpy_rule_sum(bands, sector, rule, order, ncols, data, heading, seed):
    mapping = tuple(data.draw(st.permutations(range(ncols)))[:2])
    model = DetectionProbabilityModel(factors=[
        RangeBands(edges=bands[0], values=bands[1], upper_owns=bands[2]),
        AngularSector(centre=sector[0], width=sector[1], inside=sector[2], outside=sector[3])])
    rng = np.random.default_rng(seed)
    n = max(N_POINTS // (order * order if rule == "gauss-hermite" else 5), 200)
    pose = Pose(x=rng.uniform(-100, 100), y=rng.uniform(-100, 100), heading=heading)
    means, covars = random_gaussians(rng, n, ncols, mapping, (pose.x, pose.y), 150.0)
    got = model.expected(pose, means, covars, mapping, rule, order)
    expected = numpy_rule_sum(model, pose, means, covars, mapping, rule, order)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)
    # A point mass is P_D at its mean under every rule.
    point_mass = np.all(covars == 0, axis=(1, 2))
    np.testing.assert_allclose(got[point_mass], model.evaluate(pose, means[point_mass], mapping), atol=1e-12)


def _worst_step_error(order):
    """sup_c |Σ_{x_i < c} w_i − Φ(c)| over the nodes of the 1-D rule: how badly it can
    integrate a unit step (the Chebyshev–Markov–Stieltjes bound)."""
    x, w = hermegauss(order)
    w = w / w.sum()
    cdf = np.array([0.5 * math.erfc(-v / math.sqrt(2)) for v in x])
    cumulative = np.concatenate([[0.0], np.cumsum(w)])
    return max(np.abs(cumulative[:-1] - cdf).max(), np.abs(cumulative[1:] - cdf).max())


@settings(max_examples=examples(10))
@given(order=st.integers(2, 32), my=st.floats(-40.0, 40.0), sx=st.floats(0.5, 30.0),
       sy=st.floats(0.5, 30.0), rho=st.floats(-0.95, 0.95), seed=seeds)
def test_expected_pd_of_a_half_plane_is_the_normal_cdf(order, my, sx, sy, rho, seed):
    """A sector of width π centred on +y (sensor at the origin, heading 0) is the half-plane
    y ≥ 0, so E[P_D] = Φ(m_y / σ_y) exactly. The Gauss–Hermite value must be the tensor
    rule from hermegauss (to 1e-12), within the rule's step-error bound of Φ, and the Monte
    Carlo estimate within 5 standard errors of Φ."""
    model = DetectionProbabilityModel(factors=[AngularSector(centre=math.pi / 2, width=math.pi,
                                                             inside=1.0, outside=0.0)])
    mean = np.array([[1e3, my]])  # far to the side of the apex: only the edge along +x matters
    cov = np.array([[sx * sx, rho * sx * sy], [rho * sx * sy, sy * sy]])
    pose = Pose(x=0.0, y=0.0, heading=0.0)
    got = model.expected(pose, mean, cov[None], (0, 1), "gauss-hermite", order)[0]
    exact = 0.5 * math.erfc(-my / sy / math.sqrt(2))
    # Tensor rule by hand: y = m_y + l21 u0 + l22 u1 ≥ 0.
    x, w = hermegauss(order)
    w = w / w.sum()
    l21, l22 = rho * sy, sy * math.sqrt(1 - rho * rho)
    node_y = my + l21 * x[:, None] + l22 * x[None, :]
    assume(np.abs(node_y).min() > 1e-6)  # on the edge itself the sector rounds (cos(π/2) ≠ 0)
    inside = node_y >= 0
    assert got == pytest.approx(float(np.sum(np.outer(w, w) * inside)), abs=1e-12)
    assert abs(got - exact) <= 2 * _worst_step_error(order) + 1e-12
    rng = np.random.default_rng(seed)
    samples = rng.multivariate_normal(mean[0], cov, 200_000)
    mc = model.evaluate(pose, samples, (0, 1))
    se = max(mc.std() / math.sqrt(len(mc)), 1e-4)
    assert abs(mc.mean() - exact) <= 5 * se


MODELS_FOR_MC = {
    "radar": [RangeBands(edges=(50, 1612), values=(0, 0.4, 0), upper_owns=(False, True)),
              AngularSector.blind(math.pi, math.radians(65))],
    "lidar": [RangeBands(edges=(50, 80), values=(0.95, 0.2, 0.0))],
    "sector": [0.9, AngularSector(centre=1.0, width=2.0, inside=0.3, outside=1.0)],
}


@settings(max_examples=examples(6))
@given(name=st.sampled_from(sorted(MODELS_FOR_MC)), heading=angles, seed=seeds)
def test_expected_pd_high_order_gauss_hermite_matches_monte_carlo(name, heading, seed):
    """GH32 against 10⁶ Monte Carlo samples (256 Gaussians × 4096) straddling the models'
    edges. Per Gaussian, the difference must lie within 5 MC standard errors plus the
    rule's worst-case error on the model's steps (loose: GH is no exact rule for steps).
    Over all Gaussians, the quadrature errors average out (GH integrates linear functions
    exactly, so shifting a step uniformly leaves no bias): the mean difference must be
    within 5 of its own standard errors — a sharp check of the Gaussian being integrated."""
    model = DetectionProbabilityModel(factors=MODELS_FOR_MC[name])
    rng = np.random.default_rng(seed)
    k, s = 256, 4096
    pose = Pose(x=rng.uniform(-50, 50), y=rng.uniform(-50, 50), heading=heading)
    r, t = rng.uniform(15, 120, k), rng.uniform(-np.pi, np.pi, k)
    means = np.zeros((k, 4))
    means[:, 0], means[:, 2] = pose.x + r * np.cos(t), pose.y + r * np.sin(t)
    means[:, 1], means[:, 3] = rng.normal(0, 5, k), rng.normal(0, 5, k)
    a = rng.normal(0, 1, (k, 2, 2))
    block = a @ a.transpose(0, 2, 1) * rng.uniform(5, 200, (k, 1, 1)) + np.eye(2)
    covars = np.tile(np.diag([1.0, 4.0, 1.0, 4.0]), (k, 1, 1))
    covars[:, 0::2, 0::2] = block
    gh = model.expected(pose, means, covars, (0, 2), "gauss-hermite", 32)

    z = np.einsum("kij,ksj->ksi", np.linalg.cholesky(block), rng.standard_normal((k, s, 2)))
    z += means[:, None, 0::2]
    pd = model.evaluate(pose, z.reshape(-1, 2), (0, 1)).reshape(k, s)
    mc, se = pd.mean(axis=1), pd.std(axis=1) / math.sqrt(s)
    jumps = {"radar": 0.4 * 4, "lidar": 0.75 + 0.2, "sector": 0.9 * 0.7 * 2}[name]
    assert np.all(np.abs(gh - mc) <= 5 * se + 2 * jumps * _worst_step_error(32) + 1e-12)
    diff = gh - mc
    assert abs(diff.mean()) <= 5 * diff.std() / math.sqrt(k) + 1e-4
    assert diff.std() > 0  # the Gaussians did straddle edges


def test_expected_pd_far_from_every_edge_is_exact():
    """A Gaussian whose mass (±8σ) lies inside one band has E[P_D] = that band's value."""
    model = DetectionProbabilityModel(factors=MODELS_FOR_MC["radar"])
    means = np.array([[500.0, 0, 0, 0], [0, 0, 700.0, 0]])
    covars = np.tile(np.diag([25.0, 1.0, 25.0, 1.0]), (2, 1, 1))
    for rule, order in [("cubature", 3), ("unscented", 3), ("gauss-hermite", 7), ("gauss-hermite", 32)]:
        got = model.expected(Pose(x=0.0, y=0.0, heading=0.0), means, covars, (0, 2), rule, order)
        np.testing.assert_allclose(got, 0.4, rtol=1e-14)


# --- clutter ------------------------------------------------------------------------------
KEYS = ("area", "snr", "points")


@st.composite
def clutter_rules(draw):
    key = draw(st.sampled_from(KEYS))
    threshold = draw(st.floats(-100, 100))
    missing = draw(st.one_of(st.none(), st.floats(1e-6, 10)))
    return MetadataThreshold(key=key, threshold=threshold, below=draw(st.floats(1e-6, 10)),
                             at_or_above=draw(st.floats(1e-6, 10)), missing=missing)


@settings(max_examples=examples(30))
@given(rules=st.lists(clutter_rules(), max_size=4),
       bands=st.lists(band_specs(probabilities=False), max_size=2),
       constants=st.lists(st.floats(1e-6, 10), max_size=2), x=coords, y=coords, heading=angles, seed=seeds)
def test_clutter_density_matches_numpy(rules, bands, constants, x, y, heading, seed):
    model = ClutterDensityModel(factors=[
        *rules, *[RangeBands(edges=e, values=v, upper_owns=o) for e, v, o in bands], *constants])
    keys = model.metadata_keys
    assert sorted(keys) == sorted({r.key for r in rules})
    rng = np.random.default_rng(seed)
    positions = positions_around(rng, x, y, 2500.0)
    metadata = rng.uniform(-120, 120, (N_POINTS, len(keys)))
    for k, key in enumerate(keys):
        thresholds = [r.threshold for r in rules if r.key == key]
        metadata[rng.random(N_POINTS) < 0.1, k] = rng.choice(thresholds)  # exactly on a threshold
        if all(r.missing is not None for r in rules if r.key == key):
            metadata[rng.random(N_POINTS) < 0.1, k] = np.nan
    got = model.evaluate(Pose(x=x, y=y, heading=heading), positions, metadata)

    dx, dy = positions[:, 0] - x, positions[:, 1] - y
    r = np.sqrt(dx * dx + dy * dy)
    expected = np.full(N_POINTS, float(math.prod(constants)))
    for e, v, o in bands:
        expected *= ref_bands(r, e, v, o)
    for rule in rules:
        column = metadata[:, keys.index(rule.key)]
        expected *= np.where(np.isnan(column), np.nan if rule.missing is None else rule.missing,
                             np.where(column < rule.threshold, rule.below, rule.at_or_above))
    np.testing.assert_allclose(got, expected, rtol=1e-13)
    assert np.all(got > 0)

    # The same through metadata mappings, where an absent key is "missing".
    rows = [{key: metadata[i, k] for k, key in enumerate(keys) if not np.isnan(metadata[i, k])}
            for i in range(500)]
    from_rows = model.evaluate(Pose(x=x, y=y, heading=heading), positions[:500], rows)
    np.testing.assert_array_equal(from_rows, got[:500])


# --- navigation track and mounting ----------------------------------------------------------
@settings(max_examples=examples(30))
@given(n=st.integers(1, 40), seed=seeds, data=st.data())
def test_navigation_track_interpolation_matches_numpy(n, seed, data):
    rng = np.random.default_rng(seed)
    t0 = datetime.datetime(2024, 1, 1) + datetime.timedelta(seconds=float(rng.uniform(0, 1e6)))
    gaps = rng.choice([0.001, 0.1, 1.25, 60.0], n - 1) * rng.uniform(1, 2, n - 1)
    seconds = np.concatenate([[0.0], np.cumsum(gaps)])
    timestamps = [t0 + datetime.timedelta(seconds=float(s)) for s in seconds]
    seconds = np.array([(t - t0).total_seconds() for t in timestamps])  # microsecond rounding
    positions = rng.normal(0, 1e3, (n, 2))
    # Headings hug ±π half the time, so many legs cross the wrap.
    headings = np.where(rng.random(n) < 0.5, rng.uniform(-np.pi, np.pi, n),
                        np.pi * rng.choice([-1, 1], n) + rng.normal(0, 0.3, n))
    turns = np.diff(headings)
    assume(np.all(np.abs(np.abs(np.remainder(turns + np.pi, TWO_PI) - np.pi) - np.pi) > 1e-6))
    track = NavigationTrack(timestamps=timestamps, positions=positions, headings=headings)

    queries = np.concatenate([rng.uniform(0, seconds[-1], 200), seconds])
    unwrapped = np.unwrap(headings)
    for q in queries:
        when = t0 + datetime.timedelta(seconds=float(q))
        q = (when - t0).total_seconds()
        pose = track.pose_at(when)
        np.testing.assert_allclose([pose.x, pose.y], [np.interp(q, seconds, positions[:, 0]),
                                                      np.interp(q, seconds, positions[:, 1])],
                                   rtol=1e-12, atol=1e-9)
        assert angle_off(pose.heading, np.interp(q, seconds, unwrapped)) < 1e-9
    with pytest.raises(ValueError, match="timestamp"):
        track.pose_at(t0 - datetime.timedelta(microseconds=1))
    with pytest.raises(ValueError, match="timestamp"):
        track.pose_at(timestamps[-1] + datetime.timedelta(microseconds=1))


def test_navigation_heading_takes_the_short_way_across_pi():
    t0 = datetime.datetime(2024, 1, 1)
    track = NavigationTrack(timestamps=[t0, t0 + datetime.timedelta(seconds=2)],
                            positions=[[0.0, 0.0], [2.0, -4.0]],
                            headings=[math.radians(179), math.radians(-179)])
    middle = track.pose_at(t0 + datetime.timedelta(seconds=1))
    assert (middle.x, middle.y) == (1.0, -2.0)
    assert abs(abs(middle.heading) - math.pi) < 1e-12
    quarter = track.pose_at(t0 + datetime.timedelta(seconds=0.5))
    assert quarter.heading == pytest.approx(math.radians(179.5), abs=1e-12)


@settings(max_examples=examples(30))
@given(x=coords, y=coords, heading=angles, forward=st.floats(-50, 50), left=st.floats(-50, 50),
       yaw=angles)
def test_mounting_matches_numpy_rotation(x, y, heading, forward, left, yaw):
    rotation = np.array([[math.cos(heading), -math.sin(heading)], [math.sin(heading), math.cos(heading)]])
    expected = np.array([x, y]) + rotation @ np.array([forward, left])
    sensor = Mounting(forward=forward, left=left, yaw=yaw).apply(Pose(x=x, y=y, heading=heading))
    np.testing.assert_allclose([sensor.x, sensor.y], expected, rtol=1e-12, atol=1e-9)
    assert angle_off(sensor.heading, heading + yaw) < 1e-12
    assert _core.mount((x, y, heading), forward, left, yaw) == (sensor.x, sensor.y, sensor.heading,
                                                                 0.0)
    model = SensorModel(detection=DetectionProbabilityModel(factors=[1.0]),
                        clutter=ClutterDensityModel(factors=[1.0]),
                        mounting=Mounting(forward=forward, left=left, yaw=yaw))
    assert model.context(Pose(x=x, y=y, heading=heading)).pose == sensor


# --- parallel path, out=, determinism -------------------------------------------------------
PARALLEL_N = 40_000  # above the core's threshold (32768 rows) for splitting rows over threads
RADAR = DetectionProbabilityModel(factors=MODELS_FOR_MC["radar"])


def _serial(evaluate, n, chunk=4096):
    """The same evaluation in slices below the parallel threshold."""
    return np.concatenate([evaluate(slice(i, min(i + chunk, n))) for i in range(0, n, chunk)])


def test_parallel_evaluate_equals_serial_rows():
    rng = np.random.default_rng(11)
    pose = Pose(x=10.0, y=-20.0, heading=2.0)
    states = np.zeros((PARALLEL_N, 4))
    states[:, 0::2] = positions_around(rng, 10.0, -20.0, 2000.0, PARALLEL_N)
    whole = RADAR.evaluate(pose, states)
    np.testing.assert_array_equal(whole, _serial(lambda s: RADAR.evaluate(pose, states[s]), PARALLEL_N))
    for i in rng.choice(PARALLEL_N, 300, replace=False):
        assert RADAR.evaluate(pose, states[i:i + 1])[0] == whole[i]
    assert set(np.unique(whole)) == {0.0, 0.4}


def test_parallel_expected_and_clutter_equal_serial():
    rng = np.random.default_rng(12)
    pose = Pose(x=0.0, y=0.0, heading=-1.0)
    means, covars = random_gaussians(rng, PARALLEL_N, 4, (0, 2), (0.0, 0.0), 800.0)
    whole = RADAR.expected(pose, means, covars, (0, 2), "unscented")
    np.testing.assert_array_equal(
        whole, _serial(lambda s: RADAR.expected(pose, means[s], covars[s], (0, 2), "unscented"), PARALLEL_N))
    clutter = ClutterDensityModel(factors=[
        RangeBands(edges=(1000,), values=(1e-3, 1e-2)),
        MetadataThreshold(key="area", threshold=10, below=1e-1, at_or_above=1e-3)])
    positions = means[:, 0::2]
    area = rng.uniform(0, 20, (PARALLEL_N, 1))
    whole = clutter.evaluate(pose, positions, area)
    serial = _serial(lambda s: clutter.evaluate(pose, positions[s], area[s]), PARALLEL_N)
    np.testing.assert_array_equal(whole, serial)


@pytest.mark.parametrize("n", [1, 1023, 1025, PARALLEL_N])
def test_out_buffer_is_filled_and_returned(n):
    rng = np.random.default_rng(n)
    pose = Pose(x=1.0, y=2.0, heading=0.5)
    states = np.zeros((n, 4))
    states[:, 0::2] = rng.normal(0, 800, (n, 2))
    expected = RADAR.evaluate(pose, states)
    out = np.full(n, np.nan)
    assert RADAR.evaluate(pose, states, out=out) is out
    np.testing.assert_array_equal(out, expected)
    covars = np.tile(np.eye(4) * 100, (n, 1, 1))
    out = np.full(n, np.nan)
    assert RADAR.expected(pose, states, covars, out=out) is out
    np.testing.assert_array_equal(out, RADAR.expected(pose, states, covars))
    clutter = ClutterDensityModel(factors=[RangeBands(edges=(1000,), values=(1e-3, 1e-2))])
    out = np.full(n, np.nan)
    assert clutter.evaluate(pose, states[:, 0::2], out=out) is out
    np.testing.assert_array_equal(out, clutter.evaluate(pose, states[:, 0::2]))
    # The raw core returns the caller's array too.
    out = np.full(n, np.nan)
    assert RADAR._compiled().evaluate(pose.as_tuple(), states, (0, 2), out) is out
    np.testing.assert_array_equal(out, expected)


def test_repeated_calls_are_bitwise_identical():
    rng = np.random.default_rng(13)
    pose = Pose(x=-5.0, y=5.0, heading=3.0)
    means, covars = random_gaussians(rng, PARALLEL_N, 4, (0, 2), (0.0, 0.0), 1000.0)
    first_pd = RADAR.evaluate(pose, means)
    first_e = RADAR.expected(pose, means, covars, (0, 2), "gauss-hermite", 4)
    for _ in range(4):
        np.testing.assert_array_equal(RADAR.evaluate(pose, means), first_pd)
        again = RADAR.expected(pose, means, covars, (0, 2), "gauss-hermite", 4)
        np.testing.assert_array_equal(again, first_e)
