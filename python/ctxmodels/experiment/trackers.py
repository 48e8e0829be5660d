"""The compared trackers (paper Table I), built for a simulated run or anyone's sensor data
(:func:`paper_tracker`).

Common to all: constant-velocity motion with σ_acc = 0.8 (Stone Soup's ``ConstantVelocity``
noise coefficient q = σ² = 0.64 per axis), state [x, vx, y, vy], track/birth covariance
diag([10, 15, 10, 15])², an extended Kalman updater (exact for the lidar's linear model,
linearised for the radar's bearing–range model).

JPDA (paper): ``PDAHypothesiser`` with P_D 0.4, λ 1e-3, χ² gate P_G 0.95; joint association
by efficient hypothesis management (``JPDAwithEHM2``: the same joint probabilities as the
brute-force ``JPDA``, without enumerating every joint event); M-of-N logic through
``MultiMeasurementInitiator`` (3 detections) and deletion after 30 missed updates.
JPDA (tuned): the same hypothesiser and association with its windows counted in time — a
holding track dropped after :data:`TUNED_CONFIRM_WINDOW` s and a track after
:data:`TUNED_DELETE_WINDOW` s without a detection (Stone Soup's ``UpdateTimeDeleter``),
:data:`TUNED_MIN_POINTS` detections to confirm — and duplicate tracks merged by the
track-to-track χ² test (:class:`~ctxmodels.stonesoup.DuplicateTrackDeleter`), chosen by the
declared search of ``docs/jpda_baselines.md``.
JPDA (context-aware, ours): the same with ctxmodels' context-aware hypothesiser and an
:class:`~ctxmodels.stonesoup.ExpectedMissesDeleter` (delete when Σ P_D over the misses since
the last detection reaches 3) — a miss only counts as far as the sensor could see the track —
or, whichever comes first, Stone Soup's ``CovarianceBasedDeleter`` on the position: the
GM-PHD's bound on position uncertainty (RMS x/y σ ≤ 200 m: delete once P_xx + P_yy >
2·200² m²), for the same physical reason. A track the sensors cannot see (P_D = 0: blind
sector, beyond the lidar while the radar looks elsewhere) accrues no expected misses, so
without the bound it coasts for minutes while its covariance grows without bound (constant
velocity: position variance ∝ t³). Such a track no longer says where a target is, and its
ever wider gate takes in more and more detections: by 240 s of the mixed-range scenario
there were up to 166 tracks a scan, in clusters of ~145 tracks sharing ~35 detections whose
exact joint association outgrew memory. The paper's JPDA keeps its stock deleter (30 misses).

All trackers symmetrise each Kalman posterior (Stone Soup's ``force_symmetric_covariance``):
the standard-form update :math:`P - K S K^T` amplifies its own round-off asymmetry on a
target tracked for minutes (×40 per 200 updates, measured), until covariances turn
indefinite; the radar's bearing–range model has its closed-form Jacobian.

GM-PHD (all variants): gate Mahalanobis < 3, measurement-driven birth with weight 1e-4,
survival 1, prune 1e-6, merge at Mahalanobis < 4 (squared distance 16), extraction 0.85,
a surveillance region that follows the ego (at each scan, the disc of the radar's reach,
1612 m, plus 500 m around it: :class:`~ctxmodels.stonesoup.PoseCentredRegion`) so that
components outside all coverage (P_D = 0, never decaying) cannot accumulate — the margin
keeps a target that has just left the radar's reach for as long as it could still return
(at ≤ 10 m/s relative speed, ~50 s, about when the uncertainty bound drops it), and a bound on
position uncertainty (RMS x/y σ ≤ 200 m) so that components unseen inside it (blind sector)
cannot grow into ghosts that the reducer merges real tracks into (see
:class:`~ctxmodels.stonesoup.PointProcessMultiTargetTracker`). They differ
only in P_D and λ: uniform (0.4, 1e-3 for both sensors, stock components on plain
detection sets), radar-only (the same on radar scans only), P_D-aware (eqs. pd-lidar,
pd-radar; λ 1e-3), context-aware (eqs. ``pd-*`` and ``lambda-*``) and, on the islands scenario,
line-of-sight-aware (context-aware plus land mask and radar shadow in the radar's P_D).

GM-PHD (learned λ, ours): the context-aware GM-PHD whose radar λ is not the paper's equation
but a :class:`~ctxmodels.ClutterMap` learned online from the tracker's own output
(:class:`~ctxmodels.stonesoup.ClutterMapLearner` after each scan; settings below,
:data:`MAP_PRIOR`); the lidar keeps the paper's ``area`` rule. GM-PHD (learned λ, P_D,
ours): the same with the radar's range-band P_D learned as well
(:class:`~ctxmodels.DetectionEstimate`, :class:`~ctxmodels.stonesoup.DetectionLearner`;
:data:`PD_BAND`); its blind sector stays as specified.

Reported tracks are Stone Soup's: a GM-PHD track is created when a component's weight
exceeds the extraction threshold and continues, one state per scan, while its tagged
component survives; the metrics look at the states at radar timestamps.
"""
from __future__ import annotations

