"""Seeded simulator of the paper's radar–lidar USV experiment (the "truth" side).

The recorded dataset of the paper is not public, so the experiment runs on a faithful
simulation of its sensing geometry (paper Section IV-A, Fig. 2) and scenario
descriptions. The simulator is deliberately independent of the rest of ``ctxmodels``
(it never imports ``ctxmodels._core`` or the context models): it is the ground truth the
context-aware models are judged against, so it must not share their code.

This module is the public entry point. The simulator lives in
:mod:`ctxmodels.experiment.simulation`, one module per concept, each documenting its part
in full (not to be confused with :mod:`ctxmodels.experiment.sensors`, the *trackers'*
sensor models):

``simulation.paths``
    :class:`Path`, :class:`PathBuilder`, :func:`tangent_point`: straight legs and turns.
``simulation.motion``
    :class:`PathMotion`, :class:`FormationMotion`, :class:`WeaveMotion`,
    :class:`DriftMotion`, :class:`MotionSample`: how vessels and the ego move.
``simulation.scene``
    :class:`TargetSpec`, :class:`StaticObject`, :class:`SceneLayout`: what a scenario is
    made of.
``simulation.radar`` / ``simulation.lidar``
    :class:`RadarConfig` / :class:`LidarConfig` and the simulated scans: detection
    probabilities, noise, clutter, land returns.
``simulation.geometry``
    Angles, polar coordinates, land polygons, line of sight over land.
``simulation.scans``
    :class:`SensorPose`, :class:`Scan`, scan timing, how a detection is typed.
``simulation.run``
    :func:`simulate`, :class:`ScenarioRun`, :class:`EgoNavigation`, :data:`EPOCH`.
``simulation.layouts``
    The three scenarios, :data:`SCENARIOS`, :class:`ScenarioSpec`, :func:`make_scenario`.

Conventions
-----------
Stone Soup's: world x/y Cartesian in metres; headings and bearings in radians,
measured from +x counter-clockwise. Target states are ``[x, vx, y, vy]``. A radar
bearing is relative to the ego's heading (0 = dead ahead, +π/2 = port); this is what
``CartesianToBearingRange(translation_offset=(x, y), rotation_offset=(0, 0, heading))``
produces (checked by experiment and by the tests). Both sensors are mounted at the ego's
navigation reference point (no lever arm), and the navigation track is exact (the
measurement noise stands for all error sources). Timestamps are naive
:class:`datetime.datetime` starting at :data:`EPOCH`.

Overview
--------
Radar 0.8 Hz, 50–1612 m outside a 65° blind sector astern, P_D 0.7, bearing σ 0.5° and
range σ 5 m, clutter uniform in bearing–range (1e-3 per rad·m below 1 km, 3e-3
beyond), land returns from the coast it sees. Lidar 10 Hz (first scan 43 ms after the
epoch: the sensors never share a timestamp), P_D 0.95 below 50 m and 0.2 to 80 m, x/y
centroids with σ 0.5 m and a segment ``area``, Poisson(0.3) small clutter segments per
scan. The radar's P_D, clutter and bearing σ and the lidar's clutter rate are *calibrated*
on the paper's baseline rows (``docs/calibration.md``); :data:`TRUTHS` names them
(``calibrated``, the default) beside a ``stress`` setting that copies the trackers' P_D 0.4
and far λ 1e-2 into the truth. Static objects (markers, islets) are detected but are not ground truth; land
occludes both sensors. Scenarios: ``"mixed-range"`` (1), ``"formation"`` (2),
``"islands"`` (3, ours), 480 s each. Truth trajectories are fixed per scenario: legs and
turns, with the turn rate ramping over 4 s into and out of each turn so that truth
velocities are continuous (``simulation.motion`` says why). The seed only drives
detection, noise and clutter draws, from independent radar and lidar streams.

Public API
----------
``make_scenario(name, seed, duration=None, *, radar=None, lidar=None)``
    Generate one named scenario: a :class:`ScenarioRun`, or for ``"solent"`` a
    :class:`~.solent.run.SolentRun` (real coast and traffic; its radars are fixed).
``simulate(layout, seed, duration=None, *, radar=None, lidar=None, name="custom")``
    Generate any :class:`SceneLayout` (build your own with :class:`PathBuilder`,
    :class:`PathMotion`, :class:`WeaveMotion`, :class:`FormationMotion`,
    :class:`DriftMotion`, :class:`TargetSpec`, :class:`StaticObject`).
``SCENARIOS``
    ``{name: spec}``: each spec's ``duration``; a simulated scene's :class:`ScenarioSpec`
    builds its layout (``layout()``), the Solent's :class:`SolentSpec` has none.
    ``SIMULATED_SCENARIOS`` holds the first three, ``DEFAULT_SCENARIOS`` what a study runs
    unless told.
``TRUTHS``
    ``{name: Truth}``: named radar and lidar truths (``calibrated``, ``stress``).

:class:`ScenarioRun` fields: ``name, seed, duration, truths`` (set of
``GroundTruthPath``, stable ``id``, a state at every radar and lidar timestamp while
the vessel exists), ``static_objects, land, ego`` (:class:`EgoNavigation` at every scan
time), ``radar_scans, lidar_scans`` (time-ordered :class:`Scan` =
``(timestamp, set_of_detections, SensorPose)``), ``radar_times, lidar_times, radar,
lidar``. Vessel detections are ``TrueDetection`` (``groundtruth_path`` set); clutter,
static and land returns are ``Clutter``. Every detection's ``metadata['source']`` is
``'target'`` (plus ``'truth_id'``), ``'static'`` (plus ``'static_id'``),
``'clutter'`` or ``'land'``; lidar detections also carry ``'area'``.
"""

