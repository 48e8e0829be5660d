"""Tracking time of the experiment's JPDA on scenario 1: component path vs whole-scan arrays.

Array path: the tracker ``ctxmodels.experiment`` builds (``ArrayJPDATracker`` and
``ArrayMultiMeasurementInitiator``: one Rust call per JPDA scan, holding tracks as arrays).
Component path: the same components in ctxmodels' ``MultiTargetMixtureTracker`` and
``MultiMeasurementInitiator`` (with ``FastGNNWith2DAssignment``, stock ``JPDAwithEHM2``
over the ``PDAHypothesiser``, the miss-counting deleters) — the experiment's path before.

Time is tracking only, measured as ``ctxmodels.experiment.runner.run_job`` measures it (the
loop over the tracker; the simulation is made before). Both runs are made in this process,
one after the other, on the same simulated scans; the ratio is of those two measurements.

    python benches/bench_jpda.py                      # 480 s, both paths (≈ 3 min)
    python benches/bench_jpda.py --duration 30        # a quick look
    python benches/bench_jpda.py --array-only         # skip the slow component run
    python benches/bench_jpda.py --tracker jpda-context --json out.json
"""
from __future__ import annotations

import argparse
import json
import sys
import time


def build(tracker: str, run, array: bool):
    """The experiment's tracker (the array path), or the same components in the
    component path that was the default before it (ctxmodels' stock-derived JPDA tracker
    and initiator, fast GNN association)."""
    from ctxmodels.experiment import trackers
    from ctxmodels.stonesoup import MultiMeasurementInitiator, MultiTargetMixtureTracker
    built = trackers.build_tracker(trackers.TRACKERS[tracker], run)
    if array:
        return built
    held = built.initiator
    initiator = MultiMeasurementInitiator(
        prior_state=held.prior_state, deleter=held.deleter,
        data_associator=held.data_associator, updater=held.updater,
        measurement_model=held.measurement_model, min_points=held.min_points,
        updates_only=held.updates_only)
    return MultiTargetMixtureTracker(initiator=initiator, deleter=built.deleter,
                                     detector=built.detector,
                                     data_associator=built.data_associator, updater=built.updater)


def track(tracker) -> dict:
    """Runs the tracker over all scans; tracking seconds, scans and distinct tracks."""
    started = time.perf_counter()
    seen = set()
    scans = 0
    for _, tracks in tracker:
        seen |= tracks
        scans += 1
    seconds = time.perf_counter() - started
    return {"seconds": seconds, "scans": scans, "tracks": len(seen)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=480.0, help="scenario length, s")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--scenario", default="mixed-range")
    parser.add_argument("--tracker", default="jpda", choices=("jpda", "jpda-context"))
    parser.add_argument("--array-only", action="store_true", help="skip the component run")
    parser.add_argument("--json", help="write the results to this file")
    args = parser.parse_args(argv)

    from ctxmodels.experiment.scenarios import make_scenario
    results = {"scenario": args.scenario, "seed": args.seed, "duration": args.duration,
               "tracker": args.tracker}
    for name, array in (("array", True), ("component", False)):
        if not array and args.array_only:
            continue
        run = make_scenario(args.scenario, args.seed, args.duration)  # fresh detections
        tracker = build(args.tracker, run, array)
        outcome = track(tracker)
        if array:
            outcome["array_scans"] = tracker.array_scans
            outcome["component_scans"] = tracker.component_scans
        results[name] = outcome
        print(f"{name:>9}: {outcome['seconds']:8.2f} s tracking, {outcome['scans']} scans, "
              f"{outcome['tracks']} tracks", flush=True)
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
