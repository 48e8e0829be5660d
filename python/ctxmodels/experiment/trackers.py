"""The study's trackers on its simulated runs: which it runs (:data:`DEFAULT_TRACKERS`), on
which scenarios (:func:`applicable`), and each built for a run (:func:`build_tracker`) by the
library's :func:`~ctxmodels.trackers.paper_tracker` (names and settings:
:mod:`ctxmodels.trackers`)."""
from __future__ import annotations

from ..pose import NavigationTrack
from ..trackers import TRACKERS, PaperTracker, TrackerSpec, paper_tracker
from .scenarios import SOLENT
from .sensors import paper_sensor_models
from .simulation.scans import ScanStream

#: Run when no trackers are named: all of them (each on the scenarios it is made for).
DEFAULT_TRACKERS = tuple(TRACKERS)


def applicable(tracker: str, scenario: str) -> bool:
    """Whether ``tracker`` runs on ``scenario``: the Solent's own list there
    (:data:`~.solent.trackers.TRACKERS`), else the tracker's ``only_scenarios``."""
    if scenario == SOLENT:
        from .solent.trackers import TRACKERS as SOLENT_TRACKERS
        return tracker in SOLENT_TRACKERS
    spec = TRACKERS[tracker]
    return spec.only_scenarios is None or scenario in spec.only_scenarios


def build_tracker(spec: TrackerSpec, run, fast: bool = True) -> PaperTracker:
    """A tracker for ``spec`` over the scans of a simulated ``run`` (iterate it):
    :func:`~ctxmodels.trackers.paper_tracker` on the run's radar and lidar streams and the
    ego's navigation (the Solent's: :func:`~.solent.trackers.build_solent_tracker`)."""
    if run.name == SOLENT:
        from .solent.trackers import build_solent_tracker
        return build_solent_tracker(spec, run, fast)
    streams = {"radar": ScanStream(run.radar_scans), "lidar": ScanStream(run.lidar_scans)}
    navigation = NavigationTrack(timestamps=run.ego.timestamps, positions=run.ego.positions,
                                 headings=run.ego.headings)
    models = paper_sensor_models(land=run.land if spec.line_of_sight or spec.coastal else ())
    return paper_tracker(spec, streams, models, navigation, primary="radar", fast=fast)
