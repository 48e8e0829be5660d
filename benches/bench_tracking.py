"""Tracking time of one experiment tracker over a whole scenario: array path vs component path.

Array path: the tracker ``ctxmodels.experiment`` builds — ``ArrayPointProcessTracker`` for
the GM-PHD variants, ``ArrayJPDATracker`` with ``ArrayMultiMeasurementInitiator`` for the
JPDA ones (whole scans in the Rust core). Component path: the same components scan by scan
in the stock-derived trackers (``--stock`` in the experiment): ``PointProcessMultiTargetTracker``,
or ``MultiTargetMixtureTracker`` with ``MultiMeasurementInitiator`` (fast GNN association,
stock ``JPDAwithEHM2`` over the ``PDAHypothesiser``, the miss-counting deleters).

Time is tracking only, measured by the loop ``ctxmodels.experiment.runner.run_job`` uses
(``track_scans``: the simulation is made before; the garbage collector paused while it
tracks). Both paths run in this process, one after the other, on freshly simulated scans of
the same seed; the ratio is of those two measurements. ``--repeats`` takes the minimum of
several runs of each (a shared machine only ever makes a run slower).

    python benches/bench_tracking.py                              # JPDA, 480 s, both paths
    python benches/bench_tracking.py --tracker gmphd-context --array-only --repeats 3
    python benches/bench_tracking.py --duration 30                # a quick look
    python benches/bench_tracking.py --tracker jpda-context --json out.json
    python benches/bench_tracking.py --tracker gmphd-context --models  # per scan vs per detection

``--models``: the array path twice, on the simulated scans as they are (one measurement-model
object per sensor and scan) and with each detection given its own copy of its model (equal
values, as readers and Stone Soup's sensors make them); the ratio is of those two.
"""
from __future__ import annotations

import argparse
import json
import sys


def build(tracker: str, run, array: bool):
    """The experiment's tracker (the array path), or the same components in the component
    path (for the JPDA: ctxmodels' stock-derived tracker and initiator, fast GNN)."""
    from ctxmodels.experiment import trackers
    from ctxmodels.trackers import TRACKERS
    from ctxmodels.stonesoup import MultiMeasurementInitiator, MultiTargetMixtureTracker
    spec = TRACKERS[tracker]
    built = trackers.build_tracker(spec, run).tracker
    if array:
        return built
    if spec.family != "jpda":
        return trackers.build_tracker(spec, run, fast=False).tracker
    held = built.initiator
    initiator = MultiMeasurementInitiator(
        prior_state=held.prior_state, deleter=held.deleter,
        data_associator=held.data_associator, updater=held.updater,
        measurement_model=held.measurement_model, min_points=held.min_points,
        updates_only=held.updates_only)
    return MultiTargetMixtureTracker(initiator=initiator, deleter=built.deleter,
                                     detector=built.detector,
                                     data_associator=built.data_associator, updater=built.updater)


def own_models(run) -> None:
    """Gives every detection of ``run`` its own copy of its measurement model (equal values)."""
    import copy
    for scan in (*run.radar_scans, *run.lidar_scans):
        for detection in scan.detections:
            detection.measurement_model = copy.deepcopy(detection.measurement_model)


def track(tracker) -> dict:
    """Runs the tracker over all scans as a job does; tracking seconds, scans, tracks."""
    from ctxmodels.experiment.runner import track_scans
    seconds, scans, tracks = track_scans(tracker)
    return {"seconds": seconds, "scans": scans, "tracks": len(tracks)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=480.0, help="scenario length, s")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--scenario", default="mixed-range")
    parser.add_argument("--tracker", default="jpda",
                        help="an experiment tracker (ctxmodels experiment --help lists them)")
    parser.add_argument("--repeats", type=int, default=1, help="runs per path (minimum kept)")
    parser.add_argument("--array-only", action="store_true", help="skip the component run")
    parser.add_argument("--models", action="store_true",
                        help="array path only: one model object per scan vs one per detection")
    parser.add_argument("--json", help="write the results to this file")
    args = parser.parse_args(argv)

    from ctxmodels.experiment.scenarios import make_scenario
    from ctxmodels.trackers import TRACKERS
    if args.tracker not in TRACKERS:
        parser.error(f"--tracker: unknown tracker {args.tracker!r}; choose from {sorted(TRACKERS)}")
    if args.repeats < 1:
        parser.error("--repeats: must be at least 1")
    results = {"scenario": args.scenario, "seed": args.seed, "duration": args.duration,
               "tracker": args.tracker}
    variants = ((("array", True, False), ("per-detection models", True, True)) if args.models
                else (("array", True, False), ("component", False, False)))
    for name, array, per_detection in variants:
        if not array and args.array_only:
            continue
        outcome = None
        for _ in range(args.repeats):
            run = make_scenario(args.scenario, args.seed, args.duration)  # fresh detections
            if per_detection:
                own_models(run)
            tracker = build(args.tracker, run, array)
            measured = track(tracker)
            if outcome is not None and measured["tracks"] != outcome["tracks"]:
                raise RuntimeError("the same seed gave different tracks in two runs")
            if outcome is None or measured["seconds"] < outcome["seconds"]:
                outcome = measured
            if array and hasattr(tracker, "array_scans"):  # (the JPDA counts its paths' scans)
                outcome["array_scans"] = tracker.array_scans
                outcome["component_scans"] = tracker.component_scans
        results[name] = outcome
        print(f"{name:>20}: {outcome['seconds']:8.2f} s tracking (min of {args.repeats}), "
              f"{outcome['scans']} scans, {outcome['tracks']} tracks", flush=True)
    if "per-detection models" in results:
        ratio = results["per-detection models"]["seconds"] / results["array"]["seconds"]
        results["models_ratio"] = ratio
        print(f"per-detection / per-scan models: {ratio:.2f}x (measured in this run)")
    if "component" in results:
        ratio = results["component"]["seconds"] / results["array"]["seconds"]
        results["speed_up"] = ratio
        print(f"speed-up: {ratio:.1f}x (component / array, measured in this run)")
    if args.json:
        with open(args.json, "w") as handle:
            json.dump(results, handle, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
