r"""The JPDA (and PDA) with per-scan context, and its M-of-N track initiation.

* :mod:`~ctxmodels.stonesoup.jpda.hypothesiser`: :class:`PDAHypothesiser`, the stock PDA
  hypothesiser with P_D per track and λ per detection from the scan's
  :class:`~ctxmodels.DetectorContext`.
* :mod:`~ctxmodels.stonesoup.jpda.deleter`: :class:`ExpectedMissesDeleter` (deletion on the
  expected, not the counted, number of misses), :class:`UpdateTimeStepsDeleter`,
  :class:`DuplicateTrackDeleter`, and each deletion rule's verdict from what it reads
  (Stone Soup's time and covariance deleters' too), which the component and array paths
  both call; :mod:`~ctxmodels.stonesoup.jpda.composite_deleter`: :class:`CompositeDeleter`,
  which also holds deleters comparing tracks with each other, and the composite rule.
* :mod:`~ctxmodels.stonesoup.jpda.tracker`: :class:`MultiTargetMixtureTracker` and
  :class:`MultiMeasurementInitiator`, the stock JPDA tracker and M-of-N initiator in a
  reproducible order — the reference path, component by component.
* :mod:`~ctxmodels.stonesoup.jpda.array_tracker`: :class:`ArrayJPDATracker`, the same
  Properties and tracks with each scan computed in the Rust core (what its deleter reads,
  kept per track: ``_array_deletion``); :mod:`~ctxmodels.stonesoup.jpda.array_initiator`:
  :class:`ArrayMultiMeasurementInitiator`, the M-of-N initiator with its holding tracks'
  scan in the core (the core call, the births, the holding tracks' history and what their
  deleter reads: ``_initiator_scan``, ``_initiator_births``, ``_initiator_history``,
  ``_initiator_deletion``).

The public names are those of :mod:`ctxmodels.stonesoup`.
"""
from .array_initiator import ArrayMultiMeasurementInitiator
from .array_tracker import ArrayJPDATracker
from .composite_deleter import CompositeDeleter
from .deleter import (DuplicateTrackDeleter, ExpectedMissesDeleter, MissesNotWeighedWarning,
                      UpdateTimeStepsDeleter)
from .hypothesiser import PDAHypothesiser
from .tracker import MultiMeasurementInitiator, MultiTargetMixtureTracker

__all__ = ["ArrayJPDATracker", "ArrayMultiMeasurementInitiator", "CompositeDeleter",
           "DuplicateTrackDeleter", "ExpectedMissesDeleter", "MissesNotWeighedWarning",
           "MultiMeasurementInitiator", "MultiTargetMixtureTracker", "PDAHypothesiser",
           "UpdateTimeStepsDeleter"]