import datetime
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np
from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
from stonesoup.dataassociator.probability import JPDAwithEHM2
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.hypothesiser.gaussianmixture import GaussianMixtureHypothesiser
from stonesoup.hypothesiser.probability import PDAHypothesiser as StockPDAHypothesiser
from stonesoup.measures import Mahalanobis
from stonesoup.mixturereducer.gaussianmixture import GaussianMixtureReducer
from stonesoup.models.transition.linear import ConstantVelocity
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.types.state import GaussianState
from stonesoup.updater.kalman import ExtendedKalmanUpdater
from stonesoup.updater.pointprocess import PHDUpdater as StockPHDUpdater

from .. import (AngularSector, ClutterDensityModel, DetectionEstimate, DetectionProbabilityModel,
               LandMask, LineOfSight, RangeBands, SensorModel)
from ..pose import NavigationTrack, PoseSource
from ..stonesoup.region import PoseCentredRegion
from .sensors import UNIFORM_CLUTTER, UNIFORM_PD, paper_sensor_models, uniform_clutter

SIGMA_ACC = 0.8
INIT_STD = np.array([10.0, 15.0, 10.0, 15.0])
BIRTH_WEIGHT = 1e-4
GATE_MAHALANOBIS = 3.0
MERGE_MAHALANOBIS = 4.0
PRUNE_THRESHOLD = 1e-6
EXTRACTION_THRESHOLD = 0.85
JPDA_PROB_GATE = 0.95
JPDA_MIN_POINTS = 3
JPDA_DELETE_AFTER = 30
JPDA_EXPECTED_MISSES = 3.0
#: Track-to-track test for duplicate JPDA tracks: χ² with 2 degrees of freedom at 99 %.
DUPLICATE_THRESHOLD = 9.21
#: The tuned JPDA's windows, chosen by the declared search (``scripts/tune_jpda.py``,
#: docs/jpda_baselines.md; its record: docs/figures/jpda_tuning.json).
TUNED_MIN_POINTS, TUNED_CONFIRM_WINDOW, TUNED_DELETE_WINDOW = 5, 2.6, 10.0
#: Added to the sensors' farthest P_D reach for the GM-PHD's surveillance region (m): a target
#: that has just left the radar's reach can return for ~50 s at ≤ 10 m/s relative speed.
REGION_MARGIN = 500.0
#: Components (GM-PHD) and context-aware JPDA tracks unseen long enough to be this uncertain
#: (RMS x/y σ, m) are dropped: a settled track survives ≈ 55 s unseen, about a crossing of the
#: 65° blind sector at 200 m and 5 m/s.
MAX_POSITION_STD = 200.0
#: State indices of x and y (state [x, vx, y, vy]); a list, as Stone Soup's
#: ``CovarianceBasedDeleter`` indexes the covariance's diagonal with it (a tuple would index
#: a 1-D array as two axes).
POSITION_MAPPING = [0, 2]
#: The JPDA runs (stock Stone Soup association, the slowest trackers) cover the paper's two
#: scenarios; the islands scenario is about the GM-PHD's land and line-of-sight models.
PAPER_SCENARIOS = ("mixed-range", "formation")


