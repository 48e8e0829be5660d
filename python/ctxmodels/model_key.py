"""Measurement models compared by value, so a scan's detections group by what their models
are and not by which objects they are.

Readers and Stone Soup's own sensors build a measurement model per measurement call (a
moving radar: per scan, or per target), so detections that share one sensor at one time
carry equal models in different objects. :func:`measurement_model_key` is the one place
that decides when two models are the same: the array trackers, their initiator and the
context's position and range reads all group a scan's detections by it, and keep the first
model object of each group as the group's representative.
"""
from __future__ import annotations

from itertools import repeat
from operator import is_

import numpy as np
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.measurement.nonlinear import CartesianToBearingRange

#: The model types keyed by value: their Properties say everything their functions,
#: Jacobians and inverses read. Exact types only: a subclass may read something else.
_BY_VALUE: set[type] = {LinearGaussian, CartesianToBearingRange}


def compared_by_value(kind: type) -> type:
    """Declares that models of exactly ``kind`` are determined by their Properties (so
    :func:`measurement_model_key` keys them by value); returns ``kind``."""
    _BY_VALUE.add(kind)
    return kind


class _Identity:
    """The key of a model not compared by value: equal only to itself (the model is held,
    so its address cannot be reused while the key lives)."""

    __slots__ = ("model",)

    def __init__(self, model):
        self.model = model

    def __hash__(self) -> int:
        return id(self.model)

    def __eq__(self, other) -> bool:
        return type(other) is _Identity and other.model is self.model

    def __repr__(self) -> str:
        return f"_Identity({type(self.model).__name__} at {id(self.model):#x})"


class _NotAValue(Exception):
    """A Property value with no exact, hashable form."""


def _value(value):
    """An exact, hashable form of one Property value: arrays by type, dtype, shape and
    bytes (so equal forms mean bit-identical numbers, NaN and signed zeros included)."""
    kind = type(value)
    if kind is int or kind is bool or kind is str:
        return kind, value
    if value is None:
        return value
    if kind is tuple or kind is list:  # (a mapping: ints)
        return kind, tuple([(int, v) if type(v) is int else _value(v) for v in value])
    if kind is float:
        return float, np.float64(value).tobytes()
    if isinstance(value, np.ndarray):
        if value.dtype.hasobject:
            raise _NotAValue
        return kind, value.dtype, value.shape, value.tobytes()  # (C order)
    if isinstance(value, np.generic) and not isinstance(value, np.object_):
        return kind, value.tobytes()
    raise _NotAValue


def measurement_model_key(model):
    """A hashable key of a measurement model's value: ``LinearGaussian``,
    ``CartesianToBearingRange`` and ctxmodels' ``AnalyticCartesianToBearingRange`` (exact
    types) by their type and every Property (``ndim_state``, ``mapping``, ``noise_covar``,
    ``seed``, and ``translation_offset``, ``rotation_offset``), their arrays by their exact
    bytes — equal keys mean models of the same type whose numbers are bit-identical, so
    either gives the same results. Any other model (or a Property value with no exact form)
    is keyed by identity: equal only to itself. None is keyed None."""
    if model is None:
        return None
    kind = type(model)
    if kind in _BY_VALUE:
        try:
            return (kind, *[_value(getattr(model, name)) for name in kind.properties])
        except _NotAValue:
            pass
    return _Identity(model)


def models_by_value(models) -> dict:
    """``models`` grouped by :func:`measurement_model_key`, in first-appearance order:
    key → ``(representative, indices)``, the representative the group's first model. A list
    of one object repeated (one model per scan: the usual case) is keyed once."""
    models = list(models)
    if not models:
        return {}
    first = models[0]
    if all(map(is_, models, repeat(first))):  # (identity, at C speed)
        return {measurement_model_key(first): (first, list(range(len(models))))}
    groups: dict = {}
    keys: dict = {}  # id -> key: each object keyed once (the list holds them alive)
    for i, model in enumerate(models):
        key = keys.get(id(model))
        if key is None and id(model) not in keys:
            key = keys[id(model)] = measurement_model_key(model)
        group = groups.get(key)
        if group is None:
            groups[key] = (model, [i])
        else:
            group[1].append(i)
    return groups


def scan_model_groups(detections) -> dict:
    """:func:`models_by_value` of the detections' measurement models (None for a detection
    without one). Remembered on the collection when it takes attributes (a scan's
    :class:`~ctxmodels.stonesoup.ordering.OrderedDetections`), for as long as it holds the
    same model objects: a scan is grouped once however many parts read it."""
    models = [getattr(det, "measurement_model", None) for det in detections]
    cached = getattr(detections, "_model_groups", None)
    if cached is not None and len(cached[0]) == len(models) \
            and all(map(is_, cached[0], models)):
        return cached[1]
    groups = models_by_value(models)
    try:
        detections._model_groups = (models, groups)
    except AttributeError:  # (a set, a plain list)
        pass
    return groups


def carry_model_groups(source, target, kept) -> None:
    """Remembers on ``target`` — the detections of ``source`` at the positions ``kept``
    (ascending), in that order — their :func:`scan_model_groups`, cut from the groups
    remembered on ``source`` instead of keying the models again: a group keeps its members
    among ``kept`` (renumbered), its representative becomes its first such member's model,
    and the groups stay in first-appearance order. Nothing when ``source`` has no groups
    remembered or ``target`` takes no attributes; :func:`scan_model_groups` still checks
    the remembered models against ``target``'s own."""
    cached = getattr(source, "_model_groups", None)
    if cached is None or len(cached[0]) != len(source):
        return
    models, groups = cached
    kept = list(kept)
    if len(kept) == len(models):  # all of them: the same models and groups
        try:
            target._model_groups = cached
        except AttributeError:
            pass
        return
    kept_models = [models[i] for i in kept]
    if len(groups) == 1:  # one model value: one group of them all (or none)
        key, = groups
        cut = {key: (kept_models[0], list(range(len(kept))))} if kept else {}
    else:
        position = [-1] * len(models)
        for new, old in enumerate(kept):
            position[old] = new
        firsts = []
        for key, (_, members) in groups.items():
            renumbered = [position[i] for i in members if position[i] >= 0]
            if renumbered:
                firsts.append((renumbered[0], key, renumbered))
        firsts.sort(key=lambda entry: entry[0])  # (first members are distinct)
        cut = {key: (kept_models[members[0]], members) for _, key, members in firsts}
    try:
        target._model_groups = (kept_models, cut)
    except AttributeError:
        pass


__all__ = ["carry_model_groups", "compared_by_value", "measurement_model_key",
           "models_by_value", "scan_model_groups"]
