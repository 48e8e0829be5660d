r"""Batched, context-aware drop-ins for Stone Soup's GM-PHD and GM-LCC updaters.

:class:`FastPHDUpdater` and :class:`FastLCCUpdater` take the Properties of
:class:`~stonesoup.updater.pointprocess.PHDUpdater` / :class:`~stonesoup.updater.pointprocess.LCCUpdater`
and the hypotheses of :class:`~stonesoup.hypothesiser.gaussianmixture.GaussianMixtureHypothesiser`
(``order_by_detection=True``: one multi-hypothesis per detection, the missed detections last)
and return the same :class:`~stonesoup.types.update.GaussianMixtureUpdate`. All
component–detection pairs of a scan are updated in stacked arrays (Kalman or extended Kalman
updater; any other updater is called pair by pair, with the weights still batched):

.. math::
    K = \Upsilon S^{-1},\quad x^+ = x + K\,(z - \hat z),\quad
    P^+ = P - K S K^T \ \ (\text{or Joseph: } (I - KH) P (I - KH)^T + K R K^T),

    q = \mathcal{N}(z;\ \hat z, S),\quad
    w^+ = \frac{P_D\, w\, q\, p_S}{\kappa(z) + \sum_{\text{pairs of } z} P_D\, w\, q\, p_S},
    \qquad w^{\text{miss}} = (1 - P_D)\, w\, \ell_1\, p_S

(no :math:`p_S` on the birth component's pairs; :math:`\ell_1 = 1` for the PHD, the
cumulant correction for the LCC). As in the stock updaters, :math:`z - \hat z` in the update
wraps angles (Stone Soup's angle types) while the likelihood :math:`q` uses the plain float
difference, and a zero weight becomes machine epsilon.

``update(hypotheses, detector_context=None)``: without a context, the stock update
(scalar ``prob_detection`` and ``clutter_spatial_density``). With a
:class:`~ctxmodels.DetectorContext`, :math:`P_D(x)` of every predicted state comes from one
array call (``prob_detection_array``, else ``prob_detection_states``) and
:math:`\kappa(z) = \lambda(z; S)` of every detection that gates a component from one
``clutter_spatial_density_detections`` call, with the semantics of
:class:`ctxmodels.stonesoup.pointprocess.PHDUpdater` / ``LCCUpdater``: pairs with
:math:`P_D = 0` contribute nothing and produce no component.
"""
from __future__ import annotations

import numpy as np
from scipy.stats import multivariate_normal
from stonesoup.functions import find_nearest_positive_definite
from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.numeric import Probability
from stonesoup.types.state import TaggedWeightedGaussianState
from stonesoup.types.update import GaussianMixtureUpdate
from stonesoup.updater.pointprocess import LCCUpdater, PHDUpdater

from .pointprocess import LCCUpdater as ContextLCCUpdater

from .fast import (
    KALMAN_UPDATERS,
    ObjectFactory,
    _angle_rows_of,
    detection_vectors,
    gaussian_arrays,
    measurement_batch,
    stock_gaussian_pdf,
)

_BIRTH = TaggedWeightedGaussianState.BIRTH
_COMPONENT = ObjectFactory(TaggedWeightedGaussianState, dict(
    state_vector=StateVector([0.0]), covar=CovarianceMatrix([[1.0]]), timestamp=None,
    weight=0.5, tag="probe"))


def _check_context(detector_context) -> None:
    if not ((hasattr(detector_context, "prob_detection_array")
             or hasattr(detector_context, "prob_detection_states"))
            and hasattr(detector_context, "clutter_spatial_density_detections")):
        raise TypeError("detector_context: expected a ctxmodels DetectorContext (with "
                        "prob_detection_array or prob_detection_states, and "
                        "clutter_spatial_density_detections), got "
                        f"{type(detector_context).__name__}")


class _Pairs:
    """Posterior means/covariances and likelihoods of all detection hypotheses of a scan."""

    def __init__(self, means, covars, likelihoods):
        self.means = means
        self.covars = covars
        self.likelihoods = likelihoods