@dataclass(frozen=True)
class TrackerSpec:
    name: str
    label: str
    description: str
    family: str  # "jpda" | "gmphd"
    #: Tracks on the primary (long-range) sensor's scans only (the radar-only baseline).
    primary_only: bool = False
    pd: str = "uniform"  # "uniform" | "context" | "learned" (the primary's bands, online)
    clutter: str = "uniform"  # "uniform" | "context" | "learned" (the primary's, online)
    line_of_sight: bool = False
    #: The primary's λ also has a coastal band (:data:`COAST_WIDTH`) along its P_D's land.
    coastal: bool = False
    only_scenarios: tuple[str, ...] | None = None
    extraction_threshold: float = EXTRACTION_THRESHOLD
    #: JPDA only: detections to confirm a track (M-of-N) and missed scans to delete it.
    min_points: int = JPDA_MIN_POINTS
    delete_after: int = JPDA_DELETE_AFTER
    #: JPDA only, windows in time instead of scans (None: count scans): a holding track is
    #: dropped after ``confirm_window`` s without a detection, a track after
    #: ``delete_window`` s without one in its gate (Stone Soup's ``UpdateTimeDeleter``).
    confirm_window: float | None = None
    delete_window: float | None = None
    #: JPDA only: delete the weaker of two duplicate tracks (``DuplicateTrackDeleter``).
    merge_duplicates: bool = False
    #: Rough tracking CPU seconds of a 480 s scenario at the calibrated truth (measured on
    #: the 2-core VM): orders the experiment's jobs and weights its progress estimate only.
    cost: float = 1.0

    def __post_init__(self):
        windows = (self.confirm_window, self.delete_window)
        for name, value in zip(("confirm_window", "delete_window"), windows):
            if value is not None and not (isinstance(value, (int, float)) and math.isfinite(value)
                                          and value > 0):
                raise ValueError(f"{name}: a window in seconds > 0 or None, got {value!r}")
        if self.family != "jpda" and (any(w is not None for w in windows)
                                      or self.merge_duplicates):
            raise ValueError(f"{self.name}: confirm_window, delete_window and merge_duplicates "
                             "are JPDA settings; a GM-PHD reads none of them")
        if self.uses_context and self.family == "jpda" and self.delete_window is not None:
            raise ValueError(f"{self.name}: delete_window: the context-aware JPDA deletes on "
                             "expected misses, not after a time window")

    @property
    def uses_context(self) -> bool:
        return self.pd != "uniform" or self.clutter != "uniform"


#: The study's trackers by name (``ctxmodels list``).
TRACKERS: dict[str, TrackerSpec] = {spec.name: spec for spec in (
    TrackerSpec("jpda", "JPDA", "global P_D/λ, M-of-N logic (3 to confirm, 30 misses to delete)",
                "jpda", only_scenarios=PAPER_SCENARIOS, cost=3.2),
    TrackerSpec("jpda-tuned", "JPDA (tuned)",
                "the JPDA with windows in time, chosen by a declared search on calibration "
                "seeds (docs/jpda_baselines.md): 5 detections to confirm, holding tracks "
                "dropped after 2.6 s and tracks after 10 s without a detection, duplicates "
                "merged", "jpda", only_scenarios=PAPER_SCENARIOS, min_points=TUNED_MIN_POINTS,
                confirm_window=TUNED_CONFIRM_WINDOW, delete_window=TUNED_DELETE_WINDOW,
                merge_duplicates=True, cost=3.6),
    TrackerSpec("gmphd-uniform", "GM-PHD (uniform)", "global P_D 0.4, λ 1e-3 for both sensors",
                "gmphd", cost=1.0),
    TrackerSpec("gmphd-radar-only", "GM-PHD (radar-only)", "radar scans only, global P_D/λ",
                "gmphd", primary_only=True, cost=0.2),
    TrackerSpec("gmphd-pd-aware", "GM-PHD (P_D-aware)", "P_D per eqs. pd-lidar/pd-radar, λ 1e-3",
                "gmphd", pd="context", cost=1.7),
    TrackerSpec("gmphd-context", "GM-PHD (context-aware)", "P_D and λ per the paper's equations",
                "gmphd", pd="context", clutter="context", cost=1.8),
    TrackerSpec("jpda-context", "JPDA (context-aware)",
                "context P_D/λ, deletion on expected misses Σ P_D ≥ 3 or position σ > 200 m",
                "jpda", pd="context", clutter="context", only_scenarios=PAPER_SCENARIOS,
                cost=4.3),
    TrackerSpec("gmphd-learned-clutter", "GM-PHD (learned λ)",
                "context-aware with the radar's λ learned online (clutter map) instead of "
                "the paper's equation", "gmphd", pd="context", clutter="learned", cost=1.9),
    TrackerSpec("gmphd-learned", "GM-PHD (learned λ, P_D)",
                "context-aware with the radar's λ (clutter map) and P_D (range bands) "
                "learned online instead of the paper's equations", "gmphd", pd="learned",
                clutter="learned", cost=1.9),
    TrackerSpec("gmphd-sight", "GM-PHD (line-of-sight)",
                "context-aware plus land mask and radar shadow", "gmphd", pd="context",
                clutter="context", line_of_sight=True, only_scenarios=("islands",), cost=2.1),
    TrackerSpec("gmphd-coastal", "GM-PHD (line-of-sight, coastal λ)",
                "line-of-sight-aware plus a hand-written coastal band in the radar's λ",
                "gmphd", pd="context", clutter="context", line_of_sight=True, coastal=True,
                only_scenarios=("islands",), cost=1.9),
)}


#: Run when no trackers are named: all of them (each on the scenarios it is made for).
DEFAULT_TRACKERS = tuple(TRACKERS)


def applicable(tracker: str, scenario: str) -> bool:
    spec = TRACKERS[tracker]
    return spec.only_scenarios is None or scenario in spec.only_scenarios


