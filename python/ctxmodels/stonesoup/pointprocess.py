r"""Context-aware GM-PHD and GM-LCC updaters, and the point-process tracker that feeds them.

Drop-ins for :mod:`stonesoup.updater.pointprocess` and :mod:`stonesoup.tracker.pointprocess`
(Stone Soup 1.9.1). Given a scan's :class:`~ctxmodels.DetectorContext`, the GM-PHD update
(Vo & Ma 2006) uses the state-dependent detection probability of each predicted component
:math:`j` and the clutter intensity of each detection :math:`z`:

.. math::
    w^{(j)}_{k|k}(z) = \frac{P_D(m^{(j)}_{k|k-1}; S_k)\, w^{(j)}_{k|k-1}\, q^{(j)}(z)}
        {\kappa(z) + \sum_l P_D(m^{(l)}_{k|k-1}; S_k)\, w^{(l)}_{k|k-1}\, q^{(l)}(z)},
    \qquad \kappa(z) = \lambda(z; S_k),

    w^{(j)}_{k|k} = \bigl(1 - P_D(m^{(j)}_{k|k-1}; S_k)\bigr)\, w^{(j)}_{k|k-1}\, \ell_1,

with Stone Soup's survival factor :math:`p_S` applied as the stock updater applies it, and
:math:`\ell_1 = 1` for the PHD. :math:`\lambda(z; S)` takes the place of the stock
``clutter_spatial_density``: it is the clutter *intensity* in the measurement space (the
expected number of clutter points per unit measurement volume per scan), exactly what the
stock updaters add to the normaliser. Without a context both updaters are the stock ones.

P_D is evaluated for every distinct predicted component of the scan in one
:meth:`~ctxmodels.DetectorContext.prob_detection_states` call, λ for every detection that
gates at least one component in one
:meth:`~ctxmodels.DetectorContext.clutter_spatial_density_detections` call.
"""
from __future__ import annotations

import datetime
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy.stats import multivariate_normal
from stonesoup.base import Property
from stonesoup.tracker.pointprocess import \
    PointProcessMultiTargetTracker as _StockPointProcessTracker
from stonesoup.types.numeric import Probability
from stonesoup.types.state import TaggedWeightedGaussianState
from stonesoup.types.track import Track
from stonesoup.types.update import GaussianMixtureUpdate
from stonesoup.updater.pointprocess import LCCUpdater as _StockLCCUpdater
from stonesoup.updater.pointprocess import PHDUpdater as _StockPHDUpdater

from ..context import DetectorContext
from ..foreign import as_array_context
from .birth import MeasurementDrivenBirth
from .ordering import context_kwargs, declares_context, in_stable_order
from .reduction import reduce_mixture
from .scan_checks import checked_scan, naming_scan_errors
# CircularRegion lived here: YAML written with !ctxmodels.stonesoup.pointprocess.CircularRegion
# still loads through this import.
from .region import CircularRegion, scan_region  # noqa: F401

_BIRTH = TaggedWeightedGaussianState.BIRTH


class _ScanObservability:
    """P_D of every distinct predicted component and λ of every gating detection of one
    scan, each from one array call into the context."""

    def __init__(self, hypotheses, detector_context):
        detector_context = as_array_context(detector_context, "prob_detection_states",
                                            "clutter_spatial_density_detections")
        # The hypothesiser's predictor hands every hypothesis of one component the same
        # predicted state vector and covariance, so their identities key the component.
        rows: dict[tuple[int, int], int] = {}
        row_of_prediction: dict[int, int] = {}
        states = []
        for multi_hypothesis in hypotheses:
            for hypothesis in multi_hypothesis:
                prediction = hypothesis.prediction
                key = (id(prediction.state_vector), id(prediction.covar))
                row = rows.get(key)
                if row is None:
                    row = rows[key] = len(states)
                    states.append(prediction)
                row_of_prediction[id(prediction)] = row
        pd = detector_context.prob_detection_states(states).tolist()
        # Python floats: the stock arithmetic with a float P_D, Probability weights included.
        self._pd = {key: pd[row] for key, row in row_of_prediction.items()}

        gating = [multi_hypothesis for multi_hypothesis in hypotheses[:-1]
                  if len(multi_hypothesis)]
        detections = [multi_hypothesis.single_hypotheses[0].measurement
                      for multi_hypothesis in gating]
        clutter = (detector_context.clutter_spatial_density_detections(detections).tolist()
                   if detections else [])
        # A detection that gates no component has no term to normalise: no λ needed.
        self._clutter = {id(m): value for m, value in zip(gating, clutter)}

    def prob_detection(self, prediction) -> float:
        return self._pd[id(prediction)]

    def clutter(self, multi_hypothesis) -> float:
        return self._clutter[id(multi_hypothesis)]


