"""Where the learned GM-PHDs lose to the context-aware one (docs/study.md): RMS GOSPA over
the radar times of the first 120 s (the learned models' warm-up: the map's memory is ~100
radar scans) and of the rest, on scenarios 1 and 2, seeds 0-9, paired by scenario and seed
(mean and 95 % paired-t interval). About 2 minutes on 2 cores:

    python scripts/learned_warmup.py
"""
import numpy as np
from ctxmodels.experiment.runner import simulated_run, track_scans
from ctxmodels.experiment.trackers import TRACKERS, build_tracker
from ctxmodels.experiment.scoring import score_run
from ctxmodels.stonesoup.ordering import in_track_order
T19 = 2.093  # the t quantile for a 95 % interval over 20 pairs
res = {}
for scen in ("mixed-range", "formation"):
    for seed in range(10):
        run = simulated_run(scen, seed, None, None, None)
        t = np.array([(x - run.radar_times[0]).total_seconds() for x in run.radar_times])
        for name in ("gmphd-context", "gmphd-learned-clutter", "gmphd-learned"):
            tr = build_tracker(TRACKERS[name], run)
            _, _, tracks = track_scans(tr)
            s = score_run(run, [x for x in in_track_order(tracks) if len(x)])
            d = np.asarray(s.gospa.distance)
            res[(scen, seed, name)] = (np.sqrt(np.mean(d[t < 120] ** 2)),
                                       np.sqrt(np.mean(d[t >= 120] ** 2)))
for name in ("gmphd-learned-clutter", "gmphd-learned"):
    for part, label in ((0, "first 120 s"), (1, "120-480 s")):
        diffs = np.array([res[(sc, sd, name)][part] - res[(sc, sd, "gmphd-context")][part]
                          for sc in ("mixed-range", "formation") for sd in range(10)])
        m, se = diffs.mean(), diffs.std(ddof=1) / np.sqrt(len(diffs))
        print(f"{name:22s} {label:12s} GOSPA minus context: {m:+.2f} m  "
              f"[{m - T19 * se:+.2f}, {m + T19 * se:+.2f}]")
