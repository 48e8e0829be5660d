r"""AIS position reports read into per-vessel trajectories in a local plane.

An AIS (Automatic Identification System) transponder broadcasts a ship's GNSS position,
course and speed every 2–10 s under way and every 3 min at anchor; a shore receiver logs
what it hears, with gaps where it hears nothing. :func:`read_ais` reads such a log — a CSV
file with the columns ``Time`` (ISO 8601, UTC), ``MMSI`` (the vessel's identity),
``Latitude_degrees``, ``Longitude_degrees``, ``COG_degrees`` (course over ground) and
``SOG_knots`` (speed over ground) — into one :class:`Trajectory` per vessel:

1. reports outside ``box`` (lon_min, lat_min, lon_max, lat_max) are dropped (a receiver's log
   holds the odd wild position: the Solent file has one at 54.8° E);
2. each vessel's reports are sorted by time, and a report at the same time as the one kept
   before it is dropped (duplicates);
3. an isolated jump is dropped: a report reached from the previous one *and* left for the
   next one faster than ``max_speed``;
4. the reports are mapped to east/north metres around ``origin``
   (:func:`ctxmodels.geo.lonlat_to_local`), and the trajectory is cut into *segments* where
   two reports are more than ``max_gap`` seconds apart (300 s by default: a ship at anchor
   reports every 3 min, so a longer silence is the receiver's gap, not the ship's).

:meth:`Trajectory.position_at` interpolates linearly between reports within a segment and
gives NaN elsewhere: between segments (in a gap) and before the first or after the last
report, a vessel is not known, so a study does not score it there.

:func:`solent_ais` reads the Solent log Stone Soup publishes with its 1.9.1 source
distribution (``docs/demos/SolentAIS_20160112_130211.csv``: 18,623 reports of 91 vessels,
12 January 2016, 13:02–14:26 UTC), downloaded at first use (:mod:`ctxmodels.downloads`).
"""
from __future__ import annotations

import csv
import datetime as dt
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import downloads
from .._component import as_float
from .plane import _origin, lonlat_to_local
from .shorelines import check_box

KNOT = 1852.0 / 3600.0  #: metres per second
COLUMNS = ("Time", "MMSI", "Latitude_degrees", "Longitude_degrees", "COG_degrees", "SOG_knots")
SOLENT_FILE = "docs/demos/SolentAIS_20160112_130211.csv"


@dataclass(frozen=True, eq=False)
class Trajectory:
    """One vessel's reports: ``times`` (K,) seconds after the log's ``epoch``, strictly
    increasing; ``positions`` (K, 2) east/north metres; ``course`` (K,) degrees clockwise
    from north and ``speed`` (K,) m/s as the vessel reported them; ``segments`` the
    [start, stop) index ranges of reports no more than the reader's ``max_gap`` apart."""

    mmsi: int
    times: np.ndarray
    positions: np.ndarray
    course: np.ndarray
    speed: np.ndarray
    segments: tuple[tuple[int, int], ...]

    def position_at(self, t) -> np.ndarray:
        """(N, 2) positions at times ``t`` (N,) seconds after the epoch, linear between the
        reports of a segment, NaN outside every segment (and at a NaN time)."""
        t = _seconds(t)
        out = np.full((len(t), 2), np.nan)
        for start, stop in self.segments:
            times = self.times[start:stop]
            inside = (t >= times[0]) & (t <= times[-1])
            if np.any(inside):
                for axis in range(2):
                    out[inside, axis] = np.interp(t[inside], times, self.positions[start:stop, axis])
        return out

    def velocity_at(self, t) -> np.ndarray:
        """(N, 2) east/north velocities (m/s) between the reports around each time (the
        segment's last report uses the one before it), NaN outside every segment."""
        t = _seconds(t)
        out = np.full((len(t), 2), np.nan)
        for start, stop in self.segments:
            if stop - start < 2:
                continue
            times, points = self.times[start:stop], self.positions[start:stop]
            inside = (t >= times[0]) & (t <= times[-1])
            if np.any(inside):
                k = np.clip(np.searchsorted(times, t[inside], side="right") - 1, 0, len(times) - 2)
                out[inside] = (points[k + 1] - points[k]) / (times[k + 1] - times[k])[:, None]
        return out


