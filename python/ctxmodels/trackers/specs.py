"""The study's trackers by name (the paper's Table I and ours) and their settings; built for
anyone's sensor data by :func:`~ctxmodels.trackers.paper_tracker`.

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
:class:`~ctxmodels.trackers.models.ClutterMapSettings`); the lidar keeps the paper's ``area``
rule. GM-PHD (learned λ, P_D, ours): the same with the radar's range-band P_D learned as well
(:class:`~ctxmodels.DetectionEstimate`, :class:`~ctxmodels.stonesoup.DetectionLearner`;
:class:`~ctxmodels.trackers.models.DetectionEstimateSettings`); its blind sector stays as specified.

Reported tracks are Stone Soup's: a GM-PHD track is created when a component's weight
exceeds the extraction threshold and continues, one state per scan, while its tagged
component survives; the metrics look at the states at radar timestamps.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .models import ClutterMapSettings, DetectionEstimateSettings

#: Table I: the global P_D and λ (per rad·m or m², as the sensor measures) of the JPDA and
#: the uniform / radar-only GM-PHD.
UNIFORM_PD = 0.4
UNIFORM_CLUTTER = 1e-3
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
    #: The primary's λ also has a coastal band
    #: (:data:`~ctxmodels.trackers.models.COAST_WIDTH`) along its P_D's land.
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
    #: The learned trackers' clutter map and P_D estimate (read where ``clutter`` / ``pd``
    #: is ``"learned"``); a variant is a spec with a replaced copy.
    clutter_map: ClutterMapSettings = ClutterMapSettings()
    detection_estimate: DetectionEstimateSettings = DetectionEstimateSettings()
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
                "context-aware plus land mask and radar shadow (the islands; the Solent's real "
                "coast)", "gmphd", pd="context", clutter="context", line_of_sight=True,
                only_scenarios=("islands", "solent"), cost=2.1),
    TrackerSpec("gmphd-coastal", "GM-PHD (line-of-sight, coastal λ)",
                "line-of-sight-aware plus a hand-written coastal band in the radar's λ",
                "gmphd", pd="context", clutter="context", line_of_sight=True, coastal=True,
                only_scenarios=("islands",), cost=1.9),
)}