def motion_model():
    """Constant velocity per axis; F and Q cached per scan interval (same numbers as the
    stock combined model, without rebuilding them for every prediction)."""
    from ..stonesoup.transition import CachedCombinedLinearGaussianTransitionModel
    q = SIGMA_ACC ** 2
    return CachedCombinedLinearGaussianTransitionModel([ConstantVelocity(q), ConstantVelocity(q)])


class _ScanReader:
    """One sensor's scans of a simulated run as a (time, detections) stream."""

    def __init__(self, scans):
        self.scans = scans

    def __iter__(self):
        return ((scan.timestamp, set(scan.detections)) for scan in self.scans)


def build_tracker(spec: TrackerSpec, run, fast: bool = True):
    """A Stone Soup tracker for ``spec`` over the scans of a simulated ``run`` (iterate it):
    :func:`paper_tracker` on the run's radar and lidar streams and the ego's navigation."""
    streams = {"radar": _ScanReader(run.radar_scans), "lidar": _ScanReader(run.lidar_scans)}
    navigation = NavigationTrack(timestamps=run.ego.timestamps, positions=run.ego.positions,
                                 headings=run.ego.headings)
    models = paper_sensor_models(land=run.land if spec.line_of_sight or spec.coastal else ())
    return paper_tracker(spec, streams, models, navigation, primary="radar", fast=fast)


