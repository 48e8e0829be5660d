"""The study's trackers on the Solent: which run (:data:`TRACKERS`) and the sensor models
each reads (:func:`site_models`), built by :func:`~ctxmodels.trackers.paper_tracker`.

Every tracker knows the radars' nominal values — P_D 0.7 where a radar can see, the false
alarms a scan spread over its coverage (λ = 14.3 / (2π (R − 50 m)) per rad·m) — and reads
them through the same GM-PHD; they differ only in *where* P_D applies:

``gmphd-uniform``
    P_D 0.7 everywhere, for both radars: every Southsea scan "misses" every vessel south
    of the island.
``gmphd-radar-only``
    the same on the primary radar's (the Foreland's) scans only.
``gmphd-pd-aware``
    P_D 0.7 between 50 m and each radar's reach, 0 beyond (its range bands only).
``gmphd-sight``
    the context: the range bands, the radar horizon (antenna height, vessels 5 m up), the
    land (0 on it) and the line of sight over the real shoreline with the antennas'
    clearance — what each radar can see at each scan.
``gmphd-learned``
    the context with the primary's λ (clutter map) and range-band P_D learned online
    (:class:`~ctxmodels.trackers.models.ClutterMapSettings`,
    :class:`~ctxmodels.trackers.models.DetectionEstimateSettings`).

The platform is the plane's origin (a :class:`~ctxmodels.ConstantPose`); each radar is
mounted at its site's offset from it.
"""
from __future__ import annotations

import dataclasses
import math

from ... import (ClutterDensityModel, ConstantPose, DetectionProbabilityModel, LandMask,
                 LineOfSight, Mounting, Pose, RadarHorizon, RangeBands, SensorModel)
from ...trackers import PaperTracker, TrackerSpec, paper_tracker
from ...trackers.specs import REGION_MARGIN
from ..simulation.radar import RadarConfig
from ..simulation.scans import ScanStream
from . import scene
from .radars import CLUTTER_PER_SCAN, MIN_RANGE

#: The trackers run on the Solent (``ctxmodels experiment --scenarios solent``).
TRACKERS = ("gmphd-uniform", "gmphd-radar-only", "gmphd-pd-aware", "gmphd-sight", "gmphd-learned")
#: The radars' nominal P_D (the calibrated radar's).
NOMINAL_PD = RadarConfig().prob_detection


def clutter_density(site: scene.Site) -> float:
    """The radar's false alarms a scan spread uniformly over its coverage, per rad·m."""
    return CLUTTER_PER_SCAN / (2 * math.pi * (site.reach - MIN_RANGE))


def site_models(kind: str) -> dict[str, SensorModel]:
    """Each radar's model for the trackers of ``kind``: ``'uniform'``, ``'bands'`` or
    ``'context'`` (see the module docs)."""
    land = LandMask(polygons=list(scene.land())) if kind == "context" else None
    models = {}
    for site in scene.SITES:
        if kind == "uniform":
            factors: list = [NOMINAL_PD]
        else:
            factors = [RangeBands(edges=(MIN_RANGE, site.reach), values=(0.0, NOMINAL_PD, 0.0))]
        if kind == "context":
            factors += [RadarHorizon(antenna_height=site.height, target_height=scene.VESSEL_HEIGHT),
                        land, LineOfSight(land=land, clearance=scene.CLEARANCE)]
        x, y = site.position
        models[site.name] = SensorModel(
            detection=DetectionProbabilityModel(factors=factors),
            clutter=ClutterDensityModel(factors=[clutter_density(site)]),
            mounting=Mounting(forward=x, left=y), name=site.name)
    return models


def region_radius() -> float:
    """The GM-PHD's surveillance disc around the origin: the farthest reach plus the margin."""
    return max(math.hypot(*site.position) + site.reach for site in scene.SITES) + REGION_MARGIN


def build_solent_tracker(spec: TrackerSpec, run, fast: bool = True) -> PaperTracker:
    """A tracker for ``spec`` (one of :data:`TRACKERS`) over a Solent ``run``'s scans."""
    if spec.name not in TRACKERS:
        raise ValueError(f"tracker: {spec.name!r} does not run on the Solent; choose from {TRACKERS}")
    kind = {"gmphd-uniform": "uniform", "gmphd-radar-only": "uniform",
            "gmphd-pd-aware": "bands"}.get(spec.name, "context")
    # The models carry the differences: every tracker reads its P_D and λ from them.
    learned = spec.name == "gmphd-learned"
    spec = dataclasses.replace(spec, pd="learned" if learned else "context",
                               clutter="learned" if learned else "context",
                               line_of_sight=False, coastal=False, only_scenarios=None)
    streams = {name: ScanStream(scans) for name, scans in run.scans.items()}
    platform = ConstantPose(pose=Pose(x=0.0, y=0.0, heading=0.0))
    return paper_tracker(spec, streams, site_models(kind), platform,
                         primary=scene.SITES[0].name, fast=fast, region_radius=region_radius())


__all__ = ["NOMINAL_PD", "TRACKERS", "build_solent_tracker", "clutter_density", "region_radius",
           "site_models"]
