"""Why the learned GM-PHD falls behind the line-of-sight one on the Solent (docs/study.md),
on development seeds: the two learned parts one at a time, and what each reads.

* Four trackers, otherwise the study's ``gmphd-learned``: P_D and λ both written
  (``gmphd-sight``'s models), both learned (``gmphd-learned``), λ learned only, P_D learned
  only; HOTA over the window and from 120 s on, time to track, false tracks per scan.
* In the both-learned run, before each of the Foreland's scans updates the map: the learned
  λ at its vessels' returns and at its false alarms over the simulated density (the
  simulator's ``metadata['source']`` tells them apart; a diagnostic, no tracker reads it).
* The learned P_D against range at the vessels the Foreland covers, beside the simulated P_D
  times the share of its returns that fall within the learning gate of the true position
  (its noise is known here), which is what a gated count converges to.

    python scripts/solent_learned.py [SEEDS [FIRST_SEED]]

SEEDS seeds (default 5) from FIRST_SEED (default 0); seeds from 1000 on are refused (the
study's confirmatory runs use fresh seeds from 2000). About a minute per seed on one core.
"""
import dataclasses
import sys
from collections import defaultdict

import numpy as np

from ctxmodels import ClutterMap, ConstantPose, DetectionEstimate, Pose
from ctxmodels.experiment import metrics
from ctxmodels.experiment.extraction import extracted
from ctxmodels.experiment.scoring import score_run
from ctxmodels.experiment.simulation.scans import ScanStream
from ctxmodels.experiment.solent import radars, scene
from ctxmodels.experiment.solent.run import make_solent
from ctxmodels.experiment.solent.trackers import region_radius, site_models
from ctxmodels.stonesoup.ordering import in_track_order
from ctxmodels.trackers import TRACKERS, paper_tracker
from ctxmodels.trackers.models import LEARNING_GATE

FORELAND = scene.SITES[0]
RADAR = radars.CALIBRATED
#: The simulated false alarms' density in the map's bearing–range space (rad·m): uniform
#: in bearing and in range over the Foreland's reach.
SIMULATED_DENSITY = radars.CLUTTER_PER_SCAN / (2 * np.pi * (FORELAND.reach - radars.MIN_RANGE))
VARIANTS = {"written": ("context", "context"), "learned": ("learned", "learned"),
            "λ learned": ("context", "learned"), "P_D learned": ("learned", "context")}
RANGES = (3e3, 6e3, 9e3, 12e3, 20e3)


class Reader:
    """A learner put before the real ones: reads the learned parts as the scan finds them."""

    def __init__(self, covered_at):
        self.covered_at = covered_at
        self.lam = defaultdict(list)   # (seconds bin, 'vessel' | 'clutter') -> λ / simulated
        self.pd = defaultdict(list)    # range bin -> learned P_D at covered vessels

    def learn(self, time, detections, tracks):
        context = detections.detector_context
        model = context.sensor_model
        if model.name != FORELAND.name:
            return
        seconds = (time - self.start).total_seconds()
        maps = [f for f in model.clutter.factors if isinstance(f, ClutterMap)]
        if maps:
            x0, y0 = FORELAND.position
            for d in detections:
                bearing, r = float(d.state_vector[0]), float(d.state_vector[1])
                xy = np.array([[x0 + r * np.cos(bearing), y0 + r * np.sin(bearing)]])
                learned = maps[0].intensity(context.pose, xy, np.array([r]))[0]
                kind = "vessel" if d.metadata.get("source") == "target" else "clutter"
                self.lam[(np.searchsorted((10, 30, 120, 300), seconds, side="right"), kind)].append(
                    learned / SIMULATED_DENSITY)
        if any(isinstance(f, DetectionEstimate) for f in model.detection.factors):
            positions = self.covered_at(time)
            if len(positions):
                pd = model.detection.evaluate(context.pose, positions, position_mapping=(0, 1))
                ranges = np.hypot(*(positions - np.asarray(FORELAND.position)).T)
                for k, value in zip(np.searchsorted(RANGES, ranges), pd):
                    self.pd[k].append(value)


def tracker(run, pd, clutter):
    spec = dataclasses.replace(TRACKERS["gmphd-learned"], pd=pd, clutter=clutter)
    streams = {name: ScanStream(scans) for name, scans in run.scans.items()}
    return paper_tracker(spec, streams, site_models("context"), ConstantPose(pose=Pose(x=0.0, y=0.0)),
                         primary=FORELAND.name, fast=True, region_radius=region_radius())


