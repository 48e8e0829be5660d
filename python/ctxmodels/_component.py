"""Shared behaviour of ctxmodels' declarative components.

Every model component is a Stone Soup :class:`~stonesoup.base.Base` with documented
Properties, so it prints, pickles and round-trips through Stone Soup's YAML serialiser like
any Stone Soup component. On top of that, ctxmodels components are *immutable values*:

* they compare equal when their Properties are equal (NumPy arrays compared by value) and
  hash accordingly;
* assigning a Property after construction raises, because the Rust object a component
  compiles to is built once and cached — mutating the Python side would silently leave the
  compiled model behind. Build a new component instead.
"""
from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from stonesoup.base import Base

_CACHE_PREFIX = "_cached_"


def _frozen_value(value: Any) -> Any:
    """A hashable stand-in for a Property value, equal exactly when the values are equal."""
    if isinstance(value, np.ndarray):
        return ("ndarray", value.shape, str(value.dtype), value.tobytes())
    if isinstance(value, Mapping):
        return ("mapping", tuple(sorted((k, _frozen_value(v)) for k, v in value.items())))
    if isinstance(value, (list, tuple)):
        return ("sequence", tuple(_frozen_value(v) for v in value))
    if isinstance(value, float) and math.isnan(value):
        return ("nan",)
    return value


class ModelComponent(Base):
    """Base of ctxmodels components: immutable, value-equal, cached compilation."""

    def __init__(self, *args, **kwargs):
        object.__setattr__(self, "_initialised", False)
        super().__init__(*args, **kwargs)
        object.__setattr__(self, "_initialised", True)

    def __setattr__(self, name, value):
        if getattr(self, "_initialised", False) and name in type(self).properties:
            raise AttributeError(
                f"{type(self).__name__}.{name}: ctxmodels components are immutable once built "
                f"(their compiled Rust model is cached); construct a new {type(self).__name__}")
        super().__setattr__(name, value)

    def _equality_key(self) -> tuple:
        return tuple(_frozen_value(getattr(self, name)) for name in type(self).properties)

    def __eq__(self, other):
        if type(other) is not type(self):
            return NotImplemented
        return self._equality_key() == other._equality_key()

    def __hash__(self):
        return hash((type(self).__qualname__, self._equality_key()))

    def _cached(self, key: str, build):
        """The value `build()` returns, computed once per component (compiled Rust models)."""
        attr = _CACHE_PREFIX + key
        try:
            return self.__dict__[attr]
        except KeyError:
            value = build()
            self.__dict__[attr] = value
            return value

    # Compiled Rust objects are caches, not state: leave them out of pickles and copies.
    def __getstate__(self):
        return {k: v for k, v in self.__dict__.items() if not k.startswith(_CACHE_PREFIX)}

    def __setstate__(self, state):
        self.__dict__.update(state)


def as_float(value: Any, name: str, *, finite: bool = True) -> float:
    """`value` as a float, with a clear error naming the argument."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name}: expected a number, got {type(value).__name__}")
    value = float(value)
    if finite and not math.isfinite(value):
        raise ValueError(f"{name}: must be finite, got {value}")
    return value


def as_float_tuple(values: Any, name: str) -> tuple[float, ...]:
    if isinstance(values, (str, bytes)) or not isinstance(values, (Sequence, np.ndarray)):
        raise TypeError(f"{name}: expected a sequence of numbers, got {type(values).__name__}")
    return tuple(as_float(v, f"{name}[{i}]") for i, v in enumerate(values))


def as_rows(array: Any, name: str, *, ncols: int | None = None) -> np.ndarray:
    """A C-contiguous (N, D) float64 array from `array`, or a clear error naming it."""
    try:
        rows = np.asarray(array)
    except Exception as err:  # ragged lists and the like
        raise TypeError(f"{name}: cannot be read as a numeric array ({err})") from None
    if rows.dtype == object or not (np.issubdtype(rows.dtype, np.number) or rows.dtype == np.bool_):
        raise TypeError(f"{name}: must be a numeric array, got dtype {rows.dtype}")
    if np.iscomplexobj(rows):
        raise TypeError(f"{name}: must be real, got dtype {rows.dtype}")
    if rows.ndim != 2:
        raise ValueError(f"{name}: must be a 2-D array of rows, got shape {rows.shape}")
    if ncols is not None and rows.shape[1] != ncols:
        raise ValueError(f"{name}: must have {ncols} columns, got shape {rows.shape}")
    return np.ascontiguousarray(rows, dtype=np.float64)


def frozen_copy(array: np.ndarray) -> np.ndarray:
    """A private read-only copy of an array a component keeps: later edits of the caller's
    array cannot reach it, and edits of the stored one fail loudly."""
    array = np.array(array, dtype=np.float64, order="C", copy=True)
    array.setflags(write=False)
    return array


def check_out(out: Any, n: int) -> np.ndarray | None:
    """Validates a caller's `out=` buffer (float64, C-contiguous, writeable, length n)."""
    if out is None:
        return None
    if not isinstance(out, np.ndarray):
        raise TypeError(f"out: must be a numpy.ndarray, got {type(out).__name__}")
    if out.dtype != np.float64:
        raise TypeError(f"out: must have dtype float64, got {out.dtype}")
    if out.shape != (n,):
        raise ValueError(f"out: must have shape ({n},), got {out.shape}")
    if not out.flags.c_contiguous:
        raise ValueError("out: must be C-contiguous")
    if not out.flags.writeable:
        raise ValueError("out: must be writeable")
    return out
