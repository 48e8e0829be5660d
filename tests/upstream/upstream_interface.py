"""A stand-in for the detector-context interface of Stone Soup's pull request #1291, written
from its published facts (not its code), for testing ctxmodels against that interface while
the installed Stone Soup (1.9.1) does not have it.

The facts: ``stonesoup.types.detector_context.DetectorContext`` is a plain abstract class
(``abc.ABC``, not a Stone Soup ``Base``) with two abstract methods, ``prob_detection(
hypothesis)`` returning a ``Probability`` and ``clutter_spatial_density(detection)``
returning a float; ``SimpleDetectorContext`` holds a value or a callable for each (defaults
P_D 1 and λ 1e-26); ``stonesoup.types.detection.DetectionSet`` is a ``set`` with a
``detector_context`` attribute (None by default).

:func:`install` must run before ``stonesoup.types.detection``'s users and ctxmodels are
imported; tests call it in a fresh process.
"""
from __future__ import annotations

import abc
import sys
import types


def _interface_module() -> types.ModuleType:
    from stonesoup.types.numeric import Probability

    module = types.ModuleType("stonesoup.types.detector_context")

    class DetectorContext(abc.ABC):
        """Stand-in: a sensor's P_D and clutter density at one scan."""

        @abc.abstractmethod
        def prob_detection(self, hypothesis):
            """P_D of the hypothesis' prediction, a Probability."""

        @abc.abstractmethod
        def clutter_spatial_density(self, detection):
            """λ at the detection, a float."""

    class SimpleDetectorContext(DetectorContext):
        """Stand-in: each answer is a fixed value or a function of its argument."""

        def __init__(self, prob_detection=Probability(1), clutter_spatial_density=1e-26):
            self._pd, self._clutter = prob_detection, clutter_spatial_density

        def prob_detection(self, hypothesis):
            return self._pd(hypothesis) if callable(self._pd) else Probability(self._pd)

        def clutter_spatial_density(self, detection):
            if callable(self._clutter):
                return self._clutter(detection)
            return self._clutter

    for cls in (DetectorContext, SimpleDetectorContext):
        cls.__module__ = module.__name__
        setattr(module, cls.__name__, cls)
    return module


class DetectionSet(set):
    """Stand-in: the detections of a scan, with the detector context of that scan."""

    def __init__(self, detections=(), detector_context=None):
        super().__init__(detections)
        self.detector_context = detector_context


def install() -> types.ModuleType:
    """Puts the stand-in where the pull request puts the interface; returns its module."""
    import stonesoup.types
    import stonesoup.types.detection as detection

    module = _interface_module()
    sys.modules[module.__name__] = module
    stonesoup.types.detector_context = module
    DetectionSet.__module__ = detection.__name__
    detection.DetectionSet = DetectionSet
    return module

