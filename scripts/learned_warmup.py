"""Where the learned GM-PHDs lose to the context-aware one, and what depends on the clutter
map's settings (docs/study.md): RMS GOSPA over the radar times of the first 120 s (the
learned models' warm-up: the map's memory is ~100 radar scans) and of the rest, on
scenarios 1 and 2, seeds 0-9, paired by scenario and seed with the context-aware GM-PHD
(mean and 95 % paired-t interval; negative: the learned model is better).

    python scripts/learned_warmup.py             # the study's learned trackers (~1.5 min)
    python scripts/learned_warmup.py --settings  # and the map's settings varied (~4 min)

A variant is the study's spec with its ``clutter_map`` settings replaced
(:class:`~ctxmodels.trackers.models.ClutterMapSettings`).
"""
import argparse
from concurrent.futures import ProcessPoolExecutor

import numpy as np

import dataclasses

import ctxmodels.experiment.trackers as trackers
from ctxmodels.trackers import TRACKERS
from ctxmodels.experiment.runner import simulated_run, track_scans
from ctxmodels.experiment.scoring import score_run
from ctxmodels.stonesoup.ordering import in_track_order

STUDY = {"gmphd-learned-clutter": ("gmphd-learned-clutter", {}),
         "gmphd-learned": ("gmphd-learned", {})}
#: Variants of the learned map: changes to the spec's ClutterMapSettings.
VARIED = {
    "learned, ring prior 10 scans": ("gmphd-learned", {"prior_scans": 10.0}),
    "learned, pool weight 10 scans": ("gmphd-learned", {"pooling_scans": 10.0}),
    "learned, pool weight 100 scans": ("gmphd-learned", {"pooling_scans": 100.0}),
    "learned, gated feed": ("gmphd-learned", {"weighting": "gates"}),
    "learned, gated feed, pool weight 10 scans": ("gmphd-learned", {
        "weighting": "gates", "pooling_scans": 10.0}),
    # no pooling, and a grid that also spans the blind sector
    "learned, gated feed, no pooling, full circle": ("gmphd-learned", {
        "weighting": "gates", "pooling": "none", "prior_scans": 10.0, "full_circle": True}),
}
SCENARIOS, SEEDS = ("mixed-range", "formation"), range(10)
T19 = 2.093  # the t quantile for a 95 % interval over 20 pairs


VARIANTS = {"context": ("gmphd-context", {}), **STUDY, **VARIED}


def job(label):
    tracker, changes = VARIANTS[label]
    spec = TRACKERS[tracker]
    spec = dataclasses.replace(spec, clutter_map=dataclasses.replace(spec.clutter_map, **changes))
    rms = {}
    for scenario in SCENARIOS:
        for seed in SEEDS:
            run = simulated_run(scenario, seed, None, None, None)
            t = np.array([(x - run.radar_times[0]).total_seconds() for x in run.radar_times])
            _, _, tracks = track_scans(trackers.build_tracker(spec, run))
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
