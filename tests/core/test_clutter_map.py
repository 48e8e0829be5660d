"""The learned clutter map (``ClutterMap``): the Rust estimator against an independent NumPy
one (every cell discounted every scan, no running scale), convergence to a known
stationary clutter field, composition with the other clutter factors and a detector
context, named errors, exact pickle/YAML round trips that continue identically."""
import math
import pickle

import numpy as np
import pytest
from stonesoup.serialise import YAML

from ctxmodels import ClutterDensityModel, ClutterMap, Pose, RangeBands, SensorModel
from ctxmodels import DetectionProbabilityModel

BEARINGS = np.linspace(-math.pi, math.pi, 13)
RANGES = np.array([0.0, 200.0, 600.0, 1000.0, 1600.0])


class ReferenceMap:
    """The estimator as its formula reads: N ← γN + n, S ← γS + 1, D ← γD + min(1, gated
    fraction) over every cell; λ = (λ0 s0 + N/V) / (s0 + S − D). Pooled, the prior of a
    cell is its pool's (λ0 s0 V_g + ΣN) / (s0 V_g + ΣV(S − D)), with weight s_p — or, with
    s_p None, λ_g / (τ² V) from the pool's spread τ², with the discounted sum of squared
    scan weights kept as S2 ← γ² S2 + 1, the level and spread over the cells whose counts
    the pool explains, and the others estimated alone."""

    def __init__(self, space, edges, prior, prior_scans, forgetting, pooling="none",
                 pooling_scans=10.0):
        self.space, self.edges = space, [np.asarray(e, float) for e in edges]
        self.prior, self.s0, self.gamma = prior, prior_scans, forgetting
        self.pooling, self.sp = pooling, pooling_scans
        self.volumes = np.outer(np.diff(self.edges[0]), np.diff(self.edges[1]))
        self.counts, self.exposure = np.zeros(self.volumes.shape), 0.0
        self.deficit = np.zeros(self.volumes.shape)
        self.squares = 0.0

    def coordinates(self, pose, positions, ranges):
        x, y, heading = pose
        d = np.asarray(positions, float) - [x, y]
        if self.space == "world-xy":
            return np.asarray(positions, float).T
        if self.space == "body-xy":
            c, s = math.cos(heading), math.sin(heading)
            return np.array([c * d[:, 0] + s * d[:, 1], c * d[:, 1] - s * d[:, 0]])
        bearing = np.arctan2(d[:, 1], d[:, 0]) - heading
        bearing = np.where(bearing >= math.pi, bearing - 2 * math.pi,
                           np.where(bearing < -math.pi, bearing + 2 * math.pi, bearing))
        rng = np.hypot(d[:, 0], d[:, 1])
        if ranges is not None:
            rng = np.where(np.isnan(ranges), rng, ranges)
        return np.array([bearing, rng])

    def cells(self, pose, positions, ranges=None):
        u, v = self.coordinates(pose, positions, ranges)
        i = np.searchsorted(self.edges[0], u, side="right") - 1
        j = np.searchsorted(self.edges[1], v, side="right") - 1
        inside = (u >= self.edges[0][0]) & (u < self.edges[0][-1]) & \
                 (v >= self.edges[1][0]) & (v < self.edges[1][-1])
        return i, j, inside

    def update(self, pose, positions, ranges=None, gates=np.empty((0, 3)), weights=None):
        positions = np.asarray(positions, float).reshape(-1, 2)
        gates = np.asarray(gates, float).reshape(-1, 3)
        weights = np.ones(len(positions)) if weights is None else np.asarray(weights, float)
        free = np.ones(len(positions), bool)
        for gx, gy, r in gates:
            free &= (positions[:, 0] - gx) ** 2 + (positions[:, 1] - gy) ** 2 > r * r
        n = np.zeros_like(self.counts)
        if free.any():
            i, j, inside = self.cells(pose, positions[free], None if ranges is None else ranges[free])
            np.add.at(n, (i[inside], j[inside]), weights[free][inside])
        fraction = np.zeros_like(self.counts)
        if len(gates):
            i, j, inside = self.cells(pose, gates[:, :2])
            centre_range = np.hypot(*(gates[:, :2] - pose[:2]).T)
            area = np.pi * gates[:, 2] ** 2
            if self.space == "bearing-range":
                area = area / np.maximum(centre_range, gates[:, 2])
            for a, b, k, g in zip(i, j, inside, area):
                if k:
                    fraction[a, b] += g / self.volumes[a, b]
        self.counts = self.gamma * self.counts + n
        self.deficit = self.gamma * self.deficit + np.minimum(fraction, 1.0)
        self.exposure = self.gamma * self.exposure + 1.0
        self.squares = self.gamma ** 2 * self.squares + 1.0

    def grid(self):
        if self.pooling == "none":
            return (self.prior * self.s0 + self.counts / self.volumes) / \
                (self.s0 + self.exposure - self.deficit)
        axis = 0 if self.pooling == "range" else None  # rings: every bearing (axis 0)
        volume = self.volumes.sum(axis=axis, keepdims=True)
        exposed = (self.volumes * (self.exposure - self.deficit)).sum(axis=axis, keepdims=True)
        pool = (self.prior * self.s0 * volume + self.counts.sum(axis=axis, keepdims=True)) / \
            (self.s0 * volume + exposed)
        scans = self.exposure - self.deficit
        if self.sp is not None:
            return (pool * self.sp + self.counts / self.volumes) / (self.sp + scans)
        cell_exposure = self.volumes * scans
        # cells apart: a two-sided Poisson deviance in effective counts (N S/S2) beyond
        # ln(cells of the pool / 1 %), against the level of every cell
        effective = self.exposure / self.squares
        n, mu = self.counts * effective, pool * cell_exposure * effective
        with np.errstate(divide="ignore", invalid="ignore"):
            divergence = np.where(n > 0, n * np.log(n / mu) - n + mu, mu)
        members = self.volumes.shape[0] if axis == 0 else self.volumes.size
        self.apart = (mu > 0) & (divergence > math.log(members / 0.01))
        keep = ~self.apart
        level = (self.prior * self.s0 * volume + (keep * self.counts).sum(axis=axis, keepdims=True)) / \
            (self.s0 * volume + (keep * cell_exposure).sum(axis=axis, keepdims=True))
        excess = (keep * ((self.counts - level * cell_exposure) ** 2
                          - level * cell_exposure * self.squares / self.exposure)
                  ).sum(axis=axis, keepdims=True)
        weight = (keep * cell_exposure ** 2).sum(axis=axis, keepdims=True)
        self.spread = np.where(weight > 0, np.maximum(excess, 0) / np.where(weight > 0, weight, 1), 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            sp = level / (self.spread * self.volumes)
            cells = (level * sp + self.counts / self.volumes) / (sp + scans)
        alone = (self.prior * self.s0 + self.counts / self.volumes) / (self.s0 + scans)
        return np.where(self.apart, alone, np.where(self.spread > 0, cells, level))

    def intensity(self, pose, positions, ranges=None):
        i, j, inside = self.cells(pose, positions, ranges)
        out = np.full(len(positions), self.prior)
        out[inside] = self.grid()[i[inside], j[inside]]
        return out


def _random_scan(rng, m):
    polar = np.column_stack([rng.uniform(-math.pi, math.pi, m), rng.uniform(0, 1800, m)])
    return np.column_stack([polar[:, 1] * np.cos(polar[:, 0]), polar[:, 1] * np.sin(polar[:, 0])])


@pytest.mark.parametrize("space,edges,pooling,pooling_scans", [
    ("bearing-range", (BEARINGS, RANGES), "none", 6.0),
    ("bearing-range", (BEARINGS, RANGES), "range", 6.0),
    ("bearing-range", (BEARINGS, RANGES), "range", None),
    ("bearing-range", (BEARINGS, RANGES), "grid", 6.0),
    ("body-xy", (np.linspace(-1500, 1500, 7), np.linspace(-1500, 1500, 5)), "none", 6.0),
    ("body-xy", (np.linspace(-1500, 1500, 7), np.linspace(-1500, 1500, 5)), "grid", 6.0),
    ("body-xy", (np.linspace(-1500, 1500, 7), np.linspace(-1500, 1500, 5)), "grid", None),
    ("world-xy", (np.linspace(-1000, 2000, 6), np.linspace(-1500, 1500, 4)), "none", 6.0)])
def test_matches_the_numpy_reference(space, edges, pooling, pooling_scans):
    rng = np.random.default_rng(4)
    ours = ClutterMap(space=space, edges=edges, prior_intensity=2e-4, prior_scans=4.0,
                      forgetting=0.97, pooling=pooling, pooling_scans=pooling_scans)
    reference = ReferenceMap(space, edges, 2e-4, 4.0, 0.97, pooling, pooling_scans)
    pose = (120.0, -40.0, 2.5)
    probes = _random_scan(rng, 500) + pose[:2]
    hot = np.array([[300.0, 250.0]]) + pose[:2]  # a spot with clutter in every scan
    for scan in range(150):
        positions = np.concatenate([_random_scan(rng, int(rng.integers(0, 40))) + pose[:2],
                                    hot + rng.uniform(-20, 20, (3, 2))])
        ranges = np.where(rng.random(len(positions)) < 0.5, np.nan,
                          np.hypot(*(positions - pose[:2]).T)) if space == "bearing-range" else None
        # gates around a few of the scan's own detections (tracks) and some elsewhere
        gates = np.column_stack([np.concatenate([positions[:3], _random_scan(rng, 2) + pose[:2]]),
                                 rng.uniform(0, 150, min(len(positions), 3) + 2)])
        # every other scan with clutter probabilities as weights
        weights = rng.random(len(positions)) if scan % 2 else None
        ours.update(pose, positions, ranges, gates, weights)
        reference.update(pose, positions, ranges, gates, weights)
    np.testing.assert_allclose(ours.intensity_grid(), reference.grid(), rtol=1e-12)
    np.testing.assert_allclose(ours.intensity(pose, probes), reference.intensity(pose, probes),
                               rtol=1e-12)
    assert np.ptp(reference.grid()) > 0  # the cells learned different intensities
    assert reference.deficit.max() > 0  # and gates took some exposure
    if pooling_scans is None:
        if pooling == "range":  # the hot spot's cell leaves its ring; the rings' spreads are used
            assert (reference.spread > 0).any()
            assert reference.apart.any() and not reference.apart.all()
        else:  # clutter uniform in range and bearing is dense near the sensor: on an x/y grid
            assert reference.apart.all()  # every cell differs from the grid's level and leaves



def test_converges_to_a_stationary_clutter_field():
    """Clutter drawn per scan from a known field (bearing–range cells, Poisson counts):
    after 2 000 scans with γ = 0.998 (memory 500 scans) every cell's estimate is within
    4 standard deviations of the truth — σ from the discounted counts' variance,
    λ·V·Σγ^(2j) / (V·Σγ^j)² — and within 10 % where a cell expects ≥ 5 points a scan."""
    rng = np.random.default_rng(11)
    edges = (np.linspace(-math.pi, math.pi, 9), np.array([0.0, 300.0, 1000.0, 1600.0]))
    volumes = np.outer(np.diff(edges[0]), np.diff(edges[1]))
    truth = np.tile([2e-4, 1e-3, 1e-2], (8, 1)) * np.linspace(0.5, 1.5, 8)[:, None]
    gamma, scans = 0.998, 2000
    learned = ClutterMap(space="bearing-range", edges=edges, prior_intensity=1e-3,
                         prior_scans=1.0, forgetting=gamma)
    pose = (0.0, 0.0, 0.0)
    for _ in range(scans):
        counts = rng.poisson(truth * volumes)
        points = []
        for (i, j), n in np.ndenumerate(counts):
            b = rng.uniform(edges[0][i], edges[0][i + 1], n)
            r = rng.uniform(edges[1][j], edges[1][j + 1], n)
            points.append(np.column_stack([r * np.cos(b), r * np.sin(b)]))
        positions = np.concatenate(points)
        learned.update(pose, positions, np.hypot(*positions.T))
    weights = gamma ** np.arange(scans)
    sigma = np.sqrt(truth * volumes * np.sum(weights ** 2)) / (volumes * weights.sum())
    estimate = learned.intensity_grid()
    assert np.all(np.abs(estimate - truth) <= 4 * sigma + 1e-3 / weights.sum())
    busy = truth * volumes >= 5
    assert busy.sum() == 4  # the four far cells on the busier side
    assert np.all(np.abs(estimate[busy] / truth[busy] - 1) <= 0.10)


def test_range_pooling_learns_a_ring_in_a_few_scans_and_keeps_a_hot_cell():
    """A field that depends on range only, plus one hot cell (a coast, ×20): after 40 scans
    (γ 0.99) the far ring's pooled level (its cells' mean) is within 5 % of the truth (~2σ
    of the ring's ~1 200 points plus the 1-scan prior's 3 % pull), where unpooled cells with
    a 10-scan prior are still ~20 % low by their formula; the hot cell stands well above
    its ring."""
    rng = np.random.default_rng(5)
    edges = (np.linspace(-math.pi, math.pi, 25), np.array([0.0, 300.0, 1000.0, 1600.0]))
    volumes = np.outer(np.diff(edges[0]), np.diff(edges[1]))
    truth = np.tile([2e-4, 1e-3, 1e-2], (24, 1))
    truth[5, 1] *= 20
    pooled = ClutterMap(space="bearing-range", edges=edges, prior_intensity=1e-3,
                        prior_scans=1.0, forgetting=0.99, pooling="range", pooling_scans=10.0)
    alone = ClutterMap(space="bearing-range", edges=edges, prior_intensity=1e-3,
                       prior_scans=10.0, forgetting=0.99)
    for _ in range(40):
        points = []
        for (i, j), n in np.ndenumerate(rng.poisson(truth * volumes)):
            b = rng.uniform(edges[0][i], edges[0][i + 1], n)
            r = rng.uniform(edges[1][j], edges[1][j + 1], n)
            points.append(np.column_stack([r * np.cos(b), r * np.sin(b)]))
        positions = np.concatenate(points)
        for learned in (pooled, alone):
            learned.update((0.0, 0.0, 0.0), positions, np.hypot(*positions.T))
    far = pooled.intensity_grid()[:, 2]
    assert abs(far.mean() / 1e-2 - 1) <= 0.05
    assert np.mean(alone.intensity_grid()[:, 2]) < 0.85e-2
    middle = np.delete(pooled.intensity_grid()[:, 1], 5)
    assert pooled.intensity_grid()[5, 1] > 5 * middle.max()


def test_a_model_and_a_context_read_the_map_as_it_stands():
    learned = ClutterMap(space="bearing-range", edges=(BEARINGS, RANGES),
                         prior_intensity=1e-3, prior_scans=2.0, forgetting=0.9)
    model = ClutterDensityModel(factors=[RangeBands(edges=(1000.0,), values=(1.0, 3.0)), learned])
    assert model.uses_position
    pose = Pose(x=10.0, y=5.0, heading=1.0)
    points = np.array([[300.0, 400.0], [-900.0, 1000.0], [5000.0, 0.0]])
    bands = np.array([1.0, 3.0, 3.0])
    np.testing.assert_array_equal(model.evaluate(pose, points),
                                  bands * learned.intensity(pose, points))
    sensor = SensorModel(detection=DetectionProbabilityModel(factors=[0.9]), clutter=model)
    context = sensor.context(pose)
    before = context.clutter_spatial_density_array(points)
    # a scan's detections are weighed by the map as it was; the update after the scan
    # shows in the next evaluation (the context is not a snapshot)
    learned.update(pose, points[:1].repeat(3, axis=0))
    after = context.clutter_spatial_density_array(points)
    assert after[0] > before[0] and after[2] == before[2]  # outside the grid: the prior
    np.testing.assert_array_equal(after, bands * learned.intensity(pose, points))


def test_the_order_of_a_scans_detections_does_not_matter():
    rng = np.random.default_rng(2)
    scans = [_random_scan(rng, 30) for _ in range(20)]
    maps = [ClutterMap(space="body-xy", edges=(np.linspace(-2000, 2000, 9),) * 2,
                       prior_intensity=1e-6, forgetting=0.95) for _ in range(2)]
    for scan in scans:
        maps[0].update((0.0, 0.0, 0.3), scan)
        maps[1].update((0.0, 0.0, 0.3), scan[rng.permutation(len(scan))])
    assert maps[0].counts.tobytes() == maps[1].counts.tobytes()
    assert (maps[0].exposure, maps[0].scale) == (maps[1].exposure, maps[1].scale)


def _used_map(pooling="none", pooling_scans=5.0):
    learned = ClutterMap(space="bearing-range", edges=(BEARINGS, RANGES),
                         prior_intensity=1e-3, prior_scans=3.0, forgetting=0.93,
                         pooling=pooling, pooling_scans=pooling_scans)
    rng = np.random.default_rng(8)
    for _ in range(40):
        scan = _random_scan(rng, 25)
        learned.update((0.0, 0.0, 0.0), scan, gates=np.column_stack([scan[:2], [30.0, 60.0]]))
    return learned


@pytest.mark.parametrize("pooling,pooling_scans", [("none", 5.0), ("range", 5.0),
                                                   ("range", None)])
@pytest.mark.parametrize("round_trip", ["pickle", "yaml"])
def test_state_round_trips_exactly_and_continues_identically(round_trip, pooling, pooling_scans):
    learned = _used_map(pooling, pooling_scans)
    if round_trip == "pickle":
        restored = pickle.loads(pickle.dumps(learned))
    else:
        restored = YAML().load(YAML().dumps(learned))
    assert type(restored) is ClutterMap and restored.pooling == pooling
    assert restored.pooling_scans == pooling_scans
    assert restored.intensity_grid().tobytes() == learned.intensity_grid().tobytes()
    assert restored.counts.tobytes() == learned.counts.tobytes()
    assert restored.deficit.tobytes() == learned.deficit.tobytes() and learned.deficit.sum() > 0
    assert (restored.exposure, restored.scale) == (learned.exposure, learned.scale)
    assert learned.scale > 1 and learned.counts.sum() > 0  # a state worth saving
    scan = _random_scan(np.random.default_rng(9), 12)
    learned.update((0.0, 0.0, 0.0), scan)
    restored.update((0.0, 0.0, 0.0), scan)
    assert restored.intensity_grid().tobytes() == learned.intensity_grid().tobytes()


def test_a_pickle_from_before_pooling_loads_unpooled():
    """A map pickled before ``pooling`` existed has no state for it: it loads with the
    Properties' defaults (no pooling) and the same numbers."""
    learned = _used_map()
    state = learned.__getstate__()
    for name in ("_property_pooling", "_property_pooling_scans"):
        del state[name]
    old = ClutterMap.__new__(ClutterMap)
    old.__setstate__(state)
    assert old.pooling == "none" and old.pooling_scans == 10.0
    assert old.intensity_grid().tobytes() == learned.intensity_grid().tobytes()


def test_reset_and_immutability_of_the_configuration():
    learned = _used_map()
    learned.reset()
    assert np.all(learned.intensity_grid() == 1e-3) and learned.exposure == 0.0
    with pytest.raises(AttributeError, match="^ClutterMap.forgetting: set at construction"):
        learned.forgetting = 0.5


@pytest.mark.parametrize("kwargs,argument", [
    (dict(space="polar"), "space"),
    (dict(edges=([0.0, 1.0],)), "edges"),
    (dict(edges=([0.0], [0.0, 1.0])), "edges"),
    (dict(edges=([1.0, 0.0], [0.0, 1.0])), "edges"),
    (dict(space="bearing-range", edges=([-4.0, 0.0], [0.0, 1.0])), "edges"),
    (dict(space="bearing-range", edges=([0.0, 1.0], [-1.0, 1.0])), "edges"),
    (dict(prior_intensity=0.0), "prior_intensity"),
    (dict(prior_intensity=float("nan")), "prior_intensity"),
    (dict(prior_scans=0.0), "prior_scans"),
    (dict(forgetting=0.0), "forgetting"),
    (dict(forgetting=1.01), "forgetting"),
    (dict(counts=np.zeros((2, 2))), "counts"),
    (dict(counts=-np.ones((1, 1))), "counts"),
    (dict(deficit=np.ones((1, 1))), "deficit"),
    (dict(exposure=-1.0), "exposure"),
    (dict(scale=0.0), "scale"),
    (dict(prior_intensity="high"), "prior_intensity"),
    (dict(pooling="ring"), "pooling"),
    (dict(pooling="range"), "pooling"),  # rings need a bearing-range map
    (dict(pooling="grid", pooling_scans=0.0), "pooling_scans"),
    (dict(pooling="grid", pooling_scans=float("inf")), "pooling_scans"),
])
def test_bad_configuration_is_named(kwargs, argument):
    config = dict(space="world-xy", edges=([0.0, 1.0], [0.0, 1.0]), prior_intensity=1.0)
    with pytest.raises((ValueError, TypeError), match=f"^{argument}: "):
        ClutterMap(**{**config, **kwargs})


def test_bad_updates_are_named_and_change_nothing():
    learned = _used_map()
    before = learned.counts.tobytes(), learned.exposure
    with pytest.raises(ValueError, match="^positions: "):
        learned.update((0.0, 0.0, 0.0), [[1.0, 2.0], [np.nan, 0.0]])
    with pytest.raises(ValueError, match="^ranges: "):
        learned.update((0.0, 0.0, 0.0), [[1.0, 2.0]], [np.inf])
    with pytest.raises(ValueError, match="^positions: "):
        learned.update((0.0, 0.0, 0.0), [[1.0, 2.0, 3.0]])
    with pytest.raises(ValueError, match="^gates: "):
        learned.update((0.0, 0.0, 0.0), [[1.0, 2.0]], gates=[[0.0, 0.0, -1.0]])
    with pytest.raises(ValueError, match="^gates: "):
        learned.update((0.0, 0.0, 0.0), [[1.0, 2.0]], gates=[[0.0, 0.0]])
    with pytest.raises(ValueError, match="^weights: "):
        learned.update((0.0, 0.0, 0.0), [[1.0, 2.0]], weights=[1.5])
    with pytest.raises(ValueError, match="^weights: "):
        learned.update((0.0, 0.0, 0.0), [[1.0, 2.0]], weights=[np.nan])
    with pytest.raises(ValueError, match="^weights: "):
        learned.update((0.0, 0.0, 0.0), [[1.0, 2.0]], weights=[0.5, 0.5])
    assert (learned.counts.tobytes(), learned.exposure) == before
