"""Type stubs for ``ctxmodels._core``, the compiled Rust core (source: rust/python.rs).

Array arguments must already be C-contiguous NumPy arrays of the stated dtype (rows of
float64; unaligned ones are copied); the Python components (``ctxmodels.RangeBands`` and
friends) convert and validate user input before calling in. ``out=`` buffers (aligned,
writeable) are filled in place and returned; one that overlaps an input of the call, or that
another call is writing, is a ``ValueError`` naming ``out``. ``order`` must be in 1..32 for
every rule.
"""
from collections.abc import Sequence
from typing import Any, Literal, TypeAlias, final, overload

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "AngularSector",
    "ClutterAtPose",
    "ClutterMap",
    "CoastalBand",
    "DetectionEstimate",
    "ClutterModel",
    "DetectionAtPose",
    "DetectionModel",
    "ElevationSector",
    "GaussianMixtureArrays",
    "Horizon",
    "RangeRateNotch",
    "MeasurementModel",
    "LandMask",
    "LineOfSight",
    "MetadataThreshold",
    "RadarEquation",
    "RangeBands",
    "Zone",
    "jpda_marginals",
    "jpda_predict",
    "jpda_scan",
    "initiator_births",
    "initiator_scan",
    "mount",
    "rule_points",
    "simd_backend",
]

_Pose: TypeAlias = (
    tuple[float, float, float]
    | tuple[float, float, float, float]
    | tuple[float, float, float, float, float, float, float]
    | tuple[float, float, float, float, float, float, float, float, float]
)
# `position_mapping` defaults to (0, 2) (Stone Soup's [x, vx, y, vy]). It is written `...`
# below because PyO3 renders a tuple default as `...` in the runtime signature, and stubtest
# (run bare by scripts/test.sh) checks stub defaults against that rendering.
# (x, y) or (x, y, z), then the velocity's (vx, vy) or (vx, vy, vz) where a factor reads it
_Mapping: TypeAlias = (
    tuple[int, int]
    | tuple[int, int, int]
    | tuple[int, int, int, int]
    | tuple[int, int, int, int, int, int]
)
_Floats: TypeAlias = NDArray[np.float64]
_Bools: TypeAlias = NDArray[np.bool_]
_Rule: TypeAlias = Literal["mean", "cubature", "unscented", "gauss-hermite"]

@final
class RangeBands:
    """Piecewise-constant value over range; ``upper_owns[i]``: r == edges[i] is in the band above."""

    def __new__(
        cls, edges: Sequence[float], values: Sequence[float], upper_owns: Sequence[bool]
    ) -> RangeBands: ...
    def at(self, ranges: _Floats) -> _Floats:
        """Values at each of `ranges` (±inf lie beyond / before every edge; NaN is an error)."""

@final
class RadarEquation:
    """P_D of a Swerling case 0–4 target, `pulses` pulses summed, from the SNR
    `reference_snr` (dB) at `reference_range` (m), SNR ∝ r⁻⁴, less `loss` (dB), against
    the threshold of `false_alarm_probability`."""

    def __new__(
        cls,
        reference_snr: float,
        reference_range: float,
        loss: float,
        false_alarm_probability: float,
        swerling: int,
        pulses: int,
    ) -> RadarEquation: ...
    @property
    def threshold(self) -> float:
        """The detection threshold on the sum of the pulses' powers (noise power 1)."""
    def at(self, ranges: _Floats) -> _Floats:
        """P_D at each of `ranges` (metres; NaN gives NaN)."""
    def snr(self, ranges: _Floats) -> _Floats:
        """The per-pulse SNR (linear) at each of `ranges`."""

@final
class ElevationSector:
    """``inside`` between the elevations ``lower`` and ``upper`` (radians above the
    sensor's horizontal plane), else ``outside``."""

    def __new__(cls, lower: float, upper: float, inside: float, outside: float) -> ElevationSector: ...

@final
class Horizon:
    """1 within the radar horizon of a target at its own height: plane distance at most
    ``antenna_reach`` + √(``scale`` · max(z, 0)), 0 beyond."""

    def __new__(cls, antenna_reach: float, scale: float) -> Horizon: ...

