"""The paper's sensor models (Section IV-B, eqs. pd-lidar, pd-radar, lambda-lidar,
lambda-radar) as ctxmodels :class:`~ctxmodels.SensorModel` objects, and the uniform
models of the baseline trackers (Table I: P_D 0.4, λ 1e-3).

λ is a density in each sensor's *measurement space*: per rad·m for the bearing–range radar
(its detections carry a ``CartesianToBearingRange`` model), per m² for the lidar (x/y
centroids). The paper's values are used as given in both spaces; the simulator documents
what the true clutter densities are (``ctxmodels.experiment.scenarios``).
"""
from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .. import (AngularSector, ClutterDensityModel, DetectionProbabilityModel, LandMask,
                LineOfSight, MetadataThreshold, RangeBands, SensorModel)
from ..trackers.specs import UNIFORM_CLUTTER, UNIFORM_PD


def radar_detection(land: Sequence[np.ndarray] = ()) -> DetectionProbabilityModel:
    """eq. pd-radar: 0.4 for 50 < r < 1612 m outside the 65° blind sector astern, else 0.
    With ``land``: also 0 on land and in the radar shadow behind it (line of sight)."""
    factors: list = [
        RangeBands(edges=(50.0, 1612.0), values=(0.0, 0.4, 0.0), upper_owns=(False, True)),
        AngularSector.blind(math.pi, math.radians(65.0)),
    ]
    if len(land):
        mask = LandMask(polygons=list(land))
        factors += [mask, LineOfSight(land=mask)]
    return DetectionProbabilityModel(factors=factors)


def lidar_detection() -> DetectionProbabilityModel:
    """eq. pd-lidar: 0.95 below 50 m, 0.2 for 50 ≤ r < 80 m, 0 beyond."""
    return DetectionProbabilityModel(
        factors=[RangeBands(edges=(50.0, 80.0), values=(0.95, 0.2, 0.0))])


def radar_clutter() -> ClutterDensityModel:
    """eq. lambda-radar: 1e-3 below 1000 m, 1e-2 from 1000 m on."""
    return ClutterDensityModel(factors=[RangeBands(edges=(1000.0,), values=(1e-3, 1e-2))])


def lidar_clutter(missing_area: float | None = None) -> ClutterDensityModel:
    """eq. lambda-lidar: 1e-1 for segments with area < 10 m², 1e-3 otherwise.

    The rule reads each detection's ``metadata['area']`` (m²), which the paper's lidar
    reports for every segment (and the simulated one does). A detection without it has no
    λ under the paper's equation: a ValueError naming ``'area'``, unless ``missing_area``
    gives the λ to use for it. There is no silent default: one would quietly make the
    context-aware tracker the P_D-aware one on data without areas."""
    return ClutterDensityModel(factors=[MetadataThreshold(
        key="area", threshold=10.0, below=1e-1, at_or_above=1e-3, missing=missing_area)])


def uniform_detection(pd: float = UNIFORM_PD) -> DetectionProbabilityModel:
    return DetectionProbabilityModel(factors=[pd])


def uniform_clutter(density: float = UNIFORM_CLUTTER) -> ClutterDensityModel:
    return ClutterDensityModel(factors=[density])


def paper_sensor_models(pd: str = "context", clutter: str = "context",
                        land: Sequence[np.ndarray] = (),
                        pd_evaluation: str = "mean",
                        lidar_missing_area: float | None = None) -> dict[str, SensorModel]:
    """Radar and lidar models of one tracker configuration.

    ``pd``/``clutter``: ``'uniform'`` (Table I constants) or ``'context'`` (the paper's
    equations). ``land`` adds land masking and line of sight to the radar's P_D (ours).
    ``lidar_missing_area``: λ for a lidar detection without ``metadata['area']`` under the
    context clutter model; None (the default) makes such a detection an error (see
    :func:`lidar_clutter`).
    """
    if pd not in ("uniform", "context") or clutter not in ("uniform", "context"):
        raise ValueError(f"pd/clutter: must be 'uniform' or 'context', got {pd!r}/{clutter!r}")
    radar_pd = radar_detection(land) if pd == "context" else uniform_detection()
    lidar_pd = lidar_detection() if pd == "context" else uniform_detection()
    radar_lambda = radar_clutter() if clutter == "context" else uniform_clutter()
    lidar_lambda = lidar_clutter(lidar_missing_area) if clutter == "context" else uniform_clutter()
    return {
        "radar": SensorModel(detection=radar_pd, clutter=radar_lambda, name="radar",
                             pd_evaluation=pd_evaluation),
        "lidar": SensorModel(detection=lidar_pd, clutter=lidar_lambda, name="lidar",
                             pd_evaluation=pd_evaluation),
    }