def paper_tracker(name: str | TrackerSpec, streams: Mapping[str, Iterable],
                  sensor_models: Mapping[str, SensorModel],
                  pose_source: PoseSource, *, primary: str | None = None, fast: bool = True,
                  region_radius: float | None = None):
    r"""One of the study's trackers (:data:`TRACKERS`, by name, or a :class:`TrackerSpec`)
    on anyone's sensor data.

    Iterate the returned Stone Soup tracker for ``(time, tracks)`` per scan, as any tracker.

    ``streams``: sensor name → an iterable of ``(time, detections)`` scans in time order
    (a Stone Soup detector or reader, or a list), empty scans included — an empty scan is
    what tells a context-aware tracker that the sensor looked and saw nothing. Each
    detection carries its own measurement model. Scans of different sensors are merged in
    time order; at equal times they go in the order of ``streams``.

    ``sensor_models``: sensor name → its :class:`~ctxmodels.SensorModel` (P_D and λ; the
    context-aware trackers read them, the ``pd-aware`` ones read P_D and use λ = 1e-3, the
    uniform ones read neither). For ``gmphd-sight`` give models with land and line of sight
    in P_D (:func:`~ctxmodels.experiment.sensors.radar_detection` with ``land``).

    ``pose_source``: the platform's pose at each scan's time (a
    :class:`~ctxmodels.NavigationTrack`, a :class:`~ctxmodels.stonesoup.SensorPose`, …).
    Every GM-PHD's surveillance region follows it (:class:`~ctxmodels.stonesoup.PoseCentredRegion`):
    a disc of ``region_radius`` around the platform at each scan, by default the farthest
    reach of any sensor's P_D (its outermost range band with P_D > 0, plus its mounting's
    lever arm) plus :data:`REGION_MARGIN`.

    ``primary``: the sensor kept by the single-sensor tracker (``gmphd-radar-only``).
    ``fast``: the trackers that compute each scan in the Rust core (False: the component
    path, the readable reference with the same results).

    The streams are read once, as the tracker runs: give lists or readers, not generators,
    to build several trackers from the same data. The pose source must cover every scan's
    time (contexts and the region ask it at each scan). One pose source serves all sensors:
    mounting offsets go in each ``SensorModel.mounting``.
    """
    spec = name if isinstance(name, TrackerSpec) else (
        TRACKERS.get(name) if isinstance(name, str) else None)
    if spec is None:
        raise ValueError(f"name: unknown tracker {name!r}; choose from {list(TRACKERS)}")
    if not isinstance(streams, Mapping):
        raise TypeError(f"streams: expected a mapping of sensor name -> (time, detections) "
                        f"scans, got {type(streams).__name__}")
    if not isinstance(sensor_models, Mapping):
        raise TypeError(f"sensor_models: expected a mapping of sensor name -> SensorModel, got "
                        f"{type(sensor_models).__name__}")
    streams, sensor_models = dict(streams), dict(sensor_models)
    if not streams:
        raise ValueError("streams: no sensor streams given")
    for sensor, stream in streams.items():
        if not isinstance(sensor, str):
            raise TypeError(f"streams: sensor names must be strings, got {sensor!r}")
        if stream is None or isinstance(stream, (str, bytes, Mapping)) \
                or not isinstance(stream, Iterable):
            raise TypeError(f"streams: sensor {sensor!r}: expected an iterable of (time, "
                            f"detections) scans, got {type(stream).__name__}")
    missing = [sensor for sensor in streams if not isinstance(sensor_models.get(sensor), SensorModel)]
    if missing:
        raise ValueError(f"sensor_models: need a SensorModel for every stream; missing or not a "
                         f"SensorModel for {missing}")
    if not callable(getattr(pose_source, "pose_at", None)):
        raise TypeError("pose_source: expected an object with pose_at(timestamp), got "
                        f"{type(pose_source).__name__}")
    if primary is not None and not isinstance(primary, str):
        raise TypeError(f"primary: expected a sensor name (str) or None, got "
                        f"{type(primary).__name__} {primary!r}")
    if primary is not None and primary not in streams:
        raise ValueError(f"primary: {primary!r} is not a stream (one of {list(streams)})")
    if not isinstance(fast, (bool, np.bool_)):
        raise TypeError(f"fast: expected True or False, got {type(fast).__name__} {fast!r}")
    fast = bool(fast)
    if spec.primary_only:
        if primary is None:
            raise ValueError(f"primary: {name} keeps one sensor; name it (one of "
                             f"{list(streams)})")
        streams = {primary: streams[primary]}
    if spec.line_of_sight and not any(_sees_land(sensor_models[s]) for s in streams):
        raise ValueError(f"sensor_models: {name} needs land in some sensor's P_D "
                         "(LandMask / LineOfSight factors); none has any")
    if spec.coastal:
        if primary is None:
            raise ValueError(f"primary: {name} adds a coastal band to the primary sensor's λ; "
                             f"name it (one of {list(streams)})")
        sensor_models = {**sensor_models, primary: _with_coast(sensor_models[primary])}
    if spec.pd == "context" and spec.clutter == "uniform":
        sensor_models = {s: _with(m, clutter=uniform_clutter()) for s, m in sensor_models.items()}
    if "learned" in (spec.pd, spec.clutter) and primary is None:
        raise ValueError(f"primary: {name} learns the primary sensor's model; name it (one of "
                         f"{list(streams)})")
    if spec.clutter == "learned":
        sensor_models = {**sensor_models, primary: _with(sensor_models[primary], clutter=ClutterDensityModel(
            factors=[learned_clutter_map(sensor_models[primary])]))}
    if spec.pd == "learned":
        sensor_models = {**sensor_models, primary: _with(
            sensor_models[primary], detection=learned_detection(sensor_models[primary]))}
    for sensor, stream in streams.items():
        _check_stream(sensor, stream, sensor_models[sensor] if spec.uses_context else None,
                      pose_source if spec.uses_context or spec.family == "gmphd" else None)
    region = None
    if spec.family == "gmphd":
        radius = (_region_radius([sensor_models[s] for s in streams]) if region_radius is None
                  else _given_radius(region_radius))
        region = PoseCentredRegion(pose_source=pose_source, radius=radius)
    predictor = KalmanPredictor(motion_model())
    # Symmetrised posteriors: the standard-form update P − K S Kᵀ lets round-off asymmetry
    # grow about 40-fold per 200 updates of a long-tracked target (measured, stock and core
    # alike), until covariances turn indefinite (a 240 s run, scan ~1900).
    updater = ExtendedKalmanUpdater(measurement_model=None, force_symmetric_covariance=True)
    detector = _detector(spec, streams, sensor_models, pose_source)
    if spec.family == "jpda":
        return _jpda(spec, predictor, updater, detector, fast)
    tracker = _gmphd(spec, region, predictor, updater, detector, fast)
    from ..stonesoup.learning import ClutterMapLearner, DetectionLearner, LearningTracker
    learners = []
    if spec.clutter == "learned":
        learners.append(ClutterMapLearner(
            weighting=MAP_WEIGHTING, gate_radius=LEARNING_GATE if MAP_WEIGHTING == "gates" else None))
    if spec.pd == "learned":
        learners.append(DetectionLearner(gate_radius=LEARNING_GATE))
    return LearningTracker(tracker=tracker, learners=learners) if learners else tracker