class _FastPointProcessUpdate:
    """The batched update shared by :class:`FastPHDUpdater` and :class:`FastLCCUpdater`."""

    # --- per-pair Kalman maths -------------------------------------------------------------
    def _kalman_pairs(self, hyps, pred_means, pred_covars) -> _Pairs:
        updater = self.updater
        k_pairs, ndim = pred_means.shape[0], pred_means.shape[1]
        measurements = [h.measurement for h in hyps]
        groups: dict = {}
        for k, measurement in enumerate(measurements):
            model = updater._check_measurement_model(measurement.measurement_model)
            groups.setdefault(id(model), (model, []))[1].append(k)

        post_means = np.empty((k_pairs, ndim, 1))
        post_covars = np.empty((k_pairs, ndim, ndim))
        likelihoods = np.empty(k_pairs)
        for model, members in groups.values():
            idx = np.asarray(members)
            # the stock likelihood re-predicts the measurement from hypothesis.prediction
            batch = measurement_batch(updater, model, pred_means[idx], pred_covars[idx])
            z, z_kinds = detection_vectors([measurements[k] for k in members])
            keys = [(id(hyps[k].prediction.state_vector), id(hyps[k].prediction.covar))
                    for k in members]
            likelihoods[idx] = stock_gaussian_pdf(z, batch.means, batch.covars, keys)

            # the Kalman update uses the hypothesis' own measurement prediction if it has one
            zp = batch.means.copy()
            innov_covars = batch.covars.copy()
            cross = batch.cross_covars.copy()
            zp_kinds = [batch.angle_rows] * len(members)
            seen: dict = {}
            for row, k in enumerate(members):
                meas_pred = hyps[k].measurement_prediction
                if meas_pred is None:
                    continue
                arrays = seen.get(id(meas_pred))
                if arrays is None:
                    vector = meas_pred.state_vector
                    arrays = (np.asarray(vector, dtype=np.float64).ravel(),
                              np.asarray(meas_pred.covar, dtype=np.float64),
                              np.asarray(meas_pred.cross_covar, dtype=np.float64),
                              _angle_rows_of(vector) if vector.dtype == object else {})
                    seen[id(meas_pred)] = arrays
                zp[row], innov_covars[row], cross[row], zp_kinds[row] = arrays

            gain = cross @ np.linalg.inv(innov_covars)
            innovation = z - zp
            for row in range(innovation.shape[1]):
                # z's own angle type wraps first (its __sub__ runs), else the prediction's
                classes = [zk.get(row, pk.get(row)) for zk, pk in zip(z_kinds, zp_kinds)]
                for cls in {c for c in classes if c is not None}:
                    mask = np.array([c is cls for c in classes])
                    innovation[mask, row] = cls.mod_angle(innovation[mask, row])
            post_means[idx] = pred_means[idx] + gain @ innovation[..., np.newaxis]
            if updater.use_joseph_cov:
                matrices = batch.matrices
                if matrices is None:
                    matrices = np.array([updater._measurement_matrix(hyps[k].prediction, model)
                                         for k in members], dtype=np.float64)
                i_kh = np.eye(ndim) - gain @ matrices
                noise = np.asarray(model.covar(), dtype=np.float64)
                post = (i_kh @ pred_covars[idx]) @ i_kh.transpose(0, 2, 1) \
                    + (gain @ noise) @ gain.transpose(0, 2, 1)
            else:
                post = pred_covars[idx] - (gain @ innov_covars) @ gain.transpose(0, 2, 1)
            post_covars[idx] = post

        if updater.force_positive_definite_covariance:
            post_covars = np.array([find_nearest_positive_definite(c) for c in post_covars])
        elif updater.force_symmetric_covariance:
            post_covars = (post_covars + post_covars.transpose(0, 2, 1)) / 2
        return _Pairs(post_means, post_covars, likelihoods)

    def _stock_pairs(self, hyps) -> _Pairs:
        """Any other single-target updater: its own calls, pair by pair, as stock."""
        means, covars, likelihoods = [], [], []
        for hypothesis in hyps:
            measurement = hypothesis.measurement
            meas_pred = self.updater.predict_measurement(
                hypothesis.prediction, measurement.measurement_model)
            likelihoods.append(multivariate_normal.pdf(
                measurement.state_vector.flatten(), mean=meas_pred.mean.flatten(),
                cov=meas_pred.covar))
            posterior = self.updater.update(hypothesis)
            means.append(np.asarray(posterior.mean, dtype=np.float64))
            covars.append(np.asarray(posterior.covar, dtype=np.float64))
        return _Pairs(np.array(means), np.array(covars), np.array(likelihoods))

    # --- the update ----------------------------------------------------------------------------
    def update(self, hypotheses, detector_context=None):
        """Update the mixture with one scan's hypotheses (ordered by detection, missed
        detections last); ``detector_context`` gives P_D per predicted state and λ per
        detection (see the module docstring). Returns a ``GaussianMixtureUpdate``."""
        if detector_context is not None:
            _check_context(detector_context)
            if len(hypotheses) == 0:
                raise ValueError("hypotheses: expected the per-detection multi-hypotheses "
                                 "followed by the missed-detection one, got an empty list")
        elif len(hypotheses) == 0:
            return super().update(hypotheses)  # the stock error

        det_hyps, owner = [], []
        for j, multi_hypothesis in enumerate(hypotheses[:-1]):
            for hypothesis in multi_hypothesis:
                det_hyps.append(hypothesis)
                owner.append(j)
        missed_hyps = list(hypotheses[-1])
        n_groups = len(hypotheses) - 1
        owner = np.asarray(owner, dtype=np.intp)

        det_preds = [h.prediction for h in det_hyps]
        missed_preds = [h.prediction for h in missed_hyps]
        det_means, det_covars = gaussian_arrays(det_preds)

        if detector_context is None:
            det_pd = missed_pd = self.prob_detection
            clutter = [self.clutter_spatial_density] * n_groups
        else:
            det_pd, missed_pd = self._context_pd(detector_context, det_preds, det_means,
                                                 det_covars, missed_preds)
            clutter = self._context_clutter(detector_context, hypotheses[:-1]).tolist()

        if detector_context is not None and det_hyps:
            keep = det_pd != 0  # a zero-P_D pair is exactly zero: no component (as pointprocess)
            if not keep.all():
                det_hyps = [h for h, k in zip(det_hyps, keep) if k]
                det_preds = [p for p, k in zip(det_preds, keep) if k]
                owner, det_pd = owner[keep], det_pd[keep]
                det_means, det_covars = det_means[keep], det_covars[keep]

        if not det_hyps:
            pairs = _Pairs(np.empty((0, 0, 1)), np.empty((0, 0, 0)), np.empty(0))
        elif type(self.updater) in KALMAN_UPDATERS:
            pairs = self._kalman_pairs(det_hyps, det_means, det_covars)
        else:
            pairs = self._stock_pairs(det_hyps)

        # Weights in Python scalars, in the stock order of operations and types (weights
        # may be Probability): bit-equal weights keep merged means bit-equal downstream.
        likelihoods = pairs.likelihoods.tolist()
        survival = self.prob_survival
        pds = ([self.prob_detection] * len(det_preds) if detector_context is None
               else det_pd.tolist())
        det_tags = [p.tag for p in det_preds]
        new_weights = []
        for prediction, tag, likelihood, prob_detection in zip(det_preds, det_tags,
                                                                likelihoods, pds):
            weight = prob_detection * prediction.weight * likelihood
            if tag != _BIRTH:
                weight *= survival
            new_weights.append(weight)
        weight_sums = [0] * n_groups
        for j, weight in zip(owner.tolist(), new_weights):
            weight_sums[j] += weight
        if self.normalisation:
            new_weights = [weight / (weight_sums[j] + clutter[j])
                           for j, weight in zip(owner.tolist(), new_weights)]

        l1 = self._fast_update_terms(weight_sums, clutter, hypotheses, missed_preds,
                                     missed_pd, detector_context)
        eps = np.finfo(float).eps
        components = []
        means = [m.view(StateVector) for m in pairs.means]
        covars = [c.view(CovarianceMatrix) for c in pairs.covars]
        for k, tag in enumerate(det_tags):
            weight = new_weights[k]
            components.append(_COMPONENT(
                tag=tag if tag != _BIRTH else None,
                weight=eps if weight == 0 else weight,
                state_vector=means[k], covar=covars[k],
                timestamp=det_hyps[k].measurement.timestamp))
        missed_pd_list = ([missed_pd] * len(missed_preds) if detector_context is None
                          else missed_pd.tolist())
        for prediction, prob_detection in zip(missed_preds, missed_pd_list):
            tag = prediction.tag
            if tag != _BIRTH:
                weight = prediction.weight * (1 - prob_detection) * l1 * survival
                components.append(_COMPONENT(
                    tag=tag,
                    weight=eps if weight == 0 else weight,
                    state_vector=prediction.mean,
                    covar=prediction.covar,
                    timestamp=prediction.timestamp))
        return GaussianMixtureUpdate(hypothesis=hypotheses, components=components)

    # --- context ---------------------------------------------------------------------------------
    @staticmethod
    def _context_pd(context, det_preds, det_means, det_covars, missed_preds):
        """P_D of every detection-hypothesis and missed-hypothesis prediction, one call."""
        missed_means, missed_covars = gaussian_arrays(missed_preds)
        n_det = len(det_preds)
        if n_det and len(missed_preds):
            means = np.concatenate([det_means, missed_means])
            covars = np.concatenate([det_covars, missed_covars])
        elif n_det:
            means, covars = det_means, det_covars
        else:
            means, covars = missed_means, missed_covars
        if len(means) == 0:
            return np.empty(0), np.empty(0)
        if hasattr(context, "prob_detection_array"):
            pd = context.prob_detection_array(means[..., 0], covars)
        else:
            pd = context.prob_detection_states(list(det_preds) + list(missed_preds))
        pd = np.asarray(pd, dtype=np.float64).ravel()
        if pd.shape != (len(means),):
            raise ValueError(f"detector_context: returned {pd.size} detection probabilities "
                             f"for {len(means)} states")
        return pd[:n_det], pd[n_det:]

    @staticmethod
    def _context_clutter(context, detection_hypotheses):
        """λ of every detection that gates a component (one call); 0 where none gates."""
        clutter = np.zeros(len(detection_hypotheses))
        gating = [j for j, mh in enumerate(detection_hypotheses) if len(mh)]
        if gating:
            detections = [detection_hypotheses[j].single_hypotheses[0].measurement
                          for j in gating]
            values = np.asarray(context.clutter_spatial_density_detections(detections),
                                dtype=np.float64).ravel()
            if values.shape != (len(gating),):
                raise ValueError(f"detector_context: returned {values.size} clutter densities "
                                 f"for {len(gating)} detections")
            clutter[gating] = values
        return clutter

    def _fast_update_terms(self, weight_sums, clutter, hypotheses, missed_preds,
                           missed_pd, detector_context):
        raise NotImplementedError


