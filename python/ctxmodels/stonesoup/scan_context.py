"""How a scan's :class:`~ctxmodels.DetectorContext` reaches the components of a tracker.

A scan's context travels on its detections (a :class:`~ctxmodels.DetectionSet`'s
``detector_context``) or as a ``detector_context`` keyword; a component receives it only
when it declares that parameter, so stock Stone Soup components are called exactly as the
stock trackers call them.
"""
from __future__ import annotations

import functools
import inspect


def scan_context(detections, kwargs: dict):
    """The detector context of a scan: the ``detector_context`` keyword (removed from
    ``kwargs``, so it is not forwarded to predictors and updaters) or else the
    ``detector_context`` attribute of the detection set; ``None`` if neither."""
    context = kwargs.pop("detector_context", None)
    if context is None:
        context = getattr(detections, "detector_context", None)
    return context


def context_kwargs(detections, method) -> dict:
    """``{"detector_context": context}`` when the scan's detections carry a context and the
    component ``method`` (a bound ``hypothesise``, ``associate``, ``initiate`` or
    ``delete_tracks``) declares a ``detector_context`` parameter; else ``{}``.

    A component opts in by naming the parameter. Stock Stone Soup components, which take
    only ``**kwargs``, are called as the stock tracker calls them: their keyword arguments
    travel on into predictors, transition and measurement models, and some of those were
    not written for it (1.9.1's ``CompositeHypothesiser`` takes no ``**kwargs``; cached
    transition models and ``predict_lru_cache`` would key on the context)."""
    context = getattr(detections, "detector_context", None)
    if context is None or not declares_context(method):
        return {}
    return {"detector_context": context}


def declares_context(method) -> bool:
    """Whether ``method``'s signature names a ``detector_context`` parameter."""
    return _names_context(getattr(method, "__func__", method))


@functools.cache
def _names_context(function) -> bool:
    try:
        return "detector_context" in inspect.signature(function).parameters
    except (TypeError, ValueError):
        return False


__all__ = ["context_kwargs", "declares_context", "scan_context"]