#: The learned radar clutter map (``gmphd-learned``), from the radar: its first edition's
#: settings were fixed before any run; the pooling, the ring prior's weight and the grid's
#: bearings were revised after its results showed the warm-up loss, the pool weight and
#: the feed after the second edition's sweep showed a loss with accurate bearings, and the
#: estimator (cells apart) after a 10-seed check of the third (``docs/study.md``): cells of 5° × 50 m in its bearing–range space — 5σ of its bearing
#: noise and 10σ of its range noise, so a point source's returns stay in one cell, and fine
#: enough to follow the sea clutter's step at 1 km and a coastline — over the bearings the
#: radar sees (its blind sector is not in the grid: no clutter is reported there, so its
#: cells would only learn λ ≈ 0 and pull their rings down). Cells are pooled by range ring
#: (``pooling='range'``): sea clutter depends on the grazing angle, i.e. on range, and only
#: slowly on bearing, so a ring's 59 cells share one level that is learned in a few scans,
#: where a cell alone needs ~100 (one far cell sees ~0.04 clutter points a scan). How far a
#: cell departs from its ring is not a constant but estimated from the ring's spread
#: (``pooling_scans=None``: a Gamma–Poisson hierarchy, :class:`~ctxmodels.ClutterMap`): a
#: fixed weight of 10 scans left a far cell to the noise of its ~4 discounted points, ±50 %,
#: while a ring whose cells agree should give them its level and a ring with a coast (~0.5
#: points a scan in one cell) should let that cell go. A cell its ring's level cannot
#: explain — a coast, or a static object's returns every scan — leaves the ring (and its
#: spread and level) by the map's Poisson tail test: such a source is not sea clutter,
#: and one of them made a whole ring's cells nearly unpooled. The ring's prior, λ 1e-3 per rad·m
#: (the uniform trackers' value, 10 times too low beyond 1 km by the paper's own λ_radar),
#: is a guess and worth one scan of the ring (59 cell-scans). Forgetting 0.99 per scan (a
#: memory of 100 scans, 2 minutes at 0.8 Hz: the scenes' clutter does not change faster).
#: Each detection counts as its posterior clutter probability in the GM-PHD update
#: (``weighting='posterior'``, :class:`~ctxmodels.stonesoup.ClutterMapLearner`): the
#: expected clutter count under the tracker's own model, so a target's returns count as
#: clutter only in proportion to how little the filter already believes in it (fully at
#: its first scan, less as its components gain weight, extracted or not). ``docs/study.md`` shows what depends on
#: these choices (``scripts/learned_warmup.py --settings``, ``scripts/learned_target_leak.py``).
MAP_BEARING_CELL, MAP_RANGE_CELL = math.radians(5.0), 50.0
MAP_PRIOR, MAP_PRIOR_SCANS, MAP_FORGETTING = 1e-3, 1.0, 0.99
MAP_POOLING, MAP_POOLING_SCANS = "range", None
MAP_WEIGHTING = "posterior"
#: Gates of 50 m around the tracks (:class:`~ctxmodels.stonesoup.DetectionLearner`'s
#: association): 3σ of the bearing error at 1 km hold a track's returns.
LEARNING_GATE = 50.0


def learned_clutter_map(model: SensorModel):
    """A fresh bearing–range clutter map over ``model``'s P_D reach and the bearings it sees
    (see :data:`MAP_PRIOR` and the constants beside it)."""
    from ..clutter_map import ClutterMap
    reach = _reach(model)
    if not math.isfinite(reach) or reach <= 0:
        raise ValueError("sensor_models: the learned clutter map covers the primary sensor's "
                         "reach, but its P_D has no outer range band with P_D = 0")
    low, high = _seen_bearings(model)
    bearings = np.linspace(low, high, max(1, round((high - low) / MAP_BEARING_CELL)) + 1)
    ranges = MAP_RANGE_CELL * np.arange(math.ceil(reach / MAP_RANGE_CELL) + 1)
    return ClutterMap(space="bearing-range", edges=(bearings, ranges), prior_intensity=MAP_PRIOR,
                      prior_scans=MAP_PRIOR_SCANS, forgetting=MAP_FORGETTING,
                      pooling=MAP_POOLING, pooling_scans=MAP_POOLING_SCANS)


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


#: The learned radar P_D (``gmphd-learned``): the hand-written model's range bands where it
#: is > 0 (the radar's range limits are specification) split into bands of about 200 m — a
#: radar's P_D falls with range (SNR ∝ R⁻⁴), and 8 bands still see a few targets each —
#: each a Beta posterior with prior mean 0.5 (nothing known but that the radar detects
#: something: a coin) worth 5 trials (four scans of one track overrule it), forgetting 0.99
#: per scan like the clutter map; the blind sector, land and line of sight stay as given.
PD_BAND, PD_PRIOR, PD_PRIOR_TRIALS, PD_FORGETTING = 200.0, 0.5, 5.0, 0.99


def learned_detection(model: SensorModel) -> DetectionProbabilityModel:
    """``model``'s P_D with its range bands replaced by one :class:`~ctxmodels.DetectionEstimate`
    over their support (see :data:`PD_BAND` and the constants beside it)."""
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
    count = max(1, round((high - low) / PD_BAND))
    estimate = DetectionEstimate(edges=np.linspace(low, high, count + 1), prior_probability=PD_PRIOR,
                                 prior_trials=PD_PRIOR_TRIALS, forgetting=PD_FORGETTING)
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