from __future__ import annotations

from dataclasses import dataclass

from .simulation.layouts import SCENARIOS as SIMULATED_SCENARIOS
from .simulation.layouts import ScenarioSpec
from .simulation.layouts import make_scenario as make_simulated_scenario
from .simulation.lidar import LidarConfig
from .simulation.motion import (
    DriftMotion,
    FormationMotion,
    MotionSample,
    PathMotion,
    WeaveMotion,
)
from .simulation.paths import Path, PathBuilder, tangent_point
from .simulation.radar import RadarConfig
from .simulation.run import EPOCH, EgoNavigation, ScenarioRun, simulate
from .simulation.scans import Scan, SensorPose
from .simulation.scene import SceneLayout, StaticObject, TargetSpec
from .simulation.truths import TRUTHS, Truth


#: The Solent: two coastal radars on a real coastline with real traffic (:mod:`.solent`).
SOLENT = "solent"


@dataclass(frozen=True)
class SolentSpec:
    """The Solent's registry entry (its scene: :mod:`ctxmodels.experiment.solent.scene`)."""

    name: str = SOLENT
    number: int = 4
    title: str = "Two coastal radars over the Solent"
    description: str = ("two coastal radars on the GSHHG shoreline, AIS vessels as truth "
                        "(downloaded once)")

    @property
    def duration(self) -> float:
        from .solent.scene import DURATION
        return DURATION

    def prepare(self) -> None:
        """Reads the coast and the traffic once, before a study's workers start: the first
        use downloads them, which each worker would otherwise do at the same time (forked
        workers inherit what was read)."""
        from .solent import scene
        scene.land()
        scene.traffic()


#: Every scenario by name: the paper's two, our islands, and the Solent.
SCENARIOS: dict = {**SIMULATED_SCENARIOS, SOLENT: SolentSpec()}
#: What a study runs when no scenario is named: the simulated ones (the Solent needs its
#: data downloaded once; name it).
DEFAULT_SCENARIOS = tuple(SIMULATED_SCENARIOS)


def make_scenario(name, seed: int, duration: float | None = None, *, radar=None, lidar=None):
    """A simulated scenario's run (:func:`~.simulation.layouts.make_scenario`), or the
    Solent's (:func:`~.solent.run.make_solent`; its radars' truth is fixed, so ``radar``
    and ``lidar`` must be None)."""
    if name == SOLENT:
        if radar is not None or lidar is not None:
            raise ValueError("radar/lidar: the Solent's radars are fixed (its scene module "
                             "says why); these settings are the simulated scenarios'")
        from .solent.run import make_solent
        return make_solent(seed, duration)
    return make_simulated_scenario(name, seed, duration, radar=radar, lidar=lidar)


__all__ = [
    "DEFAULT_SCENARIOS",
    "EPOCH",
    "SCENARIOS",
    "SIMULATED_SCENARIOS",
    "SOLENT",
    "TRUTHS",
    "DriftMotion",
    "EgoNavigation",
    "FormationMotion",
    "LidarConfig",
    "MotionSample",
    "Path",
    "PathBuilder",
    "PathMotion",
    "RadarConfig",
    "ScenarioRun",
    "ScenarioSpec",
    "Scan",
    "SceneLayout",
    "SensorPose",
    "StaticObject",
    "TargetSpec",
    "Truth",
    "WeaveMotion",
    "make_scenario",
    "simulate",
    "tangent_point",
]