class FastPHDUpdater(_FastPointProcessUpdate, PHDUpdater):
    r"""GM-PHD updater (Vo & Ma 2006) computing a whole scan in stacked arrays, with an
    optional per-scan detector context.

    Same Properties as :class:`stonesoup.updater.pointprocess.PHDUpdater`;
    ``prob_detection`` and ``clutter_spatial_density`` apply to scans without a context.
    Same output as the stock updater (and, with a context, as
    :class:`ctxmodels.stonesoup.pointprocess.PHDUpdater`): see the module docstring.
    """

    def _fast_update_terms(self, weight_sums, clutter, hypotheses, missed_preds,
                           missed_pd, detector_context):
        return 1


class FastLCCUpdater(_FastPointProcessUpdate, LCCUpdater):
    r"""GM-LCC updater (Clark & De Melo 2018) computing a whole scan in stacked arrays, with
    an optional per-scan detector context.

    Same Properties as :class:`stonesoup.updater.pointprocess.LCCUpdater`, including the
    second-order cumulant carried from scan to scan. With a context (as
    :class:`ctxmodels.stonesoup.pointprocess.LCCUpdater`):

    .. math::
        \mu_d = p_S \sum_j P_D^{(j)} w^{(j)}, \quad
        \mu_\phi = p_S \sum_j \bigl(1 - P_D^{(j)}\bigr) w^{(j)}, \quad
        c^{(2)} = \mu_\phi^2\, \ell_2 - \sum_z \frac{W(z)}{(W(z) + \lambda(z))^2}

    over the missed-detection hypotheses (birth included, as stock), :math:`W(z)` the
    unnormalised weight sum of detection :math:`z`.
    """

    def _fast_update_terms(self, weight_sums, clutter, hypotheses, missed_preds,
                           missed_pd, detector_context):
        if detector_context is None:
            # the stock terms, on the stock inputs (it reads hypotheses[-1] itself)
            return self._calculate_update_terms(weight_sums, hypotheses)
        # The context terms are the context-aware LCCUpdater's own, on the same inputs:
        # a detection that gated nothing has no λ term.
        clutter_terms = [clutter[j] if len(hypotheses[j]) else None
                         for j in range(len(weight_sums))]
        return ContextLCCUpdater._context_update_terms(
            self, weight_sums, clutter_terms, missed_preds, missed_pd.tolist(),
            len(hypotheses) - 1)


__all__ = ["FastLCCUpdater", "FastPHDUpdater"]