def _with_coast(model: SensorModel) -> SensorModel:
    """``model`` with a :class:`~ctxmodels.CoastalClutter` band along its P_D's land in λ."""
    from .. import CoastalClutter
    lands = [f for f in model.detection.factors if isinstance(f, LandMask)]
    lands += [f.land for f in model.detection.factors if isinstance(f, LineOfSight)]
    if not lands:
        raise ValueError("sensor_models: the coastal band follows the land in the primary "
                         "sensor's P_D (LandMask / LineOfSight factors); it has none")
    band = CoastalClutter(land=lands[0], width=COAST_WIDTH, inside=COAST_FACTOR)
    return _with(model, clutter=ClutterDensityModel(factors=[*model.clutter.factors, band]))


def _detector(spec: TrackerSpec, streams, sensor_models, pose_source):
    """The tracker's input: the sensors' scans in time order — with each scan's context
    for context-aware trackers, as plain sets for the uniform ones (stock behaviour)."""
    from ..stonesoup import ContextFeeder, MultiSensorFeeder
    if not spec.uses_context:
        return MultiSensorFeeder(feeders=list(streams.values()), sensor_names=list(streams))
    return MultiSensorFeeder(feeders=[
        ContextFeeder(reader=reader, sensor_model=sensor_models[sensor], pose_source=pose_source,
                      sensor_name=sensor)
        for sensor, reader in streams.items()], sensor_names=list(streams))


def _check_stream(sensor: str, stream, model: SensorModel | None, pose_source) -> None:
    """A stream given as a list (or tuple), checked before anything runs: each scan a
    (datetime, set of detections) pair in time order, each detection with the metadata the
    sensor's clutter rules read (``model``, for the context-aware trackers), each time within
    a :class:`~ctxmodels.NavigationTrack` pose source. Errors start ``streams:`` and name the
    sensor and the scan time. Readers and generators are checked as they are read (by the
    feeders, naming the sensor and scan the same way)."""
    from ..stonesoup.feeder import _check_metadata, _required_metadata, _scans
    if not isinstance(stream, (list, tuple)):
        return
    label = f" (sensor {sensor!r})"
    keys = _required_metadata(model) if model is not None else ()
    track = pose_source if isinstance(pose_source, NavigationTrack) else None
    for k, (time, detections) in enumerate(_scans(stream, "streams", label)):
        if not isinstance(time, datetime.datetime):
            raise TypeError(f"streams: scan {k} of sensor {sensor!r} has the time {time!r}; "
                            f"scan times must be datetimes")
        if keys:
            _check_metadata(time, detections, keys, "streams", label)
        if track is not None:
            try:
                track.pose_at(time)  # (a lookup: the log is in memory)
            except (TypeError, ValueError) as err:
                raise type(err)(f"pose_source: no pose for the scan at {time}{label}: "
                                f"{err}") from None


def _with(model: SensorModel, **changes) -> SensorModel:
    """``model`` with some Properties replaced (``clutter=...``, ``detection=...``)."""
    properties = {name: getattr(model, name) for name in type(model).properties}
    return type(model)(**{**properties, **changes})


def _sees_land(model: SensorModel) -> bool:
    return any(isinstance(f, (LandMask, LineOfSight)) for f in model.detection.factors)


def _reach(model: SensorModel) -> float:
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