def _seconds(t) -> np.ndarray:
    """``t`` as (N,) float seconds: real numbers, a scalar or one dimension."""
    given = np.asarray(t)
    if given.dtype.kind not in "iuf" or given.ndim > 1:
        raise TypeError(f"t: expected seconds after the epoch, a number or (N,) numbers, got "
                        f"{given.dtype} of shape {given.shape}")
    return np.atleast_1d(given.astype(np.float64))


@dataclass(frozen=True)
class AISLog:
    """What :func:`read_ais` read: ``epoch`` (UTC) of time 0, the ``origin`` of the plane,
    the ``trajectories`` (by MMSI, ascending) and how many reports were ``dropped`` for each
    reason."""

    epoch: dt.datetime
    origin: tuple[float, float]
    trajectories: tuple[Trajectory, ...]
    dropped: dict


def _rows(path: Path):
    with open(path, newline="", encoding="utf-8-sig") as handle:
        reader = csv.reader(handle)
        header = next(reader, None)
        if header is None:
            raise ValueError(f"source: {path} is empty")
        missing = [c for c in COLUMNS if c not in header]
        if missing:
            raise ValueError(f"source: {path} lacks the column(s) {', '.join(missing)} (it has "
                             f"{', '.join(header)})")
        index = [header.index(c) for c in COLUMNS]
        for line, row in enumerate(reader, start=2):
            if not row:
                continue
            try:
                fields = [row[i] for i in index]
                when = dt.datetime.fromisoformat(fields[0])
                if when.tzinfo is not None:
                    when = when.astimezone(dt.timezone.utc).replace(tzinfo=None)
                # (course and speed may be empty: "not available" in AIS)
                values = [float(fields[2]), float(fields[3])] + [
                    float(v) if v.strip() else float("nan") for v in fields[4:]]
                mmsi = int(fields[1])
                if not 0 <= mmsi < 2**63:
                    raise ValueError(f"MMSI {fields[1]} out of range")
                yield when, mmsi, values
            except (IndexError, ValueError, OverflowError) as err:
                raise ValueError(f"source: {path}, line {line}: not an AIS report ({err})") from None


def _isolated_jumps(times: np.ndarray, xy: np.ndarray, max_speed: float) -> np.ndarray:
    """Reports reached from the previous one and left for the next one, both faster than
    ``max_speed``."""
    step = np.hypot(*np.diff(xy, axis=0).T)
    dt_ = np.maximum(np.diff(times), 1e-9)
    fast = step > max_speed * dt_
    jump = np.zeros(len(times), bool)
    jump[1:-1] = fast[:-1] & fast[1:]
    return jump


