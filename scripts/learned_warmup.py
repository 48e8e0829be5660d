"""Where the learned GM-PHDs lose to the context-aware one, and what depends on the clutter
map's settings (docs/study.md): RMS GOSPA over the radar times of the first 120 s (the
learned models' warm-up: the map's memory is ~100 radar scans) and of the rest, on
scenarios 1 and 2, seeds 0-9, paired by scenario and seed with the context-aware GM-PHD
(mean and 95 % paired-t interval; negative: the learned model is better).

    python scripts/learned_warmup.py             # the study's learned trackers (~1.5 min)
    python scripts/learned_warmup.py --settings  # and the map's settings varied (~4 min)

A variant changes module constants of ``ctxmodels.experiment.trackers`` (``MAP_*``, and
for "full circle" the bearings the grid spans) in the worker process that runs it; every
job sets all of them, so no setting leaks into the next job.
"""
import argparse
import math
from concurrent.futures import ProcessPoolExecutor

import numpy as np

import ctxmodels.experiment.trackers as trackers
import ctxmodels.trackers.models as learned_settings
from ctxmodels.trackers import TRACKERS
from ctxmodels.experiment.runner import simulated_run, track_scans
from ctxmodels.experiment.scoring import score_run
from ctxmodels.stonesoup.ordering import in_track_order

SETTINGS = ("MAP_PRIOR_SCANS", "MAP_POOLING", "MAP_POOLING_SCANS", "MAP_WEIGHTING",
            "_seen_bearings")
DEFAULTS = {name: getattr(learned_settings, name) for name in SETTINGS}
STUDY = {"gmphd-learned-clutter": ("gmphd-learned-clutter", {}),
         "gmphd-learned": ("gmphd-learned", {})}
VARIED = {
    "learned, ring prior 10 scans": ("gmphd-learned", {"MAP_PRIOR_SCANS": 10.0}),
    "learned, pool weight 10 scans": ("gmphd-learned", {"MAP_POOLING_SCANS": 10.0}),
    "learned, pool weight 100 scans": ("gmphd-learned", {"MAP_POOLING_SCANS": 100.0}),
    "learned, gated feed": ("gmphd-learned", {"MAP_WEIGHTING": "gates"}),
    # the second edition's map: gated feed, pool weight 10 scans
    "learned, gated feed, pool weight 10 scans": ("gmphd-learned", {
        "MAP_WEIGHTING": "gates", "MAP_POOLING_SCANS": 10.0}),
    # the first edition's map: no pooling, its grid also spanned the blind sector
    "learned, gated feed, no pooling, full circle": ("gmphd-learned", {
        "MAP_WEIGHTING": "gates", "MAP_POOLING": "none", "MAP_PRIOR_SCANS": 10.0,
        "_seen_bearings": lambda model: (-math.pi, math.pi)}),
}
SCENARIOS, SEEDS = ("mixed-range", "formation"), range(10)
T19 = 2.093  # the t quantile for a 95 % interval over 20 pairs


VARIANTS = {"context": ("gmphd-context", {}), **STUDY, **VARIED}


def job(label):
    tracker, changes = VARIANTS[label]
    for name, value in {**DEFAULTS, **changes}.items():
        setattr(learned_settings, name, value)
    rms = {}
    for scenario in SCENARIOS:
        for seed in SEEDS:
            run = simulated_run(scenario, seed, None, None, None)
            t = np.array([(x - run.radar_times[0]).total_seconds() for x in run.radar_times])
            _, _, tracks = track_scans(trackers.build_tracker(TRACKERS[tracker], run))
            d = np.asarray(score_run(run, [x for x in in_track_order(tracks) if len(x)]).gospa.distance)
            rms[(scenario, seed)] = (np.sqrt(np.mean(d[t < 120] ** 2)),
                                     np.sqrt(np.mean(d[t >= 120] ** 2)))
    return label, rms


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--settings", action="store_true", help="vary the map's settings too")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    variants = ["context", *STUDY, *(VARIED if args.settings else ())]
    with ProcessPoolExecutor(args.workers) as pool:
        results = dict(pool.map(job, variants))
    for label in variants:
        if label == "context":
            continue
        parts = []
        for part, span in ((0, "first 120 s"), (1, "120-480 s")):
            diffs = np.array([results[label][key][part] - results["context"][key][part]
                              for key in sorted(results[label])])
            m, se = diffs.mean(), diffs.std(ddof=1) / np.sqrt(len(diffs))
            parts.append(f"{span} {m:+.2f} m [{m - T19 * se:+.2f}, {m + T19 * se:+.2f}]")
        print(f"{label:38s} GOSPA minus context: " + "; ".join(parts))


if __name__ == "__main__":
    main()
