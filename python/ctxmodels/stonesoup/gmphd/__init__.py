r"""The Gaussian-mixture PHD (and LCC) filter with per-scan context.

* :mod:`~ctxmodels.stonesoup.gmphd.updater`: :class:`PHDUpdater` and :class:`LCCUpdater`,
  the stock updaters with P_D per predicted component and λ per detection from the scan's
  :class:`~ctxmodels.DetectorContext`.
* :mod:`~ctxmodels.stonesoup.gmphd.tracker`: :class:`PointProcessMultiTargetTracker`, the
  stock point-process tracker handing each scan's context to them — the reference path,
  component by component.
* :mod:`~ctxmodels.stonesoup.gmphd.array_tracker`: :class:`ArrayPointProcessTracker`, the
  same Properties and tracks with each scan computed in the Rust core (its plan of what the
  core runs: ``_plan``).
* :mod:`~ctxmodels.stonesoup.gmphd.birth`: :class:`MeasurementDrivenBirth`, births placed
  at the detections no component explains; :mod:`~ctxmodels.stonesoup.gmphd.region`: the
  surveillance region (:class:`CircularRegion`, :class:`PoseCentredRegion`);
  :mod:`~ctxmodels.stonesoup.gmphd.reduction`: mixture reduction in a reproducible order.

The public names are those of :mod:`ctxmodels.stonesoup`.
"""
from .array_tracker import ArrayPointProcessTracker
from .birth import TABLE_I_BIRTH_COVAR, MeasurementDrivenBirth
from .region import CircularRegion, PoseCentredRegion
from .tracker import PointProcessMultiTargetTracker
from .updater import LCCUpdater, PHDUpdater

__all__ = ["ArrayPointProcessTracker", "CircularRegion", "LCCUpdater", "MeasurementDrivenBirth",
           "PHDUpdater", "PointProcessMultiTargetTracker", "PoseCentredRegion",
           "TABLE_I_BIRTH_COVAR"]
