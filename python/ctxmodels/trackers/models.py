"""The sensor models a tracker of :data:`~ctxmodels.trackers.TRACKERS` reads, made from the
user's: λ replaced by the uniform constant (P_D-aware), a coastal band added along the
land (``gmphd-coastal``), or the primary sensor's λ and P_D learned online (``gmphd-learned*``),
with the settings of each."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import (AngularSector, ClutterDensityModel, DetectionEstimate, DetectionProbabilityModel,
               LandMask, LineOfSight, RangeBands, SensorModel)

@dataclass(frozen=True)
class ClutterMapSettings:
    """The learned radar clutter map (``gmphd-learned-clutter``, ``gmphd-learned``); a
    :class:`~ctxmodels.trackers.TrackerSpec` carries one, and a variant is a replaced copy.

    Cells of 5° × 50 m in the radar's bearing–range space — 5σ of its bearing noise and 10σ
    of its range noise, so a point source's returns stay in one cell, and fine enough to
    follow the sea clutter's step at 1 km and a coastline — over the bearings the radar sees
    (its blind sector is not in the grid: no clutter is reported there, so its cells would
    only learn λ ≈ 0 and pull their rings down). Cells are pooled by range ring
    (``pooling='range'``): sea clutter depends on the grazing angle, i.e. on range, and only
    slowly on bearing, so a ring's 59 cells share one level that is learned in a few scans,
    where a cell alone needs ~100 (one far cell sees ~0.04 clutter points a scan). How far a
    cell departs from its ring is estimated from the ring's spread (``pooling_scans=None``: a
    Gamma–Poisson hierarchy, :class:`~ctxmodels.ClutterMap`): a ring whose cells agree gives
    them its level, a ring with a coast (~0.5 points a scan in one cell) lets that cell go. A
    cell its ring's level cannot explain — a coast, or a static object's returns every scan —
    leaves the ring by the map's Poisson tail test: such a source is not sea clutter. The
    ring's prior, λ 1e-3 per rad·m (the uniform trackers' value), is a guess worth one scan
    of the ring (59 cell-scans). Forgetting 0.99 per scan (a memory of 100 scans, 2 minutes
    at 0.8 Hz: the scenes' clutter does not change faster). Each detection counts as its
    posterior clutter probability in the GM-PHD update (``weighting='posterior'``,
    :class:`~ctxmodels.stonesoup.ClutterMapLearner`): the expected clutter count under the
    tracker's own model, so a target's returns count as clutter only in proportion to how
    little the filter already believes in it. ``docs/study.md`` shows what depends on these
    choices and which were revised after results (``scripts/learned_warmup.py --settings``,
    ``scripts/learned_target_leak.py``)."""

    bearing_cell: float = math.radians(5.0)
    range_cell: float = 50.0
    prior: float = 1e-3
    prior_scans: float = 1.0
    forgetting: float = 0.99
    pooling: str = "range"
    pooling_scans: float | None = None
    #: ``"posterior"`` or ``"gates"`` (:class:`~ctxmodels.stonesoup.ClutterMapLearner`).
    weighting: str = "posterior"
    #: The grid spans every bearing, the blind sector too (a variant, not the study's).
    full_circle: bool = False


@dataclass(frozen=True)
class DetectionEstimateSettings:
    """The learned radar P_D (``gmphd-learned``): the hand-written model's range bands where
    it is > 0 (the radar's range limits are specification) split into bands of about 200 m
    — a radar's P_D falls with range (SNR ∝ R⁻⁴), and 8 bands still see a few targets each —
    each a Beta posterior with prior mean 0.5 (nothing known but that the radar detects
    something: a coin) worth 5 trials (four scans of one track overrule it), forgetting 0.99
    per scan like the clutter map; the blind sector, land and line of sight stay as given."""

    band: float = 200.0
    prior: float = 0.5
    prior_trials: float = 5.0
    forgetting: float = 0.99


#: Gates of 50 m around the tracks (the learners' association): 3σ of the bearing error at
#: 1 km hold a track's returns.
LEARNING_GATE = 50.0


def learned_clutter_map(model: SensorModel, settings: ClutterMapSettings = ClutterMapSettings()):
    """A fresh bearing–range clutter map over ``model``'s P_D reach and the bearings it sees
    (:class:`ClutterMapSettings`)."""
    from ..clutter_map import ClutterMap
    reach = sensor_reach(model)
    if not math.isfinite(reach) or reach <= 0:
        raise ValueError("sensor_models: the learned clutter map covers the primary sensor's "
                         "reach, but its P_D has no outer range band with P_D = 0")
    low, high = (-math.pi, math.pi) if settings.full_circle else _seen_bearings(model)
    bearings = np.linspace(low, high, max(1, round((high - low) / settings.bearing_cell)) + 1)
    ranges = settings.range_cell * np.arange(math.ceil(reach / settings.range_cell) + 1)
    return ClutterMap(space="bearing-range", edges=(bearings, ranges),
                      prior_intensity=settings.prior, prior_scans=settings.prior_scans,
                      forgetting=settings.forgetting, pooling=settings.pooling,
                      pooling_scans=settings.pooling_scans)


def _seen_bearings(model: SensorModel) -> tuple[float, float]:
    """The bearings (within [-π, π]) outside ``model``'s one blind sector astern (an
    :class:`~ctxmodels.AngularSector` with P_D 0 inside that holds bearing π); the whole
    circle without one (a blind sector elsewhere splits the interval: it stays in the grid)."""
    blind = [f for f in model.detection.factors if isinstance(f, AngularSector)
             and f.inside == 0 and f.outside > 0]
    if len(blind) != 1:
        return -math.pi, math.pi
    centre, half = blind[0].centre, blind[0].width / 2
    if abs(math.remainder(centre - math.pi, 2 * math.pi)) > half or half >= math.pi:
        return -math.pi, math.pi
    low, high = math.remainder(centre + half, 2 * math.pi), math.remainder(centre - half, 2 * math.pi)
    return (low, high) if low < high else (-math.pi, math.pi)


def learned_detection(model: SensorModel,
                      settings: DetectionEstimateSettings = DetectionEstimateSettings(),
                      ) -> DetectionProbabilityModel:
    """``model``'s P_D with its range bands replaced by one :class:`~ctxmodels.DetectionEstimate`
    over their support (:class:`DetectionEstimateSettings`)."""
    bands = [f for f in model.detection.factors if isinstance(f, RangeBands)]
    if len(bands) != 1:
        raise ValueError("sensor_models: the learned P_D replaces the primary sensor's range "
                         f"bands, which must be one RangeBands factor; it has {len(bands)}")
    edges, values = bands[0].edges, bands[0].values
    seen = [i for i, value in enumerate(values) if value > 0]
    if not seen or seen[-1] == len(edges) or seen != list(range(seen[0], seen[-1] + 1)):
        raise ValueError("sensor_models: the learned P_D needs the primary's range bands to be "
                         "> 0 on one bounded interval of range")
    low, high = (float(edges[seen[0] - 1]) if seen[0] else 0.0), float(edges[seen[-1]])
    count = max(1, round((high - low) / settings.band))
    estimate = DetectionEstimate(edges=np.linspace(low, high, count + 1),
                                 prior_probability=settings.prior,
                                 prior_trials=settings.prior_trials, forgetting=settings.forgetting)
    return DetectionProbabilityModel(factors=[estimate if f is bands[0] else f
                                              for f in model.detection.factors])


#: The hand-written coastal band (``gmphd-coastal``), from the simulated radar before any
#: run: shore returns are 0.01 per metre of seen coastline per scan, measured with σ 1° in
#: bearing (6–13 m across the line of sight at the islands' 350–760 m) and 5 m in range.
#: Half-width 25 m: 2σ of a 1° bearing error at 750 m (4σ of the calibrated 0.5°; the
#: band is hand-written, not tuned to either). Factor 100: the returns spread over
#: the 50 m band are 2e-4 per m², 0.1 per rad·m at the islands' middle range (550 m) —
#: 100 times the sea's 1e-3 there. (One factor for all ranges: at 350 m it is 1.5× too
#: high, at 750 m 1.4× too low.)
COAST_WIDTH, COAST_FACTOR = 25.0, 100.0


def with_coast(model: SensorModel) -> SensorModel:
    """``model`` with a :class:`~ctxmodels.CoastalClutter` band along its P_D's land in λ."""
    from .. import CoastalClutter
    lands = [f for f in model.detection.factors if isinstance(f, LandMask)]
    lands += [f.land for f in model.detection.factors if isinstance(f, LineOfSight)]
    if not lands:
        raise ValueError("sensor_models: the coastal band follows the land in the primary "
                         "sensor's P_D (LandMask / LineOfSight factors); it has none")
    band = CoastalClutter(land=lands[0], width=COAST_WIDTH, inside=COAST_FACTOR)
    return _with(model, clutter=ClutterDensityModel(factors=[*model.clutter.factors, band]))


def with_uniform_clutter(model: SensorModel, density: float) -> SensorModel:
    """``model`` with λ the constant ``density`` everywhere (its P_D kept)."""
    return _with(model, clutter=ClutterDensityModel(factors=[density]))


def with_learned_clutter(model: SensorModel, settings: ClutterMapSettings) -> SensorModel:
    """``model`` with λ a fresh :func:`learned_clutter_map` (learned as the tracker runs)."""
    return _with(model, clutter=ClutterDensityModel(
        factors=[learned_clutter_map(model, settings)]))


def with_learned_detection(model: SensorModel, settings: DetectionEstimateSettings) -> SensorModel:
    """``model`` with its range bands' P_D a fresh :func:`learned_detection`."""
    return _with(model, detection=learned_detection(model, settings))


def _with(model: SensorModel, **changes) -> SensorModel:
    """``model`` with some Properties replaced (``clutter=...``, ``detection=...``)."""
    properties = {name: getattr(model, name) for name in type(model).properties}
    return type(model)(**{**properties, **changes})


def sees_land(model: SensorModel) -> bool:
    return any(isinstance(f, (LandMask, LineOfSight)) for f in model.detection.factors)


def sensor_reach(model: SensorModel) -> float:
    """How far from the platform the sensor's P_D can be > 0: the least outer edge of its
    range bands' last band with P_D > 0 and of its learned bands that are 0 beyond (inf
    without such bands), plus the lever arm."""
    reach = math.inf
    for factor in model.detection.factors:
        if isinstance(factor, (int, float)) and factor == 0:
            return 0.0
        if isinstance(factor, RangeBands):
            seen = [i for i, value in enumerate(factor.values) if value > 0]
            if not seen:
                return 0.0
            if seen[-1] < len(factor.edges):
                reach = min(reach, float(factor.edges[seen[-1]]))
        if isinstance(factor, DetectionEstimate) and factor.outside == 0:
            reach = min(reach, float(factor.edges[-1]))
    mounting = model.mounting
    arm = 0.0 if mounting is None else math.hypot(mounting.forward, mounting.left)
    return reach + arm