def _given_radius(value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
            or not (math.isfinite(value) and value > 0):
        raise ValueError(f"region_radius: must be a finite number of metres > 0, got {value!r}")
    return float(value)


def _region_radius(models) -> float:
    reach = max(_reach(model) for model in models)
    if not math.isfinite(reach):
        raise ValueError("region_radius: a sensor's P_D has no outer range band with P_D = 0 "
                         "(a constant P_D, say), so its reach is unbounded; give the "
                         "surveillance region's radius (m)")
    return reach + REGION_MARGIN


def position_std_deleter():
    r"""Stone Soup's ``CovarianceBasedDeleter`` deleting a track whose RMS x/y position σ
    exceeds :data:`MAX_POSITION_STD`: the GM-PHD's bound (``retain_position_std`` keeps a
    component while :math:`P_{xx} + P_{yy} \le 2\sigma_{\max}^2`). Stone Soup 1.9.1 deletes
    when the sum of the ``mapping``'s diagonal entries of the last state's covariance is
    strictly greater than ``covar_trace_thresh`` (``mapping`` None or empty: the whole trace),
    so with the threshold :math:`2\sigma_{\max}^2` (80000 m², exact in floating point) it
    deletes exactly the tracks the GM-PHD bound would drop."""
    from stonesoup.deleter.error import CovarianceBasedDeleter
    return CovarianceBasedDeleter(covar_trace_thresh=2.0 * MAX_POSITION_STD ** 2,
                                  mapping=list(POSITION_MAPPING))


def _jpda(spec, predictor, updater, detector, fast):
    from stonesoup.deleter.multi import CompositeDeleter
    from stonesoup.deleter.time import UpdateTimeDeleter

    from ..stonesoup import CompositeDeleter as PairwiseCompositeDeleter
    from ..stonesoup import (ArrayJPDATracker, ArrayMultiMeasurementInitiator,
                             DuplicateTrackDeleter, ExpectedMissesDeleter, FastGNNWith2DAssignment,
                             MultiMeasurementInitiator, MultiTargetMixtureTracker,
                             PDAHypothesiser, UpdateTimeStepsDeleter)
    hypothesiser_class = PDAHypothesiser if spec.uses_context else StockPDAHypothesiser
    hypothesiser = hypothesiser_class(predictor, updater, clutter_spatial_density=UNIFORM_CLUTTER,
                                      prob_detect=UNIFORM_PD, prob_gate=JPDA_PROB_GATE)
    if spec.uses_context:
        deleter = CompositeDeleter(intersect=False, deleters=[
            ExpectedMissesDeleter(expected_misses=JPDA_EXPECTED_MISSES, hypothesiser=hypothesiser),
            position_std_deleter()])
    elif spec.delete_window is not None:
        deleter = UpdateTimeDeleter(time_since_update=datetime.timedelta(seconds=spec.delete_window))
    else:
        deleter = UpdateTimeStepsDeleter(time_steps_since_update=spec.delete_after)
    if spec.merge_duplicates:  # (ctxmodels' composite: Stone Soup's asks track by track)
        deleter = PairwiseCompositeDeleter(intersect=False, deleters=[
            deleter, DuplicateTrackDeleter(threshold=DUPLICATE_THRESHOLD, mapping=POSITION_MAPPING)])
    holding = (UpdateTimeStepsDeleter(time_steps_since_update=JPDA_DELETE_AFTER)
               if spec.confirm_window is None else
               UpdateTimeDeleter(time_since_update=datetime.timedelta(seconds=spec.confirm_window)))
    prior = GaussianState(np.zeros((4, 1)), np.diag(INIT_STD ** 2))
    # The array tracker and initiator compute each scan in the Rust core; the component
    # path is the readable reference with the same results.
    initiator = (ArrayMultiMeasurementInitiator if fast else MultiMeasurementInitiator)(
        prior_state=prior, deleter=holding,
        data_associator=(FastGNNWith2DAssignment if fast else GNNWith2DAssignment)(DistanceHypothesiser(
            predictor, updater, Mahalanobis(), missed_distance=GATE_MAHALANOBIS)),
        updater=updater, min_points=spec.min_points)
    return (ArrayJPDATracker if fast else MultiTargetMixtureTracker)(
        initiator=initiator, deleter=deleter, detector=detector,
        data_associator=JPDAwithEHM2(hypothesiser), updater=updater)


def _gmphd(spec, region, predictor, updater, detector, fast):
    from ..stonesoup.birth import MeasurementDrivenBirth
    from ..stonesoup.array_tracker import ArrayPointProcessTracker
    from ..stonesoup.pointprocess import PHDUpdater, PointProcessMultiTargetTracker
    hypothesiser = GaussianMixtureHypothesiser(DistanceHypothesiser(
        predictor, updater, Mahalanobis(), missed_distance=GATE_MAHALANOBIS),
        order_by_detection=True)
    phd_class = PHDUpdater if spec.uses_context else StockPHDUpdater
    phd = phd_class(updater, clutter_spatial_density=UNIFORM_CLUTTER, prob_detection=UNIFORM_PD)
    # (Uniform trackers get plain sets, so even the context-capable fast updater runs stock.)
    reducer = GaussianMixtureReducer(prune_threshold=PRUNE_THRESHOLD,
                                     merge_threshold=MERGE_MAHALANOBIS ** 2)
    birth = MeasurementDrivenBirth(birth_weight=BIRTH_WEIGHT, birth_covar=np.diag(INIT_STD ** 2))
    # The array tracker computes each scan in the Rust core; the component path is the
    # readable reference with the same results.
    tracker_class = ArrayPointProcessTracker if fast else PointProcessMultiTargetTracker
    return tracker_class(
        detector=detector, hypothesiser=hypothesiser, updater=phd, reducer=reducer,
        extraction_threshold=spec.extraction_threshold, birth=birth,
        surveillance_region=region, max_position_std=MAX_POSITION_STD)
