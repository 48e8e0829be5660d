"""What a :class:`~ctxmodels.DetectorContext` prepares once for its scan's P_D and λ calls.

A tracker asks a scan's context for :math:`P_D` once per hypothesis (Stone Soup's stock
hypothesisers and updaters) or once per batch of a few states. Reading the context's
Properties, converting the pose, checking the position mapping and wrapping the result in
a new :class:`~stonesoup.types.numeric.Probability` on every call would cost several
microseconds of Python around a fraction of a microsecond in the core. :class:`ScanCalls`
does that work once per context: the snapshot of the detection model that the whole scan
evaluates (its learned factors fixed as they stand, :meth:`~ctxmodels.DetectionProbabilityModel.frozen`), that
snapshot in the core at the scan's pose and mapping (and the sensor model's rule for the
expected P_D of a Gaussian), the clutter model at the pose, and one ``Probability`` per
distinct P_D value (a scan has a handful: products of band, sector and land values).
"""
from __future__ import annotations

from stonesoup.types.numeric import Probability

from . import _core


class ScanCalls:
    """The ``detection`` snapshot and the clutter model of ``sensor_model`` fixed at ``pose``
    for the thin calls; the values are the general path's, bit for bit (tested)."""

    __slots__ = ("detection", "at_pose", "mean_only", "_probabilities", "_clutter",
                 "_clutter_at_pose")

    #: Distinct P_D values whose Probability is kept (a scan has a handful).
    max_probabilities = 256

    def __init__(self, sensor_model, detection, pose):
        #: What every P_D path of the context evaluates: ``sensor_model``'s detection model
        #: with its learned factors fixed (one snapshot for the scan).
        self.detection = detection
        self.at_pose = _core.DetectionAtPose(self.detection._compiled(),
                                             pose.as_tuple(),
                                             sensor_model.core_mapping,
                                             sensor_model.pd_evaluation, sensor_model.pd_order)
        self._clutter = (sensor_model.clutter, pose)
        self._clutter_at_pose = None
        #: P_D is read at the mean of a Gaussian (no integration over its covariance).
        self.mean_only = sensor_model.pd_evaluation == "mean"
        self._probabilities: dict[float, Probability] = {}

    @property
    def clutter_at_pose(self) -> _core.ClutterAtPose:
        """The clutter model at the pose, built on the first λ call that uses it (the
        trackers' λ calls on detections take the general path)."""
        at_pose = self._clutter_at_pose
        if at_pose is None:
            clutter, pose = self._clutter
            at_pose = self._clutter_at_pose = _core.ClutterAtPose(clutter._compiled(),
                                                                  pose.as_tuple())
        return at_pose

    def probability(self, value: float) -> Probability:
        """``Probability(value)``, built once per distinct value (Probabilities are
        immutable numbers, so the callers may share one)."""
        found = self._probabilities.get(value)
        if found is None:
            if len(self._probabilities) >= self.max_probabilities:
                self._probabilities.clear()
            found = self._probabilities[value] = Probability(value)
        return found
