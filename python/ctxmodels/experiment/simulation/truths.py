"""Named settings of the simulated sensors' truth: what the world is, as opposed to what
the trackers assume.

``calibrated``
    The defaults of :class:`~.radar.RadarConfig` and :class:`~.lidar.LidarConfig`: the
    values the calibration (``docs/calibration.md``) chose from the paper's *baseline*
    rows of Table II — radar P_D 0.7 for every object, clutter 1e-3 per rad·m below
    1000 m and 3e-3 beyond, bearing σ 0.5°, lidar clutter 0.3 points per scan.

``stress``
    A stress test: it copies two of the paper's
    *tracker* settings into the truth — radar P_D 0.4 for every object and far clutter
    1e-2 per rad·m (the context-aware λ) — with bearing σ 1° and 3 lidar clutter points
    per scan. The paper's own baseline results rule it out as a model of its data (its
    radar-only GM-PHD, which assumes 1e-3 everywhere, scored an RMS GOSPA of 24.2 m on
    scenario 1: at most 1.3 missed-plus-false tracks a scan), and it makes the
    context-aware trackers' models the true ones: findings on it are true largely by
    construction. The sweep maps the findings across both.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .lidar import LidarConfig
from .radar import RadarConfig

__all__ = ["TRUTHS", "Truth"]


@dataclass(frozen=True)
class Truth:
    """One named truth: the simulated radar and lidar."""

    name: str
    radar: RadarConfig
    lidar: LidarConfig
    description: str


#: The named truths by name; ``calibrated`` is every scenario's default.
TRUTHS: dict[str, Truth] = {truth.name: truth for truth in (
    Truth("calibrated", RadarConfig(), LidarConfig(),
          "calibrated on the paper's baseline rows (docs/calibration.md)"),
    Truth("stress",
          RadarConfig(prob_detection=0.4, bearing_std=math.radians(1.0),
                      clutter_per_scan_near=5.0, clutter_per_scan_far=32.0),
          LidarConfig(clutter_per_scan=3.0),
          "heavy far clutter, radar P_D 0.4: the trackers' settings copied into the truth"),
)}
