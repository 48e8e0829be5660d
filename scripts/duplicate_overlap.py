"""How often the tuned JPDA's duplicate test deletes a track that would survive if the
duplicates were judged among the time deleter's survivors only (its partner deleted by the
time window at the same scan): docs/jpda_baselines.md. Usage:
``python scripts/duplicate_overlap.py FIRST_SEED STOP_SEED`` (both paper scenarios, 480 s).

Counts, cumulative over the runs: ``time_deleted`` (the time window's verdicts),
``dup_deleted`` (the duplicate test's, not also the window's), ``extra`` (of those, the ones
the test would not delete among the window's survivors)."""
import sys

from ctxmodels.experiment.runner import simulated_run, track_scans
from ctxmodels.experiment.trackers import build_tracker
from ctxmodels.stonesoup.jpda.array_tracker import ArrayJPDATracker
from ctxmodels.trackers import TRACKERS


def main(first: int, stop: int) -> dict:
    stats = dict(time_deleted=0, dup_deleted=0, extra=0)
    deleting = ArrayJPDATracker._delete

    def counting(self, tracks, detections, latest=None):
        deleted = deleting(self, tracks, detections, latest)
        window, duplicates = self.deleter.deleters
        tracks = list(tracks)
        timed = {t for t in tracks if window.check_for_deletion(t)}
        duped = duplicates.tracks_to_delete(tracks) - timed
        after = duplicates.tracks_to_delete([t for t in tracks if t not in timed])
        stats["time_deleted"] += len(timed)
        stats["dup_deleted"] += len(duped)
        stats["extra"] += len(duped - after)
        return deleted

    ArrayJPDATracker._delete = counting
    try:
        for scenario in ("mixed-range", "formation"):
            for seed in range(first, stop):
                run = simulated_run(scenario, seed, None, None, None)
                track_scans(build_tracker(TRACKERS["jpda-tuned"], run))
                print(scenario, seed, stats, flush=True)
    finally:
        ArrayJPDATracker._delete = deleting
    return stats


if __name__ == "__main__":
    main(int(sys.argv[1]), int(sys.argv[2]))
