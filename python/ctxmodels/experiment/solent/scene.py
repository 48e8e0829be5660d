"""The Solent scene: two coastal radars at declared real sites, the GSHHG shoreline around
them, and the AIS vessels of 12 January 2016 as ground truth.

Everything here is fixed before any tracker runs (``docs/study.md`` gives the reasons):

* **Sites** (GSHHG full resolution puts the shore 70–200 m from both):

  - ``foreland``, the primary: the Foreland, Bembridge, on the Isle of Wight's eastern tip
    (1.0735° W, 50.6830° N): a long-range radar, antenna 30 m up, 20 km, 0.4 Hz;
  - ``southsea``: Southsea Castle, Portsmouth (1.0889° W, 50.7780° N): a short-range
    radar, antenna 15 m up, 10 km, 1 Hz.

  The Foreland sees Spithead's eastern half, the Nab and the Channel south and east of the
  island, not the water behind the island's north-east coast; Southsea sees Spithead to
  Ryde and the harbour mouth, not beyond the island.
* **Land**: the GSHHG full-resolution shoreline in :data:`BOX`; each antenna sees over the
  land within :data:`CLEARANCE` of it.
* **Window**: :data:`WINDOW_START` s after the log's first report (13:02:11 UTC), the
  :data:`DURATION` s window that holds the most AIS reports inside the two radars' reach
  among the windows starting on whole minutes (:func:`busiest_window`; a test recomputes it).
* **Truth**: each AIS vessel where the log knows it (between reports of a segment,
  :mod:`ctxmodels.geo.ais`) and it is on water per the shoreline (5 % of the reports in the
  box lie on GSHHG's land: berths, and Portsmouth Harbour's mouth, where the shoreline lies
  ~300 m off the charted one), with its height :data:`VESSEL_HEIGHT` for the horizon.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from ...geo.ais import solent_ais
from ...geo.plane import lonlat_to_local
from ...geo.shorelines import shoreline_polygons

#: The scene: longitude/latitude box of the shoreline and of the AIS reports kept.
BOX = (-1.40, 50.50, -0.75, 50.88)
#: The plane's origin: Southsea Castle.
ORIGIN = (-1.0889, 50.7780)
#: Land within this distance of an antenna blocks nothing (m): both stand on the shore.
CLEARANCE = 500.0
#: Height of every vessel above the sea for the radar horizon (m); AIS gives none.
VESSEL_HEIGHT = 5.0
#: The plane's formulas: NumPy's, the same bits on every install (PROJ's, where pyproj is
#: installed, agree to well under a millimetre but not to the bit).
BACKEND = "numpy"
#: The scores' distances are the paper's (HOTA 5 m and 30 m, GOSPA c = 30 m for its 1.6 km
#: radar) times this: these radars reach 10 and 20 km, and a bearing error spans metres in
#: proportion to range.
DISTANCE_SCALE = 10.0
#: The window (s): its start after the log's first report, and its length.
DURATION = 600.0
WINDOW_START = 4440.0


@dataclass(frozen=True)
class Site:
    """A radar at a real site: ``lonlat``, antenna ``height`` (m), ``reach`` (m), scan
    ``period`` and ``phase`` (s)."""

    name: str
    label: str
    lonlat: tuple[float, float]
    height: float
    reach: float
    period: float
    phase: float

    @property
    def position(self) -> tuple[float, float]:
        x, y = lonlat_to_local([self.lonlat], ORIGIN, backend=BACKEND)[0]
        return float(x), float(y)


#: The two radars, the primary first (the evaluation runs at its scans).
SITES = (
    Site("foreland", "Foreland (Bembridge)", (-1.0735, 50.6830), 30.0, 20_000.0, 2.5, 0.0),
    Site("southsea", "Southsea Castle", (-1.0889, 50.7780), 15.0, 10_000.0, 1.0, 0.37),
)


@functools.cache
def land() -> tuple[dict, ...]:
    """The shoreline's land polygons in :data:`BOX`, in the plane of :data:`ORIGIN`."""
    return _frozen(shoreline_polygons(BOX, ORIGIN, "f", backend=BACKEND))


@functools.cache
def traffic():
    """The Solent AIS log inside :data:`BOX`, in the plane of :data:`ORIGIN`."""
    log = solent_ais(BOX, ORIGIN, backend=BACKEND)
    for trajectory in log.trajectories:
        for array in (trajectory.times, trajectory.positions, trajectory.course, trajectory.speed):
            array.setflags(write=False)
    return log


def _frozen(polygons) -> tuple[dict, ...]:
    """Polygons whose arrays cannot be written (they are shared by every run)."""
    for polygon in polygons:
        for ring in [polygon["shell"], *polygon["holes"]]:
            ring.setflags(write=False)
    return tuple(polygons)


def near_a_radar(positions: np.ndarray) -> np.ndarray:
    """Whether each (N, 2) position lies within some radar's reach."""
    near = np.zeros(len(positions), dtype=bool)
    for site in SITES:
        offset = positions - np.asarray(site.position)
        near |= np.hypot(offset[:, 0], offset[:, 1]) < site.reach
    return near


def busiest_window(duration: float = DURATION, step: float = 60.0) -> float:
    """The start (s after the log's first report) of the ``duration`` window, on a ``step``
    grid, holding the most AIS reports within some radar's reach (the first on ties)."""
    log = traffic()
    times = np.concatenate([t.times for t in log.trajectories])
    near = near_a_radar(np.concatenate([t.positions for t in log.trajectories]))
    starts = np.arange(0.0, max(times[near]) - duration + step, step)
    counts = [np.count_nonzero(near & (times >= s) & (times < s + duration)) for s in starts]
    return float(starts[int(np.argmax(counts))])


def horizon_range(antenna: float, target: float = VESSEL_HEIGHT, k: float = 4 / 3) -> float:
    """√(2kRh_a) + √(2kRh_t) (m): the radar horizon over a smooth Earth, k = 4/3, R = 6371 km
    (the trackers' :class:`~ctxmodels.RadarHorizon` takes the same; this truth computes its
    own). For these radars 31.8 km and 25.2 km: beyond both reaches, so it never binds here."""
    radius = 6_371_000.0
    return math.sqrt(2 * k * radius * antenna) + math.sqrt(2 * k * radius * target)
