"""SensorModel: the declarative configuration of one sensor, and its per-scan contexts."""
from __future__ import annotations

import datetime
from collections.abc import Callable, Sequence

from stonesoup.base import Property

from ._component import ModelComponent, as_int, as_position_mapping, velocity_indices
from .errors import ArgumentError, ArgumentTypeError
from .clutter import ClutterDensityModel
from .detection import MAX_ORDER, PD_RULES, DetectionProbabilityModel
from .detection_estimate import DetectionEstimate
from .horizon import RadarHorizon
from .range_rate import RangeRateNotch
from .pose import Mounting, Pose, as_pose

#: What :meth:`SensorModel.context` and :meth:`SensorModel.from_stonesoup` call, registered
#: (:func:`provide`) by the modules that hold them: ``"context"`` by :mod:`ctxmodels.context`
#: (``DetectorContext._of``; that module imports this one for its Property types) and
#: ``"from_stonesoup"`` by :mod:`ctxmodels.stonesoup.sensor_adapter` (the Stone Soup adapters
#: build on the core). So this module imports neither (no import circle); ``import
#: ctxmodels`` imports both.
_PROVIDED: dict[str, Callable] = {}


def provide(name: str, function: Callable) -> None:
    """Registers ``function`` as what ``SensorModel.<name>`` calls (see :data:`_PROVIDED`)."""
    _PROVIDED[name] = function


def _provided(name: str) -> Callable:
    try:
        return _PROVIDED[name]
    except KeyError:
        raise RuntimeError(f"SensorModel.{name}: its module is not imported yet "
                           "(import ctxmodels first)") from None