@final
class RangeRateNotch:
    """``inside`` where the radial speed is within ``width`` of 0 (or of the first
    ``multiples`` multiples of ``blind_speed``), else ``outside``."""

    def __new__(
        cls, width: float, blind_speed: float | None, multiples: int, inside: float, outside: float
    ) -> RangeRateNotch: ...

@final
class AngularSector:
    """Body-frame sector: ``inside`` within ``width / 2`` of ``centre`` (radians), else ``outside``."""

    def __new__(cls, centre: float, width: float, inside: float, outside: float) -> AngularSector: ...

@final
class LandMask:
    """Validated land polygons with a containment index; boundary counts as land."""

    def __new__(cls, polygons: Sequence[tuple[_Floats, Sequence[_Floats]]]) -> LandMask:
        """`polygons`: list of (shell, [holes]) with rings as (K, 2) float64 arrays."""
    def contains(self, points: _Floats) -> _Bools:
        """Whether each (x, y) row of `points` is on land (boundary included); NaN/±inf rows
        are an error."""
    @property
    def vertex_count(self) -> int: ...

@final
class LineOfSight:
    """Occlusion of sensor → target segments by a :class:`LandMask`."""

    def __new__(cls, land: LandMask, clearance: float = 0.0) -> LineOfSight: ...
    def visible(self, sensor: tuple[float, float], targets: _Floats) -> _Bools:
        """Whether each target row of `targets` (M, 2) is visible from `sensor` (x, y); NaN/±inf
        are an error."""

@final
class DetectionModel:
    """P_D as the product of its factors (each in [0, 1])."""

    def __new__(
        cls,
        factors: Sequence[
            float
            | RangeBands
            | AngularSector
            | RadarEquation
            | ElevationSector
            | Horizon
            | RangeRateNotch
            | LandMask
            | LineOfSight
            | DetectionEstimate
        ],
    ) -> DetectionModel:
        """`factors`: floats (constants), RangeBands, AngularSector, LandMask (0 on land),
        LineOfSight (0 when shadowed), DetectionEstimate (shared, read as it stands). P_D is
        their product."""
    def evaluate(
        self,
        pose: _Pose,
        states: _Floats,
        position_mapping: _Mapping = ...,
        out: _Floats | None = None,
    ) -> _Floats:
        """P_D at the positions of `states` (N, D) for a sensor at `pose` (x, y, heading)."""
    @overload
    def evaluate_particles(
        self,
        pose: _Pose,
        particles: _Floats,
        position_mapping: _Mapping = ...,
        log: bool = False,
        missed: Literal[False] = False,
    ) -> _Floats:
        """P_D at each particle of `particles` (D, N), C- or Fortran-ordered, read in place;
        `log`: log P_D (log 0 = -inf, NumPy's bits); `missed`: also 1 − P_D (or its log),
        returned as a pair."""
    @overload
    def evaluate_particles(
        self,
        pose: _Pose,
        particles: _Floats,
        position_mapping: _Mapping = ...,
        log: bool = False,
        *,
        missed: Literal[True],
    ) -> tuple[_Floats, _Floats]: ...
    def expected(
        self,
        pose: _Pose,
        means: _Floats,
        covars: _Floats,
        position_mapping: _Mapping = ...,
        rule: _Rule = "cubature",
        order: int = 3,
        out: _Floats | None = None,
    ) -> _Floats:
        """Expected P_D of Gaussians (`means` (N, D), `covars` (N, D, D)) under `rule`."""

