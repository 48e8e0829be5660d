"""One seeded run of the Solent scene (:func:`make_solent`) and the study's trackers on it
(:func:`build_solent_tracker`).

Ground truth: a vessel is scored at a time when the log knows where it is, it is on water,
it lies within some radar's reach (range and horizon: :func:`~.radars.within_reach`), and
some radar sees it at some time of the window (:func:`~.radars.covered`: line of sight
too). Land hiding a vessel for a while does not take it out of the truth, as the paper's
blind sector does not; a vessel no radar ever sees is not in the study. Each unbroken
stretch of scored times over both radars' scans is one ``GroundTruthPath``
(``"<MMSI>/<k>"``). The scores are
taken at the primary radar's scans, as the paper scores at its radar's.
"""
from __future__ import annotations

import datetime
import functools
from dataclasses import dataclass

import numpy as np
from stonesoup.types.array import StateVector
from stonesoup.types.groundtruth import GroundTruthPath, GroundTruthState

from . import scene
from .radars import covered, generate_scans, on_water, scan_times, within_reach


@dataclass(eq=False)
class SolentRun:
    """A run: the truth paths, each radar's scans (the primary's first) and the land."""

    name: str
    seed: int
    duration: float
    truths: set[GroundTruthPath]
    scans: dict
    land: tuple
    static_objects: tuple = ()
    description: str = "two coastal radars over the Solent, AIS vessels as truth"
    #: The scores' distances are the paper's times this (:data:`~.scene.DISTANCE_SCALE`).
    distance_scale: float = scene.DISTANCE_SCALE

    @property
    def radar_times(self) -> list[datetime.datetime]:
        """The evaluation times: the primary radar's scans."""
        return [scan.timestamp for scan in self.scans[scene.SITES[0].name]]

    @property
    def truth_by_id(self) -> dict[str, GroundTruthPath]:
        return {truth.id: truth for truth in sorted(self.truths, key=lambda path: path.id)}

    @property
    def static_positions(self) -> np.ndarray:
        return np.zeros((0, 2))


@functools.lru_cache(maxsize=4)
def _truth(duration: float):
    """The seed-free part of a run: times, vessel positions and velocities, who is scored
    when, and the truth paths."""
    log = scene.traffic()
    epoch = log.epoch + datetime.timedelta(seconds=scene.WINDOW_START)
    times = {site.name: scan_times(site, epoch, duration) for site in scene.SITES}
    every = sorted({t for ts in times.values() for t in ts})
    seconds = np.array([(t - log.epoch).total_seconds() for t in every])
    vessels = log.trajectories
    positions = np.stack([v.position_at(seconds) for v in vessels], axis=1)  # (T, N, 2)
    velocities = np.stack([v.velocity_at(seconds) for v in vessels], axis=1)
    known = np.isfinite(positions).all(axis=2) & np.isfinite(velocities).all(axis=2)
    flat = positions.reshape(-1, 2)
    present = known.reshape(-1).copy()
    present[present] = on_water(flat[present], scene.land())
    seen, reachable = {}, np.zeros(present.shape, dtype=bool)
    for site in scene.SITES:
        by_site = np.zeros(present.shape, dtype=bool)
        by_site[present] = covered(site, flat[present], scene.land())
        seen[site.name] = by_site.reshape(known.shape)
        reachable[present] |= within_reach(site, flat[present])
    # within some radar's reach while some radar sees it at some time of the window: land
    # hiding it for a while does not take it out of the truth (as the paper's blind sector
    # does not); a vessel no radar ever sees is not in the study
    ever_seen = np.logical_or.reduce(list(seen.values())).any(axis=0)
    scored = reachable.reshape(known.shape) & ever_seen[None, :]
    paths, owner = [], np.full(known.shape, -1)
    for j, vessel in enumerate(vessels):
        runs = np.flatnonzero(np.diff(np.concatenate([[0], scored[:, j].astype(int), [0]])))
        for k, (start, stop) in enumerate(zip(runs[::2], runs[1::2])):
            states = [GroundTruthState(StateVector([positions[i, j, 0], velocities[i, j, 0],
                                                    positions[i, j, 1], velocities[i, j, 1]]),
                                       timestamp=every[i]) for i in range(start, stop)]
            owner[start:stop, j] = len(paths)
            paths.append(GroundTruthPath(states, id=f"{vessel.mmsi}/{k}"))
    index = {t: i for i, t in enumerate(every)}
    return times, index, positions, seen, owner, paths


def make_solent(seed: int, duration: float | None = None) -> SolentRun:
    """The Solent scene's run for ``seed`` over its window (``duration`` s from its start,
    :data:`~.scene.DURATION` by default): same seed, same run."""
    duration = scene.DURATION if duration is None else float(duration)
    if not 0 < duration <= scene.DURATION:
        raise ValueError(f"duration: the Solent window holds {scene.DURATION:g} s, got {duration}")
    times, index, positions, seen, owner, paths = _truth(duration)
    streams = np.random.SeedSequence(seed).spawn(len(scene.SITES))
    scans = {}
    for site, stream in zip(scene.SITES, streams):
        rows = [index[t] for t in times[site.name]]
        on_path = np.empty((len(rows), owner.shape[1]), dtype=object)
        for k, i in enumerate(rows):
            on_path[k] = [paths[o] if o >= 0 else None for o in owner[i]]
        scans[site.name] = generate_scans(site, times[site.name], positions[rows],
                                          seen[site.name][rows], on_path,
                                          np.random.default_rng(stream))
    return SolentRun("solent", seed, duration, set(paths), scans, scene.land())