class _ContextPointProcessUpdate:
    """The context path shared by the PHD and LCC updaters (mixed into their stock classes)."""

    def update(self, hypotheses, detector_context: DetectorContext | None = None):
        r"""Update the mixture with the hypotheses of one scan, ordered by detection with the
        missed-detection hypotheses last (``GaussianMixtureHypothesiser(...,
        order_by_detection=True)``).

        Without ``detector_context`` this is the stock update. With it, P_D comes from the
        context per predicted component and κ(z) = λ(z; S) per detection; a component with
        P_D = 0 has no detection term (its missed-detection term keeps its weight).

        The returned update's ``clutter_probabilities`` maps each detection that some
        component explains to its posterior clutter probability
        :math:`\kappa(z) / (\kappa(z) + \sum_l p_S P_D w q(z))` (the others: 1).
        """
        if detector_context is None:
            return super().update(hypotheses)
        return self._update_with_context(hypotheses, detector_context)

    def _update_with_context(self, hypotheses, detector_context):
        if len(hypotheses) == 0:
            raise ValueError("hypotheses: expected the per-detection multi-hypotheses followed "
                             "by the missed-detection one, got an empty list")
        scan = _ScanObservability(hypotheses, detector_context)
        updated_components = []
        weight_sums = []
        clutter_terms = []
        clutter_probabilities = {}
        # Same floating-point operations, in the same order, as the stock update, with the
        # scalar P_D and clutter density replaced by the context's values.
        for multi_hypothesis in hypotheses[:-1]:
            detection_components = []
            weight_sum = 0
            for hypothesis in multi_hypothesis:
                prediction = hypothesis.prediction
                prob_detection = scan.prob_detection(prediction)
                if prob_detection == 0:
                    continue  # the term is exactly zero: don't materialise it
                measurement = hypothesis.measurement
                measurement_prediction = self.updater.predict_measurement(
                    prediction, measurement.measurement_model)
                likelihood = multivariate_normal.pdf(
                    measurement.state_vector.flatten(),
                    mean=measurement_prediction.mean.flatten(),
                    cov=measurement_prediction.covar)
                weight = prob_detection * prediction.weight * likelihood
                if prediction.tag != _BIRTH:
                    weight *= self.prob_survival
                weight_sum += weight
                posterior = self.updater.update(hypothesis)
                detection_components.append(TaggedWeightedGaussianState(
                    tag=prediction.tag if prediction.tag != _BIRTH else None,
                    weight=weight,
                    state_vector=posterior.mean,
                    covar=posterior.covar,
                    timestamp=posterior.timestamp))
            weight_sums.append(weight_sum)
            clutter = scan.clutter(multi_hypothesis) if len(multi_hypothesis) else None
            clutter_terms.append(clutter)
            if weight_sum > 0:
                clutter_probabilities[multi_hypothesis.single_hypotheses[0].measurement] = \
                    float(clutter / (weight_sum + clutter))
            for component in detection_components:
                if self.normalisation:
                    component.weight /= (weight_sum + clutter)
                updated_components.append(component)

        missed = [hypothesis.prediction for hypothesis in hypotheses[-1]]
        missed_pd = [scan.prob_detection(prediction) for prediction in missed]
        l1 = self._context_update_terms(weight_sums, clutter_terms, missed, missed_pd,
                                        len(hypotheses) - 1)

        for prediction, prob_detection in zip(missed, missed_pd):
            if prediction.tag != _BIRTH:
                updated_components.append(TaggedWeightedGaussianState(
                    tag=prediction.tag,
                    weight=prediction.weight * (1 - prob_detection) * l1 * self.prob_survival,
                    state_vector=prediction.mean,
                    covar=prediction.covar,
                    timestamp=prediction.timestamp))

        # As stock: no zero weights, which the GaussianMixtureReducer would divide by.
        for component in updated_components:
            if component.weight == 0:
                component.weight = np.finfo(float).eps
        update = GaussianMixtureUpdate(hypothesis=hypotheses, components=updated_components)
        # (not a Property: read once by the tracker, see clutter_probabilities there)
        update.clutter_probabilities = clutter_probabilities
        return update

    def _context_update_terms(self, weight_sums, clutter_terms, missed, missed_pd,
                              number_of_measurements):
        raise NotImplementedError


