r"""A detection probability learned online: a P_D factor whose per-band values come from
whether the tracks a sensor should have seen were detected, scan after scan.

Band :math:`b = [e_b, e_{b+1})` of range from the sensor holds a Beta posterior over its
detection probability :math:`p_b`. A Beta(:math:`p_0 s_0,\ (1 - p_0) s_0`) prior — mean
:math:`p_0`, worth :math:`s_0` trials — updated with trials :math:`j` (one track at one
scan: hit :math:`d_j \in \{0, 1\}`, weight :math:`w_j \in [0, 1]`), each discounted by
:math:`\gamma` per update since (exponential forgetting), has the posterior mean

.. math::
    \hat p_b = \frac{p_0 s_0 + H_b}{s_0 + T_b}, \qquad
    H_b = \sum_{j:\, w_j > 0} \gamma^{k-j} d_j, \qquad T_b = \sum_j \gamma^{k-j} w_j,

clamped to [0, 1]: the factor's value at a range in band :math:`b` (``outside`` below the
first edge and from the last on). The weight of a trial is the product of the sensor's
*other* P_D factors at the track: a track in a blind sector or behind land (weight 0) is no
evidence about :math:`p_b`, hit or miss — it changes neither :math:`H_b` nor :math:`T_b`.
With weights 0 or 1 — sectors, land and line of sight — the
estimate is the Beta posterior mean exactly; with fractional weights it is the ratio
estimator :math:`\sum d / \sum w`, shrunk to the prior. Where there is no evidence, it
stays at :math:`p_0`.

Like :class:`~ctxmodels.ClutterMap` the estimate is *state*: every
:class:`~ctxmodels.DetectionProbabilityModel` built with it reads it as it stands when the
model is put at a scan's pose (a :class:`~ctxmodels.DetectorContext` keeps that for the
scan), so an update after a scan's tracking reaches the scans after it, never the scan
itself. :class:`~ctxmodels.stonesoup.DetectionLearner` feeds it from a tracker's output.
Its state (:attr:`hits`, :attr:`trials`) pickles and round-trips through Stone Soup's YAML
exactly.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from stonesoup.base import Property

from . import _core
from ._component import LearnedComponent, as_array, as_float, as_rows
from .pose import Pose, pose_tuple
from .range_bands import RangeBands


class DetectionEstimate(LearnedComponent):
    """An online P_D estimate per range band (see the module docs); a factor of
    :class:`~ctxmodels.DetectionProbabilityModel`."""

    edges: Sequence[float] = Property(doc="Band edges in metres of range from the sensor, "
                                          "strictly increasing, >= 0; at least two. Bands "
                                          "are half-open, [e_b, e_(b+1)).")
    prior_probability: float = Property(doc=r"Prior P_D :math:`p_0`, in (0, 1).")
    prior_trials: float = Property(default=5.0, doc=r"Prior weight :math:`s_0` in trials (> 0).")
    forgetting: float = Property(default=0.99, doc=r"Forgetting factor :math:`\gamma` per "
                                                   "update, in (0, 1]; memory ≈ 1/(1 − γ) scans.")
    outside: float = Property(default=0.0, doc="The factor below the first edge and from the "
                                               "last edge on, in [0, 1] (0: the sensor sees "
                                               "nothing there).")
    hits: np.ndarray = Property(default=None, doc="State: the discounted hits per band. None: "
                                                  "a fresh estimate. Read back, the current state.")
    trials: np.ndarray = Property(default=None, doc="State: the discounted trial weights per "
                                                    "band. None: a fresh estimate.")

    STATE = (("hits", None), ("trials", None))

    @hits.getter
    def hits(self) -> np.ndarray:
        return self._core.state()[0]

    @trials.getter
    def trials(self) -> np.ndarray:
        return self._core.state()[1]

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.edges = tuple(as_array(self.edges, "edges", 1, "(B + 1,) band edges").tolist())
        self._start()

    def _build(self, hits, trials) -> _core.DetectionEstimate:
        bands = max(len(self.edges) - 1, 0)
        hits, trials = (_per_band(values, name, bands) for values, name in
                        ((hits, "hits"), (trials, "trials")))
        # (finite=False: the core names non-finite values with the rule they break)
        number = lambda value, name: as_float(value, name, finite=False)  # noqa: E731
        return _core.DetectionEstimate(list(self.edges),
                                       number(self.prior_probability, "prior_probability"),
                                       number(self.prior_trials, "prior_trials"),
                                       number(self.forgetting, "forgetting"),
                                       number(self.outside, "outside"), hits, trials)

    def update(self, pose: Pose | Sequence[float], positions, detected, weights=None) -> None:
        """One scan's trials: tracks at world ``positions`` (M, 2), whether each was
        ``detected`` (M,) (booleans or 0/1), and their ``weights`` (M,) in [0, 1] (None:
        all 1). Forgets one scan even without trials."""
        positions = as_rows(positions, "positions", ncols=2)
        detected = np.asarray(as_array(detected, "detected", 1, "(M,) 0/1 flags"),
                              dtype=np.float64)
        weights = (np.ones(len(positions)) if weights is None
                   else as_array(weights, "weights", 1, "(M,) weights"))
        self._core.update(pose_tuple(pose), positions, detected, weights)

    def probabilities(self) -> np.ndarray:
        """The posterior mean P_D of every band, (B,)."""
        return self._core.probabilities()

    def bands(self) -> RangeBands:
        """The estimate as it stands, as fixed :class:`~ctxmodels.RangeBands`: ``outside``
        below the first edge and from the last on, :meth:`probabilities` between, each edge
        in the band above it. What a scan's P_D reads (the same bits)."""
        probabilities = self.probabilities()
        # Every scan asks; between updates the estimate is the same, bit for bit, and so is
        # the (immutable) RangeBands it gives, kept with the bytes it was built from.
        key = probabilities.tobytes()
        last = self.__dict__.get("_cached_bands")
        if last is not None and last[0] == key:
            return last[1]
        bands = RangeBands(edges=self.edges,
                           values=(self.outside, *probabilities.tolist(), self.outside),
                           upper_owns=True)
        self.__dict__["_cached_bands"] = (key, bands)
        return bands



def _per_band(values, argument: str, bands: int) -> list | None:
    if values is None:
        return None
    values = as_array(values, argument, 1, f"({bands},) values, one per band")
    if values.shape != (bands,):
        raise ValueError(f"{argument}: must have {bands} entries (one per band), got "
                         f"{values.shape[0]}")
    return values.tolist()


__all__ = ["DetectionEstimate"]