class SensorModel(ModelComponent):
    r"""One sensor's observability: its P_D model, its clutter model, where its position
    sits in the track state, and where it is mounted on the platform.

    :meth:`context` builds the :class:`~ctxmodels.DetectorContext` of one scan from the
    platform pose at that scan. ``pd_evaluation`` chooses how P_D of a Gaussian track is
    taken: ``'mean'`` evaluates :math:`P_D` at the mean (Stone Soup's convention); the
    others integrate :math:`E[P_D(p)],\ p \sim \mathcal{N}(m, P)` over the position block
    of the covariance with the third-degree cubature rule (4 points), the unscented
    transform (5 points) or a ``pd_order``×``pd_order`` Gauss–Hermite rule.
    """

    detection: DetectionProbabilityModel = Property(doc="P_D(x; S).")
    clutter: ClutterDensityModel = Property(doc="λ(z; S), in the detections' measurement space.")
    position_mapping: Sequence[int] = Property(
        default=(0, 2), doc="Indices of x and y in the track state (Stone Soup CV: (0, 2)), or "
                            "of x, y and z for a sensor that covers heights (ranges are then "
                            "slant ranges from the pose's z; λ is read on the x/y plane).")
    velocity_mapping: Sequence[int] = Property(
        default=None, doc="Indices of the velocity in the track state, as many as "
                          "position_mapping's (Stone Soup CV: (1, 3), or (1, 3, 5) in 3-D): "
                          "read by a RangeRateNotch; None: no factor reads velocities.")
    mounting: Mounting = Property(default=None, doc="Sensor mounting on the platform; "
                                                    "default: at the platform's reference point.")
    pd_evaluation: str = Property(default="mean", doc="One of 'mean', 'cubature', "
                                                      "'unscented', 'gauss-hermite'.")
    pd_order: int = Property(default=3, doc="Nodes per axis of the Gauss–Hermite rule.")
    name: str = Property(default="", doc="A label for plots and logs.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if not isinstance(self.detection, DetectionProbabilityModel):
            raise TypeError(f"detection: expected a DetectionProbabilityModel, "
                            f"got {type(self.detection).__name__}")
        if not isinstance(self.clutter, ClutterDensityModel):
            raise TypeError(f"clutter: expected a ClutterDensityModel, "
                            f"got {type(self.clutter).__name__}")
        # Any integer type (NumPy's too), stored as a tuple of ints.
        self._replace("position_mapping", as_position_mapping(self.position_mapping, heights=True))
        if self.velocity_mapping is not None:
            self._replace("velocity_mapping", velocity_indices(self.velocity_mapping,
                                                                self.position_mapping))
        if self.pd_evaluation not in PD_RULES:
            raise ValueError(f"pd_evaluation: must be one of {PD_RULES}, got {self.pd_evaluation!r}")
        try:
            self._replace("pd_order", as_int(self.pd_order, "pd_order", low=1, high=MAX_ORDER))
        except ArgumentTypeError as err:  # a non-integer order is a ValueError here
            raise ArgumentError(err.argument, err.detail) from None
        if self.mounting is not None and not isinstance(self.mounting, Mounting):
            raise TypeError(f"mounting: expected a Mounting, got {type(self.mounting).__name__}")
        self._check_reads()

    def _check_reads(self) -> None:
        """The state must hold what the factors read: a height for a horizon at each
        target's height, a velocity for a range-rate notch; and learned P_D bands, learned
        per plane range, are not read per slant range."""
        factors = self.detection.factors
        spatial = len(self.position_mapping) == 3
        if not spatial and any(isinstance(f, RadarHorizon) and f.target_height is None
                               for f in factors):
            raise ArgumentError("position_mapping", f"{tuple(self.position_mapping)} gives no "
                                "height, but the radar horizon is at each target's height "
                                "(target_height=None); give the (x, y, z) indices")
        if self.velocity_mapping is None and any(isinstance(f, RangeRateNotch) for f in factors):
            raise ArgumentError("velocity_mapping", "is not given, but the RangeRateNotch reads "
                                "each target's velocity; give the state's velocity indices")
        if not spatial and self.clutter.uses_height:
            raise ArgumentError("position_mapping", f"{tuple(self.position_mapping)} gives no "
                                "height, but the clutter model's ElevationSector reads each "
                                "detection's height; give the (x, y, z) indices")
        if spatial and any(isinstance(f, DetectionEstimate) for f in factors):
            raise ArgumentError("position_mapping", "a DetectionEstimate learns P_D per plane "
                                "range, which a model with heights would read per slant range; "
                                "give the (x, y) indices")

    @property
    def core_mapping(self) -> tuple[int, ...]:
        """The state columns the core reads: ``position_mapping`` then ``velocity_mapping``."""
        return tuple(self.position_mapping) + tuple(self.velocity_mapping or ())

    @property
    def plane_mapping(self) -> tuple[int, int]:
        """The state indices of x and y: the plane below a target with a height, where
        births and what is learned from detections are read (λ reads the heights too)."""
        return tuple(self.position_mapping[:2])

    def sensor_pose(self, platform_pose: Pose) -> Pose:
        """The sensor's own pose on a platform at ``platform_pose``."""
        return platform_pose if self.mounting is None else self.mounting.apply(platform_pose)

    @classmethod
    def from_stonesoup(cls, sensor, prob_detection: float, clutter_density: float,
                       *, name: str = "") -> SensorModel:
        """The model of a Stone Soup radar's coverage (range limit, rotating field of view)
        with P_D ``prob_detection`` inside it and λ ``clutter_density``; its pose at a scan
        is :func:`ctxmodels.stonesoup.sensor_pose`. See
        :mod:`ctxmodels.stonesoup.sensor_adapter`, which does the conversion."""
        return _provided("from_stonesoup")(cls, sensor, prob_detection, clutter_density,
                                           name=name)

    def context(self, pose: Pose | Sequence[float], timestamp: datetime.datetime | None = None):
        """The :class:`~ctxmodels.DetectorContext` of a scan taken with the *platform* at
        ``pose`` (a :class:`Pose` or an (x, y, heading) triple)."""
        return _provided("context")(self, self.sensor_pose(as_pose(pose)), timestamp)
