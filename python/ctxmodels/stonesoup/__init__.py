"""Drop-in components for released Stone Soup (1.9.1) that read per-scan detector contexts.

* Feeding: :class:`ContextFeeder` attaches one sensor's :class:`~ctxmodels.DetectorContext`
  to each of its scans; :class:`MultiSensorFeeder` interleaves several sensors' scans in
  time order. Either is the ``detector`` of a stock tracker.
* PDA/JPDA: :class:`PDAHypothesiser`, the stock hypothesiser with :math:`P_D` per track and
  :math:`\\lambda` per detection taken from the scan's context (stock behaviour without one).
* Track management: :class:`ExpectedMissesDeleter` deletes JPDA tracks on the expected, not
  the counted, number of missed detections.
"""
from .deleter import ExpectedMissesDeleter
from .feeder import ContextFeeder, MultiSensorFeeder
from .hypothesiser import PDAHypothesiser

__all__ = [
    "ContextFeeder",
    "ExpectedMissesDeleter",
    "MultiSensorFeeder",
    "PDAHypothesiser",
]