@final
class DetectionAtPose:
    """A detection model fixed at one sensor pose and position mapping (a detector
    context's thin calls): the common case only, None for anything else."""

    def __new__(
        cls,
        model: DetectionModel,
        pose: _Pose,
        position_mapping: _Mapping = ...,
        rule: _Rule = "mean",
        order: int = 3,
    ) -> DetectionAtPose: ...
    def evaluate(self, states: object, out: object | None = None) -> _Floats | None:
        """P_D at each row of `states` (N, D), into `out` if given; None (nothing evaluated)
        unless `states` is a C-contiguous, aligned float64 2-D array.

        An `out` that is not a float64 (N,) C-contiguous, aligned array also returns None
        (the Python layer's check names what is wrong with it)."""
    def at(self, vector: object) -> float | None:
        """P_D at one state vector, a float64 (D, 1) column or (D,) array whose position is
        finite: the same bits as a row of [`Self::evaluate`]. None for anything else."""
    def expected_at(self, vector: object, state: object) -> float | None:
        """Expected P_D under the rule over one Gaussian: `vector` a float64 (D, 1) column or
        (D,) array, the mean of `state`, whose `covar` is read only then (a particle state
        computes it) and must be a float64 (D, D) array; the same bits as a row of the
        model's `expected`. None for anything else, or a position or covariance block the
        general path refuses (it then names the fault)."""

@final
class ClutterAtPose:
    """A clutter model fixed at one sensor pose (a detector context's thin calls): the
    common case only, None for anything else."""

    def __new__(cls, model: ClutterModel, pose: _Pose) -> ClutterAtPose: ...
    def evaluate(
        self, positions: object, metadata: object | None = None, out: object | None = None
    ) -> _Floats | None:
        """λ at world `positions` (M, 2) with `metadata` (M, K) in the model's column order
        (None when the model reads no metadata), into `out` if given. None (nothing
        evaluated) unless every array is a C-contiguous, aligned float64 array of its shape."""

@final
class MetadataThreshold:
    """λ factor from metadata column ``column``: ``below`` if value < threshold, else
    ``at_or_above``; ``missing`` for NaN (None: NaN is an error)."""

    def __new__(
        cls,
        column: int,
        threshold: float,
        below: float,
        at_or_above: float,
        missing: float | None = None,
    ) -> MetadataThreshold: ...

@final
class ClutterModel:
    """λ as the product of its factors (each finite and > 0)."""

    def __new__(
        cls,
        factors: Sequence[
            float | RangeBands | MetadataThreshold | ClutterMap | CoastalBand | Zone | ElevationSector
        ],
    ) -> ClutterModel:
        """`factors`: floats (constants), RangeBands (over range from the sensor),
        MetadataThreshold rules, clutter maps, coastal bands, zones and elevation sectors.
        λ is their product."""
    @property
    def metadata_columns(self) -> int: ...
    @property
    def uses_position(self) -> bool: ...
    @property
    def uses_height(self) -> bool: ...
    def evaluate(
        self,
        pose: _Pose,
        positions: _Floats,
        metadata: _Floats,
        out: _Floats | None = None,
        ranges: _Floats | None = None,
    ) -> _Floats:
        """λ at world `positions` (M, 2), or (M, 3) with heights (slant ranges, elevations),
        with `metadata` (M, metadata_columns), NaN = missing; range bands read `ranges[i]`
        (a measured range) where given and not NaN."""

@final
class ClutterMap:
    """A clutter-intensity map learned online (Gamma posterior per cell, forgetting)."""

    def __new__(
        cls,
        space: Literal["bearing-range", "body-xy", "world-xy"],
        edges0: Sequence[float],
        edges1: Sequence[float],
        prior_intensity: float,
        prior_scans: float,
        forgetting: float,
        counts: Sequence[float] | None = None,
        deficit: Sequence[float] | None = None,
        exposure: float = 0.0,
        scale: float = 1.0,
        pooling: Literal["none", "range", "grid"] = "none",
        pooling_scans: float | None = ...,  # 10.0
    ) -> ClutterMap:
        """`space`: "bearing-range", "body-xy" or "world-xy"; `edges0`, `edges1`: the grid's
        edges on each axis (bearing or x, then range or y); the prior's intensity and weight
        in scans; the forgetting factor per scan; optionally a saved state; the pooling
        ("none", "range" or "grid") and its weight in scans."""
    @property
    def shape(self) -> tuple[int, int]: ...
    def update(
        self,
        pose: _Pose,
        positions: _Floats,
        ranges: _Floats | None = None,
        gates: _Floats | None = None,
        weights: _Floats | None = None,
    ) -> None:
        """One scan: its detections' world `positions` (M, 2), measured `ranges` (M,) or None
        (NaN entries: from the position), `gates` (G, 3: x, y, radius) around tracks, and
        optionally each detection's clutter probability `weights` (M,) in [0, 1]."""
    def intensity(self, pose: _Pose, positions: _Floats, ranges: _Floats | None = None) -> _Floats:
        """λ of the map alone at world `positions` (M, 2) (the prior outside the grid)."""
    def intensities(self) -> _Floats:
        """The posterior mean λ of every cell, (n0 · n1,) row-major."""
    def state(self) -> tuple[_Floats, _Floats, float, float]:
        """(counts, deficit, exposure, scale): the state an update changes, as stored (see the
        core)."""

