r"""The Gaussian-mixture point-process tracker (GM-PHD / GM-LCC) fed scan contexts: the
reference, component-by-component path.

A drop-in for :mod:`stonesoup.tracker.pointprocess` (Stone Soup 1.9.1) that hands each scan's
:class:`~ctxmodels.DetectorContext` to the context-aware updaters of
:mod:`~ctxmodels.stonesoup.gmphd.updater`, adds measurement-driven births and a surveillance
region; :class:`~ctxmodels.stonesoup.ArrayPointProcessTracker`
(:mod:`~ctxmodels.stonesoup.gmphd.array_tracker`) computes the same scans in the Rust core.
"""
from __future__ import annotations

import datetime
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from stonesoup.base import Property
from stonesoup.tracker.pointprocess import \
    PointProcessMultiTargetTracker as _StockPointProcessTracker
from stonesoup.types.state import TaggedWeightedGaussianState
from stonesoup.types.track import Track

from ..._upstream import take_attribute
from ..ordering import in_stable_order
from ..scan_context import context_kwargs, declares_context
from ..scan_checks import checked_scan, naming_scan_errors
from .birth import MeasurementDrivenBirth
from .reduction import reduce_mixture
from .region import scan_region


class PointProcessMultiTargetTracker(_StockPointProcessTracker):
    r"""The stock GM point-process tracker (GM-PHD / GM-LCC), fed scan contexts.

    Each scan's context is read from ``detections.detector_context`` (a
    :class:`~ctxmodels.DetectionSet`) and passed to an updater whose ``update`` takes a
    ``detector_context`` (:class:`PHDUpdater`, :class:`LCCUpdater`), so a scan with *no*
    detections still applies the context's P_D to every component. A hypothesiser whose
    ``hypothesise`` declares a ``detector_context`` parameter is handed it too. A stock
    updater, or a plain ``set`` of detections, gives the stock tracker's behaviour exactly.

    Per scan :math:`k`: (1) the stock ``birth_component`` (if any) and the measurement-driven
    births that are due (see :class:`~ctxmodels.stonesoup.MeasurementDrivenBirth`) join
    the mixture; (2) hypothesise, (3) update, (4) drop components whose mean lies outside the
    ``surveillance_region`` or whose position uncertainty exceeds ``max_position_std``,
    (5) reduce, (6) update and end tracks as stock; (7) the scan's
    detections queue births for later scans (births outside the region are not queued).
    Without ``birth_component`` and ``birth`` no births are added (the stock tracker needs a
    ``birth_component``).

    **Why a surveillance region.** With P_D = 0 outside every sensor's coverage and survival
    probability 1, a component that drifts out of coverage keeps its weight forever (its
    missed-detection factor is 1) and is never pruned, so the mixture grows without bound.
    The region bounds the filter honestly: the PHD is estimated inside the region only, and
    the intensity of components whose mean leaves it is discarded (not redistributed). A
    region is a :class:`CircularRegion`, any object with ``contains(points) -> bool array``
    (e.g. a :class:`~ctxmodels.LandMask` built from the region's polygon: inside = kept),
    or a callable ``f(points) -> bool array``; ``points`` are the (N, 2) world x/y of the
    component means (``position_mapping``). A region with an ``at(timestamp)`` method gives
    each scan's region from it, so a region can follow a moving platform
    (:class:`~ctxmodels.stonesoup.PoseCentredRegion`).

    **Why a bound on position uncertainty.** The same missed-detection factor of 1 lets a
    component that stays unseen *inside* the region (a radar blind sector, beyond the lidar
    while the radar is elsewhere) keep its weight while its covariance grows without bound
    (constant velocity: position variance :math:`\propto t^3`). Such a component is no
    longer a target estimate, and it is harmful: the stock reducer merges a candidate
    :math:`c` into the heaviest component :math:`b` when
    :math:`(m_c - m_b)^T P_c^{-1} (m_c - m_b) <` ``merge_threshold``, measured with the
    *candidate's* covariance (Vo & Ma's rule), so a 300 m-wide ghost swallows a well-tracked
    target hundreds of metres away and moves its mean there. ``max_position_std``
    (:math:`\sigma_{\max}`) drops, after each update, every component with
    :math:`\sqrt{\operatorname{tr} P_{xy} / 2} > \sigma_{\max}` (the RMS standard deviation
    of its x/y position); its weight is discarded, as for the region.
    """

    birth: MeasurementDrivenBirth = Property(
        default=None,
        doc="Measurement-driven birth; None keeps the stock single ``birth_component`` only.")
    surveillance_region: Any = Property(
        default=None,
        doc="Region outside which components are dropped after each update: a "
            "CircularRegion, an object with ``contains(points)``, or a callable on (N, 2) "
            "positions returning a boolean mask; an object with ``at(timestamp)`` gives the "
            "scan's region (PoseCentredRegion). None: no bound (stock).")
    max_position_std: float = Property(
        default=None,
        doc="Components whose RMS x/y position standard deviation "
            ":math:`\\sqrt{\\operatorname{tr} P_{xy}/2}` exceeds this (m) are dropped after "
            "each update. None: no bound (stock).")
    position_mapping: Sequence[int] = Property(
        default=(0, 2), doc="Indices of x and y in the state, for the surveillance region and "
                            "the position-uncertainty bound.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if self.birth is not None and not isinstance(self.birth, MeasurementDrivenBirth):
            raise TypeError(f"birth: expected a MeasurementDrivenBirth, "
                            f"got {type(self.birth).__name__}")
        region = self.surveillance_region
        if region is not None and not (hasattr(region, "contains") or callable(region)
                                       or callable(getattr(region, "at", None))):
            raise TypeError("surveillance_region: expected an object with contains(points) or "
                            f"at(timestamp), or a callable, got {type(region).__name__}")
        mapping = tuple(self.position_mapping)
        if len(mapping) != 2 or not all(isinstance(i, (int, np.integer)) and i >= 0
                                        for i in mapping) or mapping[0] == mapping[1]:
            raise ValueError(f"position_mapping: must be two different indices >= 0, got {mapping}")
        limit = self.max_position_std
        if limit is not None and not (isinstance(limit, (int, float, np.floating))
                                      and math.isfinite(limit) and limit > 0):
            raise ValueError(
                f"max_position_std: must be a finite number > 0 or None, got {limit!r}")
        self._pending_births: list[TaggedWeightedGaussianState] = []
        self._region = None  # this scan's region (see scan_region)
        # the last scan's (time, detections, their probabilities): a mapping only when read
        self._clutter_probabilities = None

    @property
    def clutter_probabilities(self) -> tuple[datetime.datetime, dict] | None:
        r"""The last scan's time and its detections, each with its posterior probability
        of being clutter in the update:
        :math:`\kappa(z) / (\kappa(z) + \sum_j p_S P_D^{(j)} w^{(j)} q^{(j)}(z))` over the
        predicted components (births included) that gate :math:`z`; 1 for a detection
        that none explains. What a clutter learner counts, in expectation
        (:class:`~ctxmodels.stonesoup.ClutterMapLearner` with ``weighting="posterior"``).
        None before the first scan, and after a scan that a stock updater updated on the
        component path (it does not report its terms)."""
        if self._clutter_probabilities is None:
            return None
        time, detections, probabilities = self._clutter_probabilities
        return time, dict(zip(detections, np.asarray(probabilities, dtype=float).tolist()))

    def _inside_mask(self, points: np.ndarray) -> np.ndarray:
        """Whether each (x, y) row of ``points`` lies in this scan's surveillance region."""
        region = self._region
        mask = region.contains(points) if hasattr(region, "contains") else region(points)
        mask = np.asarray(mask, dtype=bool).ravel()
        if mask.shape != (len(points),):
            raise ValueError(f"surveillance_region: returned {mask.shape[0]} flags for "
                             f"{len(points)} positions")
        return mask

    def _inside(self, components) -> list:
        if self._region is None or not components:
            return list(components)
        mapping = list(self.position_mapping)
        points = np.array([np.asarray(c.state_vector, dtype=np.float64).ravel()[mapping]
                           for c in components])
        mask = self._inside_mask(points)
        return [c for c, keep in zip(components, mask) if keep]

    def _certain_enough(self, components) -> list:
        """The components whose x/y position uncertainty is within ``max_position_std``."""
        if self.max_position_std is None or not components:
            return list(components)
        x, y = self.position_mapping
        position_variance = np.array([c.covar[x, x] + c.covar[y, y] for c in components],
                                     dtype=np.float64)  # tr P_xy
        keep = position_variance <= 2.0 * float(self.max_position_std) ** 2
        return [c for c, kept in zip(components, keep) if kept]

    def __next__(self) -> tuple[datetime.datetime, set[Track]]:
        # the scan checked first (see ctxmodels.stonesoup.scan_checks), so the array and
        # component paths refuse the same scans with the same message
        time, detections = checked_scan(self, next(self.detector_iter))
        with naming_scan_errors(self, time, detections):
            return self._scan(time, detections)

    def _scan(self, time, detections) -> tuple[datetime.datetime, set[Track]]:
        """One scan of the component path on a checked scan."""
        context = getattr(detections, "detector_context", None)
        # Detections in value order, not set (address) order: hypothesis order, and so the
        # merge order among equal weights, is then the same in every process.
        detections = in_stable_order(detections)
        use_context = context is not None and declares_context(self.updater.update)
        if not use_context:
            context = None

        self._region = scan_region(self.surveillance_region, time)
        if self.birth_component is not None:
            self.birth_component.timestamp = time
            self.gaussian_mixture.append(self.birth_component)
        if self.birth is not None:
            entering, self._pending_births = self.birth.due(self._pending_births, time, context)
            for component in entering:
                self.gaussian_mixture.append(component)

        # The scan's context goes to a hypothesiser that declares detector_context.
        hypothesiser = self.hypothesiser
        hypotheses = hypothesiser.hypothesise(
            self.gaussian_mixture.components, detections, time,
            **context_kwargs(detections, hypothesiser.hypothesise))
        if use_context:
            self.gaussian_mixture = self.updater.update(hypotheses, detector_context=context)
        else:
            self.gaussian_mixture = self.updater.update(hypotheses)
        reported = take_attribute(self.gaussian_mixture, "clutter_probabilities")
        self._clutter_probabilities = None if reported is None else (
            time, detections, [reported.get(detection, 1.0) for detection in detections])
        if self._region is not None:
            self.gaussian_mixture.components = self._inside(self.gaussian_mixture.components)
        if self.max_position_std is not None:
            self.gaussian_mixture.components = self._certain_enough(
                self.gaussian_mixture.components)
        # The stock reduction, its mixture in a reproducible order (see reduce_mixture)
        self.gaussian_mixture.components = reduce_mixture(self.reducer,
                                                          self.gaussian_mixture.components)
        self.update_tracks()
        self.end_tracks()

        if self.birth is not None:
            self._pending_births.extend(
                self._inside(self.birth.components(detections, time, context)))
        return time, self.tracks


__all__ = ["PointProcessMultiTargetTracker"]