def read_ais(source, box=None, origin=None, *, max_gap: float = 300.0,
             max_speed: float = 60.0 * KNOT, backend: str = "auto") -> AISLog:
    """Read an AIS CSV log (see the module docstring) into trajectories.

    ``box`` (lon_min, lat_min, lon_max, lat_max) degrees keeps the reports inside it (all by
    default; the plane is local, so a log spread over more than
    :data:`ctxmodels.geo.MAX_DISTANCE` needs one). ``origin`` (longitude, latitude) is the
    plane's origin, the box's centre by default (else the reports' mean). ``max_gap``
    (seconds) cuts a trajectory into segments; ``max_speed`` (m/s, 60 knots by default)
    marks an isolated jump. ``backend``: :func:`~ctxmodels.geo.lonlat_to_local`'s."""
    if not isinstance(source, (str, Path)):
        raise TypeError(f"source: expected a file path, got {type(source).__name__}")
    path = Path(source)
    if not path.is_file():
        raise FileNotFoundError(f"source: no such file: {path}")
    max_gap = as_float(max_gap, "max_gap")
    if not max_gap > 0:
        raise ValueError(f"max_gap: must be positive seconds, got {max_gap}")
    max_speed = as_float(max_speed, "max_speed")
    if not max_speed > 0:
        raise ValueError(f"max_speed: must be positive m/s, got {max_speed}")
    bounds = check_box(box) if box is not None else None
    try:
        reports = list(_rows(path))
    except UnicodeDecodeError as err:
        raise ValueError(f"source: {path} is not UTF-8 text ({err.reason} at byte {err.start})") from None
    if not reports:
        raise ValueError(f"source: {path} holds no reports")
    epoch = min(r[0] for r in reports)
    times = np.array([(r[0] - epoch).total_seconds() for r in reports])
    mmsi = np.array([r[1] for r in reports], dtype=np.int64)
    values = np.array([r[2] for r in reports], dtype=np.float64).reshape(-1, 4)
    lat, lon, course, sog = values.T
    dropped = {"outside box": 0, "duplicate time": 0, "isolated jump": 0}
    # a position off the Earth (or not a number) is the receiver's garbage, as a wild one is
    keep = (np.isfinite(lat) & np.isfinite(lon) & (np.abs(lat) <= 90.0)
            & (np.abs(lon) <= 180.0))
    dropped["not a position"] = int(np.count_nonzero(~keep))
    if bounds is not None:
        inside = (lon >= bounds[0]) & (lon <= bounds[2]) & (lat >= bounds[1]) & (lat <= bounds[3])
        dropped["outside box"] = int(np.count_nonzero(keep & ~inside))
        keep &= inside
    if not keep.any() and origin is None and bounds is None:
        raise ValueError(f"source: {path} holds no report with a position (so no origin for "
                         f"the plane either)")
    if origin is not None:
        origin = _origin(origin)
    elif bounds is not None:
        origin = (0.5 * (bounds[0] + bounds[2]), 0.5 * (bounds[1] + bounds[3]))
    else:
        origin = (float(np.mean(lon[keep])), float(np.mean(lat[keep])))
    order = np.lexsort((np.arange(len(times)), times, mmsi))  # stable: the log's order at ties
    order = order[keep[order]]
    xy = np.full((len(times), 2), np.nan)
    xy[order] = lonlat_to_local(np.column_stack([lon[order], lat[order]]), origin, backend=backend)
    trajectories = []
    for vessel in np.unique(mmsi[order]):
        rows = order[mmsi[order] == vessel]
        first = np.ones(len(rows), bool)
        first[1:] = times[rows][1:] != times[rows][:-1]
        dropped["duplicate time"] += int(np.count_nonzero(~first))
        rows = rows[first]
        jump = _isolated_jumps(times[rows], xy[rows], max_speed)
        dropped["isolated jump"] += int(np.count_nonzero(jump))
        rows = rows[~jump]
        cuts = np.flatnonzero(np.diff(times[rows]) > max_gap) + 1
        edges = [0, *cuts.tolist(), len(rows)]
        trajectories.append(Trajectory(
            mmsi=int(vessel), times=times[rows], positions=xy[rows], course=course[rows],
            speed=sog[rows] * KNOT, segments=tuple(zip(edges[:-1], edges[1:]))))
    return AISLog(epoch=epoch, origin=origin, trajectories=tuple(trajectories), dropped=dropped)


def solent_ais(box=None, origin=None, **options) -> AISLog:
    """The Solent log of 12 January 2016 (downloaded at first use), read by
    :func:`read_ais` with ``box``, ``origin`` and its options."""
    return read_ais(downloads.member(downloads.STONESOUP, SOLENT_FILE), box, origin, **options)


__all__ = ["AISLog", "COLUMNS", "KNOT", "Trajectory", "read_ais", "solent_ais"]