@final
class Zone:
    """A factor: `inside` within a set of polygons (boundary included), `outside` elsewhere."""

    def __new__(cls, polygons: LandMask, inside: float, outside: float) -> Zone:
        """`inside` within `polygons` (boundary included), `outside` elsewhere."""

@final
class CoastalBand:
    """A clutter factor, higher within a width of a coastline the sensor sees."""

    def __new__(cls, land: LandMask, width: float, inside: float, seen_only: bool) -> CoastalBand:
        """λ × `inside` within `width` m of `land`'s coastline (`seen_only`: coast the sensor
        sees), × 1 elsewhere."""
    def evaluate(self, pose: _Pose, positions: _Floats) -> _Floats:
        """The factor at world `positions` (M, 2) for a sensor at `pose`."""

@final
class DetectionEstimate:
    """A detection probability learned online per range band (Beta posterior, forgetting)."""

    def __new__(
        cls,
        edges: Sequence[float],
        prior_probability: float,
        prior_trials: float,
        forgetting: float,
        outside: float,
        hits: Sequence[float] | None = None,
        trials: Sequence[float] | None = None,
    ) -> DetectionEstimate:
        """Band `edges` (m of range); the prior's P_D and weight in trials; the forgetting
        factor per update; the value outside the bands; optionally a saved state."""
    def update(self, pose: _Pose, positions: _Floats, detected: _Floats, weights: _Floats) -> None:
        """One scan's trials: track `positions` (M, 2), `detected` (M,) 0/1, `weights` (M,)."""
    def probabilities(self) -> _Floats:
        """The posterior mean P_D of every band."""
    def state(self) -> tuple[_Floats, _Floats]:
        """(hits, trials): the state an update changes."""

def mount(
    pose: _Pose, forward: float, left: float, yaw: float, up: float = 0.0
) -> tuple[float, float, float, float]:
    """The pose (x, y, heading, z) of a sensor mounted on a platform at `pose`."""

def rule_points(rule: _Rule, order: int = 3) -> tuple[list[tuple[float, float]], list[float]]:
    """Points and weights of an integration rule in standard-normal space."""

def simd_backend() -> Literal["avx2", "portable"]:
    """The build of the array kernels this process runs (``CTXMODELS_SIMD=portable`` forces
    the portable one); both give the same bits."""

# --- GM-PHD scan core (rust/gmphd, binding rust/python/mixture.rs) -----------------------

@final
class MeasurementModel:
    """A measurement model of the scan cores (`GaussianMixtureArrays.update`, `jpda_scan`,
    `initiator_scan`, `initiator_births`)."""

    @staticmethod
    def linear(
        matrix: _Floats, noise_covar: _Floats, pseudo_inverse: _Floats | None = None
    ) -> MeasurementModel:
        """A linear Gaussian model: `matrix` (m, D), `noise_covar` (m, m); `pseudo_inverse`
        (D, m): the H⁺ of new tracks (default: the core's SVD)."""
    @staticmethod
    def bearing_range(
        mapping: tuple[int, int],
        translation_offset: tuple[float, float],
        rotation_matrix: _Floats,
        noise_covar: _Floats,
        jacobian: Literal["finite-difference", "analytic"] = "finite-difference",
        inverse_rotation_matrix: _Floats | None = None,
    ) -> MeasurementModel:
        """A 2-D bearing–range model (Stone Soup's `CartesianToBearingRange`);
        `inverse_rotation_matrix`: the inverse function's R⁻¹ (default: the core's inverse)."""
    @property
    def ndim_meas(self) -> int:
        """Number of measured values per detection."""