def one_seed(seed, readers):
    run = make_solent(seed)
    truths = list(run.truth_by_id.values())
    at = defaultdict(list)
    for truth in truths:
        for state in truth.states:
            at[state.timestamp].append([state.state_vector[0, 0], state.state_vector[2, 0]])
    land = scene.land()

    def covered_at(time):
        positions = np.asarray(at.get(time, []), dtype=float).reshape(-1, 2)
        return positions[radars.covered(FORELAND, positions, land)] if len(positions) else positions

    scores = {}
    for name, (pd, clutter) in VARIANTS.items():
        built = tracker(run, pd, clutter)
        if name == "learned":
            reader = Reader(covered_at)
            reader.start = run.radar_times[0]
            built.learners.insert(0, reader)
            readers.append(reader)
        tracks = set()
        for _, current in built:
            tracks |= current
        reported = extracted([t for t in in_track_order(tracks) if len(t)], "stone-soup")
        score = score_run(run, reported)
        frames = metrics.frames_from_stonesoup(truths, reported, run.radar_times)
        late = [f for f, t in zip(frames, run.radar_times) if (t - run.radar_times[0]).total_seconds() >= 120]
        scale = scene.DISTANCE_SCALE
        hota_late = metrics.hota_from_frames(
            late, full_similarity_distance=metrics.FULL_SIMILARITY_DISTANCE * scale,
            zero_similarity_distance=metrics.ZERO_SIMILARITY_DISTANCE * scale).hota
        m = score.management
        scores[name] = (100 * score.hota.hota, 100 * hota_late, m.time_to_track, m.false_tracks_per_scan)
    return scores


def main(argv):
    count = int(argv[0]) if argv else 5
    first = int(argv[1]) if len(argv) > 1 else 0
    if first + count > 1000:
        sys.exit("solent_learned: development seeds only (below 1000)")
    readers, table = [], defaultdict(list)
    for seed in range(first, first + count):
        for name, row in one_seed(seed, readers).items():
            table[name].append(row)
            print(seed, f"{name:12s}", "HOTA {:.1f}, from 120 s {:.1f}, time to track {:.1f} s, "
                  "false tracks a scan {:.2f}".format(*row), flush=True)
    written = np.asarray(table["written"])
    print("\nmeans over seeds (Δ: against the written models, paired)")
    for name, rows in table.items():
        rows = np.asarray(rows)
        d = (rows - written)[:, :2].mean(axis=0)
        print(f"  {name:12s} HOTA {rows[:, 0].mean():.1f} (Δ {d[0]:+.2f}), from 120 s Δ {d[1]:+.2f}, "
              f"time to track {rows[:, 2].mean():.1f} s, false tracks a scan {rows[:, 3].mean():.2f}")
    print("\nlearned λ over the simulated density at the Foreland's returns, before each update "
          "(median, share above 100×)")
    windows = ("0-10 s", "10-30 s", "30-120 s", "120-300 s", "300 s on")
    merged = defaultdict(list)
    for reader in readers:
        for key, values in reader.lam.items():
            merged[key].extend(values)
    for k, window in enumerate(windows):
        cells = []
        for kind in ("vessel", "clutter"):
            v = np.asarray(merged.get((k, kind), []))
            cells.append(f"{kind} {np.median(v):8.2f} ({np.mean(v > 100):.0%})" if len(v) else f"{kind} —")
        print(f"  {window:10s}", "  ".join(cells))
    rng = np.random.default_rng(0)
    print(f"\nlearned P_D at covered vessels against range (simulated {RADAR.prob_detection:.2f}; "
          f"gate {LEARNING_GATE:g} m)")
    pd = defaultdict(list)
    for reader in readers:
        for k, values in reader.pd.items():
            pd[k].extend(values)
    low = 50.0
    for k, high in enumerate(RANGES):
        r = rng.uniform(low, high, 20_000)
        across, along = r * rng.normal(0, RADAR.bearing_std, r.size), rng.normal(0, RADAR.range_std, r.size)
        within = np.mean(np.hypot(across, along) <= LEARNING_GATE)
        learned = f"{np.mean(pd[k]):.2f}" if pd[k] else "— (no vessel covered)"
        print(f"  {low / 1e3:4.1f}-{high / 1e3:4.1f} km: learned {learned}; "
              f"simulated × share within the gate {RADAR.prob_detection * within:.2f}")
        low = high


if __name__ == "__main__":
    main(sys.argv[1:])
