"""Evaluation metrics of the paper's experiment: HOTA (:mod:`.hota`) and GOSPA
(:mod:`.gospa`) on positions, both evaluated only at caller-given timestamps (the
experiment uses the radar timestamps, so the extra tracker outputs a multi-sensor tracker
makes between radar scans do not count). Both read a plain NumPy form, one
:class:`~.frames.EvaluationFrame` per time (:mod:`.frames`, which also makes frames from
Stone Soup truths and tracks); :func:`~.hota.hota` and :func:`~.gospa.gospa` do both steps
at once."""
from .frames import EvaluationFrame, frames_from_stonesoup
from .gospa import GOSPA_C, GOSPAResult, combine_gospa, gospa, gospa_from_frames, gospa_split
from .hota import (FULL_SIMILARITY_DISTANCE, HOTA_ALPHAS, ZERO_SIMILARITY_DISTANCE, HOTAResult,
                   combine_hota, hota, hota_from_frames, hota_from_similarity,
                   position_similarity)

__all__ = [
    "FULL_SIMILARITY_DISTANCE",
    "GOSPA_C",
    "HOTA_ALPHAS",
    "ZERO_SIMILARITY_DISTANCE",
    "EvaluationFrame",
    "HOTAResult",
    "GOSPAResult",
    "position_similarity",
    "hota_from_similarity",
    "hota_from_frames",
    "combine_hota",
    "gospa_from_frames",
    "combine_gospa",
    "gospa_split",
    "frames_from_stonesoup",
    "hota",
    "gospa",
]