@final
class GaussianMixtureArrays:
    """Gaussian components as arrays, updated scan by scan in place (see `ctxmodels.gmphd`)."""

    def __new__(cls, ndim: int) -> GaussianMixtureArrays: ...
    def __len__(self) -> int: ...
    @property
    def ndim(self) -> int: ...
    @property
    def next_tag(self) -> int: ...
    def reserve_tags(self, count: int) -> int:
        """`count` fresh tags; returns the first."""
    def extend(
        self,
        means: _Floats,
        covars: _Floats,
        weights: _Floats,
        tags: Sequence[int],
        times: Sequence[int],
    ) -> None:
        """Appends components: `means` (N, D), `covars` (N, D, D), `weights` (N,), `tags`
        (0 = birth, others reserved), `times` (integer clock)."""
    def extend_births(
        self,
        means: _Floats,
        covar: _Floats,
        weights: _Floats,
        time: int,
        circle: tuple[tuple[int, int], tuple[float, float], float] | None = None,
    ) -> None:
        """Births at the `means` rows (N, D), each with `covar` (D, D), its `weights` entry, tag 0 and
        `time`; with `circle` = `(position_mapping, centre, radius)` only those inside it."""
    def distinct_times(self) -> list[int]:
        """The distinct component times, ascending."""
    def predict(
        self, from_times: Sequence[int], now: int, transitions: _Floats, noises: _Floats
    ) -> None:
        """Kalman prediction to `now`: components stamped `from_times[g]` use
        `transitions[g]`, `noises[g]`; all then take the time `now`."""
    def update(
        self,
        model: MeasurementModel,
        detections: _Floats,
        prob_detection: _Floats,
        clutter: _Floats,
        *,
        prob_survival: float,
        missed_distance: float,
        squared: bool,
        include_all: bool,
        normalise: bool,
        skip_undetectable: bool,
        time: int,
        force_symmetric: bool = False,
    ) -> _Floats:
        """The GM-PHD update with one scan's `detections` (M, m), `prob_detection` per
        component and `clutter` (λ) per detection; returns each detection's posterior
        clutter probability (M,)."""
    def prob_detection(self, at_pose: DetectionAtPose) -> _Floats | None:
        """P_D at each component's mean from `at_pose`, read in place (the same bits as
        `at_pose.evaluate(self.means())`); None when the core cannot evaluate them."""
    def retain(self, keep: Sequence[bool]) -> None:
        """Keeps the components whose flag is true."""
    def retain_inside_circle(
        self, position_mapping: tuple[int, int], centre: tuple[float, float], radius: float
    ) -> None:
        """Keeps the components whose `position_mapping` x/y lies in the disc of `radius`
        around `centre` (boundary included)."""
    def take_from(self, other: GaussianMixtureArrays, take: Sequence[bool]) -> None:
        """Moves the components of `other` whose flag in `take` is true to the end of this
        mixture, in order; the others stay in `other`."""
    def retain_position_std(self, position_mapping: tuple[int, int], max_std: float) -> None:
        """Keeps the components with `√(tr P_xy / 2) ≤ max_std`."""
    def reduce(
        self,
        *,
        pruning: bool,
        prune_threshold: float,
        merging: bool,
        merge_threshold: float,
        truncating: bool,
        max_components: int,
        kdtree_max_distance: float | None = None,
    ) -> None:
        """Prune, merge (and make tags unique), truncate, as `GaussianMixtureReducer`."""
    def track_states(self, tracked: Sequence[int], threshold: float
                     ) -> tuple[list[int], list[float], _Floats, _Floats, list[int]]:
        """The rows extending a ``tracked`` tag's track or above ``threshold`` (births
        excepted), as tags, weights, means (k, D, 1) and covariances (k, D, D), and the
        ``tracked`` tags no row carries any more."""
    def means(self) -> _Floats: ...
    def covars(self) -> _Floats: ...
    def weights(self) -> _Floats: ...
    def tags(self) -> NDArray[np.uint64]: ...
    def times(self) -> NDArray[np.int64]: ...
    def __reduce__(self) -> tuple[Any, ...]: ...
    def __setstate__(self, state: tuple[Any, ...]) -> None: ...
