"""The reference paper's Table II: HOTA (%) and RMS GOSPA (m) on the recorded data.

Keyed by the study's tracker names and scopes. The *baseline* rows (JPDA, uniform and
radar-only GM-PHD) are the evidence the simulated truth is calibrated against
(:mod:`~ctxmodels.experiment.calibration`); the *claimed* rows (P_D-aware, context-aware) are
what the study tests and never enter the calibration.
"""
from __future__ import annotations

from typing import NamedTuple


class Score(NamedTuple):
    """One cell pair of Table II."""

    hota: float  #: HOTA, %
    gospa: float  #: RMS GOSPA, m (c = 30 m, p = 2, α = 2)


#: Table II by tracker, then scope ("combined", then the study's scenario names).
TABLE_II: dict[str, dict[str, Score]] = {
    "jpda": {"combined": Score(67.5, 35.2), "mixed-range": Score(71.2, 29.6),
             "formation": Score(64.3, 39.5)},
    "gmphd-uniform": {"combined": Score(42.0, 49.2), "mixed-range": Score(10.1, 61.4),
                      "formation": Score(57.3, 35.2)},
    "gmphd-radar-only": {"combined": Score(74.3, 32.7), "mixed-range": Score(85.6, 24.2),
                         "formation": Score(63.0, 38.5)},
    "gmphd-pd-aware": {"combined": Score(80.1, 29.4), "mixed-range": Score(89.5, 22.1),
                       "formation": Score(71.4, 34.6)},
    "gmphd-context": {"combined": Score(81.4, 27.1), "mixed-range": Score(89.7, 21.8),
                      "formation": Score(73.5, 31.0)},
}

#: The rows that may set the simulated truth: the paper's baselines.
BASELINES = ("gmphd-radar-only", "gmphd-uniform", "jpda")
#: The rows the study tests: never used to set the truth.
CLAIMED = ("gmphd-pd-aware", "gmphd-context")

#: The JPDA that stands for the paper's where a finding names it: the better of the literal
#: (``jpda``) and the tuned one on the calibration seeds (docs/jpda_baselines.md). Both
#: show the paper's JPDA row beside them.
PAPER_JPDA = "jpda-tuned"
_ROW_OF = {"jpda-tuned": "jpda"}


def paper_row(tracker: str) -> dict[str, Score]:
    """Table II's row for a study tracker (by scope), empty when the paper has none."""
    return TABLE_II.get(_ROW_OF.get(tracker, tracker), {})


#: The scenarios the paper recorded, by the study's names.
PAPER_SCENARIOS = ("mixed-range", "formation")

__all__ = ["BASELINES", "CLAIMED", "PAPER_JPDA", "PAPER_SCENARIOS", "Score", "TABLE_II",
           "paper_row"]
