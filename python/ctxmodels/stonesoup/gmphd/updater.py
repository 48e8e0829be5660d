r"""Context-aware GM-PHD and GM-LCC updaters.

Drop-ins for :mod:`stonesoup.updater.pointprocess` (Stone Soup 1.9.1). Given a scan's
:class:`~ctxmodels.DetectorContext`, the GM-PHD update (Vo & Ma 2006) uses the
state-dependent detection probability of each predicted component :math:`j` and the
clutter intensity of each detection :math:`z`:

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

import numpy as np
from scipy.stats import multivariate_normal
from stonesoup.types.numeric import Probability
from stonesoup.types.state import TaggedWeightedGaussianState
from stonesoup.types.update import GaussianMixtureUpdate
from stonesoup.updater.pointprocess import LCCUpdater as _StockLCCUpdater
from stonesoup.updater.pointprocess import PHDUpdater as _StockPHDUpdater

from ...context import DetectorContext
from ...foreign import as_array_context

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


__all__ = ["LCCUpdater", "PHDUpdater"]