class PHDUpdater(_ContextPointProcessUpdate, _StockPHDUpdater):
    r"""Gaussian-mixture PHD updater (Vo & Ma 2006) with per-scan context: P_D per predicted
    component and κ(z) = λ(z; S) per detection (see the module docstring). Same Properties as
    :class:`stonesoup.updater.pointprocess.PHDUpdater`, whose ``prob_detection`` and
    ``clutter_spatial_density`` apply to scans without a context.
    """

    def _context_update_terms(self, weight_sums, clutter_terms, missed, missed_pd,
                              number_of_measurements):
        return 1


class LCCUpdater(_ContextPointProcessUpdate, _StockLCCUpdater):
    r"""Gaussian-mixture LCC updater (Clark & De Melo 2018) with per-scan context.

    Besides the first-order terms of :class:`PHDUpdater`, the second-order terms take the
    context's values:

    .. math::
        \mu_d = p_S \sum_j P_D^{(j)} w^{(j)}_{k|k-1}, \qquad
        \mu_\phi = p_S \sum_j \bigl(1 - P_D^{(j)}\bigr) w^{(j)}_{k|k-1}, \qquad
        c^{(2)}_{k|k} = \mu_\phi^2\, \ell_2
            - \sum_{z} \frac{W(z)}{\bigl(W(z) + \lambda(z; S)\bigr)^2},

    with :math:`W(z)` the detection's unnormalised weight sum (zero, and no λ needed, for a
    detection that gates no component). ``mean_number_of_false_alarms`` and
    ``variance_of_false_alarms`` stay Properties: a context gives λ's density, not the
    clutter cardinality. When P_D is the same for every component of the scan, the sums are
    taken as the stock updater takes them (:math:`P_D \cdot \sum_j w^{(j)}`), so a constant
    context reproduces the stock numbers exactly.
    """

    def _context_update_terms(self, weight_sums, clutter_terms, missed, missed_pd,
                              number_of_measurements):
        predicted_weight_sum = Probability.sum(
            prediction.weight for prediction in missed) * self.prob_survival
        predicted_c2 = self.second_order_cumulant * self.prob_survival ** 2
        if not missed_pd or all(pd == missed_pd[0] for pd in missed_pd):
            prob_detection = missed_pd[0] if missed_pd else 0.0
            detected_weight_sum = prob_detection * predicted_weight_sum
            misdetected_weight_sum = (1 - prob_detection) * predicted_weight_sum
        else:
            detected_weight_sum = Probability.sum(
                pd * prediction.weight for pd, prediction in zip(missed_pd, missed)) \
                * self.prob_survival
            misdetected_weight_sum = Probability.sum(
                (1 - pd) * prediction.weight for pd, prediction in zip(missed_pd, missed)) \
                * self.prob_survival
        alpha_pred = ((predicted_weight_sum + self.mean_number_of_false_alarms) ** 2) \
            / (predicted_c2 + self.second_order_false_alarm_cumulant + 1e-26)
        denominator = alpha_pred + detected_weight_sum + self.mean_number_of_false_alarms
        numerator = alpha_pred + number_of_measurements
        l1 = numerator / denominator
        l2 = numerator / (denominator ** 2)
        detected_c2 = Probability.sum([
            0.0 if clutter is None else weight_sum / ((weight_sum + clutter) ** 2)
            for weight_sum, clutter in zip(weight_sums, clutter_terms)])
        self.second_order_cumulant = (misdetected_weight_sum ** 2) * l2 - detected_c2
        return np.float64(l1)


class PointProcessMultiTargetTracker(_StockPointProcessTracker):
    r"""The stock GM point-process tracker (GM-PHD / GM-LCC), fed scan contexts.

    Each scan's context is read from ``detections.detector_context`` (a
    :class:`~ctxmodels.DetectionSet`) and passed to an updater whose ``update`` takes a
    ``detector_context`` (:class:`PHDUpdater`, :class:`LCCUpdater`), so a scan with *no*
    detections still applies the context's P_D to every component. A hypothesiser whose
    ``hypothesise`` declares a ``detector_context`` parameter is handed it too. A stock
    updater, or a plain ``set`` of detections, gives the stock tracker's behaviour exactly.

    Per scan :math:`k`: (1) the stock ``birth_component`` (if any) and the measurement-driven
    births that are due (see :class:`~ctxmodels.stonesoup.birth.MeasurementDrivenBirth`) join
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
        reported = vars(self.gaussian_mixture).pop("clutter_probabilities", None)
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
                self._inside(self.birth.components(detections, time)))
        return time, self.tracks


__all__ = ["LCCUpdater", "PHDUpdater", "PointProcessMultiTargetTracker"]
