"""What a scenario is made of: the ego's motion, the evaluated vessels, static objects
and land (:class:`SceneLayout`); :func:`.run.simulate` adds the random draws.

Static objects (sea markers, islets) are detected like vessels by both sensors but are
not evaluated ground truth (the paper evaluates the RTK-logged moving vessels); a run
keeps them in :attr:`~.run.ScenarioRun.static_objects`. Land polygons occlude both
sensors (:mod:`.geometry`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .motion import DriftMotion, FormationMotion, PathMotion, WeaveMotion

__all__ = ["SceneLayout", "StaticObject", "TargetSpec"]


@dataclass(frozen=True)
class TargetSpec:
    """An evaluated (RTK-logged) moving vessel."""

    id: str
    motion: PathMotion | FormationMotion | WeaveMotion
    lidar_area: float = 20.0


@dataclass(frozen=True)
class StaticObject:
    """A sea marker or islet: detected by the sensors, not evaluated ground truth."""

    id: str
    position: tuple[float, float]
    kind: str = "marker"
    lidar_area: float = 2.0


@dataclass(frozen=True)
class SceneLayout:
    """Everything fixed about a scenario; :func:`simulate` adds the random draws."""

    ego: DriftMotion | PathMotion
    targets: tuple[TargetSpec, ...]
    static_objects: tuple[StaticObject, ...] = ()
    land: tuple[np.ndarray, ...] = ()
    default_duration: float = 480.0
    description: str = ""