# --- whole-scan JPDA (source: rust/python/jpda.rs) ------------------------------------------
# Used by ctxmodels.stonesoup.ArrayJPDATracker; see rust/jpda.rs for the mathematics.

def jpda_predict(
    means: _Floats,
    covars: _Floats,
    transition_index: Sequence[int],
    transition_matrices: _Floats,
    transition_covars: _Floats,
) -> tuple[_Floats, _Floats]:
    """Kalman prediction of `means` (T, D) / `covars` (T, D, D) with transition
    `transition_index[t]` of `transition_matrices` / `transition_covars` (K, D, D)."""

def jpda_scan(
    model: MeasurementModel,
    means: _Floats,
    covars: _Floats,
    detections: _Floats,
    prob_detect: _Floats | DetectionAtPose,
    clutter_density: _Floats,
    prob_gate: float,
    gate_threshold: float,
    include_all: bool = False,
    *,
    transition_index: Sequence[int] | None = None,
    transition_matrices: _Floats | None = None,
    transition_covars: _Floats | None = None,
    force_symmetric: bool = False,
) -> dict[str, _Floats | _Bools]:
    """One JPDA scan: keys means, covars, is_update, taken, gated, weights, marginals,
    meas_means, meas_covars, cross_covars, prob_detect (the P_D used) and, with the
    transitions (the states are then the tracks' last ones, predicted first), pred_means
    and pred_covars. `prob_detect`: one P_D per track, or a `DetectionAtPose` read at each
    predicted mean."""

def jpda_marginals(weights: _Floats, gated: _Bools) -> _Floats:
    """Exact joint association marginals of (T, M+1) weights (column 0: missed detection)
    and the (T, M) gated hypotheses."""

def initiator_scan(
    models: Sequence[MeasurementModel],
    means: _Floats,
    covars: _Floats,
    transition_index: NDArray[np.int64],
    transition_matrices: _Floats,
    transition_covars: _Floats,
    detections: _Floats,
    model_index: NDArray[np.int64],
    missed_distance: float,
    points: NDArray[np.int64],
    since: NDArray[np.int64],
    new_time: _Bools,
    *,
    squared: bool = False,
    include_all: bool = False,
    force_symmetric: bool = False,
    updates_only: bool = False,
    min_points: int = 2,
) -> dict[str, NDArray[Any]]:
    """One scan of the M-of-N initiator's holding rows: prediction of the last states
    `means` (H, D) / `covars` (H, D, D) (row h with transition `transition_index[h]`),
    Mahalanobis gate against `detections` (M, m) (detection j measured by
    `models[model_index[j]]`), GNN 2-D assignment (missed cost `missed_distance`), Kalman
    update of the assigned rows and the M-of-N counts. Keys pred_means, pred_covars, means,
    covars, assigned (−1: missed), distances, meas_means, meas_covars, cross_covars (per
    updated row, in row order), points, since, released (whether an unreleased row
    is deleted is the caller's deleter's verdict)."""

def initiator_births(
    models: Sequence[MeasurementModel],
    detections: _Floats,
    model_index: NDArray[np.int64],
    prior_mean: _Floats,
    prior_covar: _Floats,
    diag_load: float = 0.0,
) -> tuple[_Floats, _Floats]:
    """The M-of-N initiator's new tracks, as Stone Soup's `SimpleMeasurementInitiator` builds
    them (to rounding): for `detections` (M, m), detection j measured by
    `models[model_index[j]]`, the means (M, D) and covariances (M, D, D) from the prior
    `prior_mean` (D,) / `prior_covar` (D, D) with its mapped entries zeroed, the model's
    inverse (H⁺ z, or the bearing–range inverse function), `J⁺ R J⁺ᵀ` and `diag_load` on
    the diagonal."""

# --- end of whole-scan JPDA -------------------------------------------------------------------
