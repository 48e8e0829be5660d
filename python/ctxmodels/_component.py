"""Shared behaviour of ctxmodels' declarative components.

Every model component is a Stone Soup :class:`~stonesoup.base.Base` with documented
Properties, so it prints, pickles and round-trips through Stone Soup's YAML serialiser like
any Stone Soup component. On top of that, ctxmodels components are *immutable values*:

* they compare equal when their Properties are equal (NumPy arrays compared by value) and
  hash accordingly;
* assigning a Property after construction raises, because the Rust object a component
  compiles to is built once and cached — mutating the Python side would silently leave the
  compiled model behind. Build a new component instead. For the same reason sequence
  Properties are stored as tuples (nested sequences as nested tuples) and arrays as private
  read-only copies: editing the list a component was built from changes nothing.
"""
from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from stonesoup.base import Base, Property

from ._upstream import property_slot
from .errors import ArgumentError, ArgumentTypeError, ShapeError

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


def freeze(value: Any) -> Any:
    """`value` with every list/tuple as a tuple and every array as a read-only private copy,
    recursively (mapping values too, in a new dict); other values as they are."""
    if isinstance(value, np.ndarray):
        if not value.flags.writeable and value.flags.owndata:
            return value  # already a private frozen copy
        copy = np.array(value, copy=True, order="C")
        copy.setflags(write=False)
        return copy
    if isinstance(value, (list, tuple)) and not hasattr(value, "_fields"):  # not namedtuples
        return tuple(freeze(v) for v in value)
    if isinstance(value, dict):
        return {k: freeze(v) for k, v in value.items()}
    return value


class LearnedComponent(Base):
    """A component with a state learned online, kept in a core estimator (``_core``): its
    configuration Properties are fixed at construction, and its state Properties
    (``STATE``: name and fresh value, in the order ``_build`` takes them) change only
    through ``update`` and :meth:`reset`. Pickles rebuild the core from the state."""

    STATE: tuple[tuple[str, Any], ...] = ()

    def _build(self, *state):  # the core estimator from a state (None: fresh)
        raise NotImplementedError

    def _start(self) -> None:
        """Builds the core from the state Properties as given (at the end of ``__init__``)."""
        self.__dict__["_core"] = self._build(*(getattr(self, property_slot(name))
                                               for name, _ in self.STATE))

    def __setattr__(self, name, value):
        if name in type(self).properties and "_core" in self.__dict__:
            raise AttributeError(f"{type(self).__name__}.{name}: set at construction; the "
                                 "state changes through update() and reset()")
        super().__setattr__(name, value)

    def reset(self) -> None:
        """Back to the prior (the configuration is kept)."""
        self.__dict__["_core"] = self._build(*(fresh for _, fresh in self.STATE))

    def __getstate__(self):
        state = {k: v for k, v in self.__dict__.items()
                 if k != "_core" and not k.startswith(_CACHE_PREFIX)}
        state.update({property_slot(name): getattr(self, name) for name, _ in self.STATE})
        return state

    def __setstate__(self, state):
        # a pickle from before a Property was added: that Property's default
        for name, prop in type(self).properties.items():
            if prop.default is not Property.empty:
                state.setdefault(property_slot(name), prop.default)
        self.__dict__.update(state)
        self.__dict__["_core"] = self._build(*(state[property_slot(name)]
                                               for name, _ in self.STATE))


class ModelComponent(Base):
    """Base of ctxmodels components: immutable, value-equal, cached compilation."""

    def __init__(self, *args, **kwargs):
        object.__setattr__(self, "_initialised", False)
        super().__init__(*args, **kwargs)
        # Lists the caller keeps could otherwise be edited behind the compiled model.
        for name in type(self).properties:
            value = getattr(self, name)
            frozen = freeze(value)
            if frozen is not value:
                setattr(self, name, frozen)
        object.__setattr__(self, "_initialised", True)

    def _replace(self, name: str, value: Any) -> None:
        """Sets Property `name` to its normalised `value` during construction."""
        object.__setattr__(self, "_initialised", False)
        try:
            setattr(self, name, freeze(value))
        finally:
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
        # Unpickled arrays come back writeable: make them private and read-only again.
        for name in type(self).properties:
            value = getattr(self, name, None)
            frozen = freeze(value)
            if frozen is not value:
                self._replace(name, frozen)


#: Types NumPy or Python count as numbers that are not quantities here (flags, durations).
_NOT_NUMBERS = (bool, np.bool_, np.timedelta64, np.datetime64)


def as_float(value: Any, name: str, *, finite: bool = True) -> float:
    """`value` as a float, with a clear error naming the argument."""
    if isinstance(value, _NOT_NUMBERS) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ArgumentTypeError(name, f"expected a number, got {type(value).__name__}")
    try:
        value = float(value)
    except OverflowError:  # a Python int beyond a double's range
        raise ArgumentError(name, "is too large for a float") from None
    if finite and not math.isfinite(value):
        raise ArgumentError(name, f"must be finite, got {value}")
    return value


def as_float_tuple(values: Any, name: str) -> tuple[float, ...]:
    if isinstance(values, (str, bytes)) or not isinstance(values, (Sequence, np.ndarray)):
        raise ArgumentTypeError(name, f"expected a sequence of numbers, got {type(values).__name__}")
    return tuple(as_float(v, f"{name}[{i}]") for i, v in enumerate(values))


def as_sequence(values: Any, name: str, what: str = "items") -> tuple:
    """`values` (a list, tuple or 1-D array) as a tuple, or a TypeError naming it."""
    if isinstance(values, (str, bytes, Mapping)) or not isinstance(values, (Sequence, np.ndarray)):
        raise ArgumentTypeError(name, f"expected a sequence of {what}, got {type(values).__name__}")
    return tuple(values)


def as_int(value: Any, name: str, *, low: int = 0, high: int | None = None) -> int:
    """An integer of any type (Python or NumPy, not bool) in [low, high], naming `name`."""
    if isinstance(value, _NOT_NUMBERS) or not isinstance(value, (numbers.Integral, np.integer)):
        raise ArgumentTypeError(name, f"expected an integer, got {type(value).__name__} {value!r}")
    value = int(value)
    if value < low or (high is not None and value > high):
        bounds = f">= {low}" if high is None else f"in {low}..{high}"
        raise ArgumentError(name, f"must be an integer {bounds}, got {value}")
    return value


# Column indices beyond this are certainly wrong (and would overflow the core's int64).
_MAX_INDEX = 2**31


def as_position_mapping(mapping: Any, name: str = "position_mapping", *,
                        heights: bool = False) -> tuple[int, ...]:
    """Two different non-negative integer column indices (x, y), as a tuple of ints; with
    ``heights``, also three (x, y, z) for states with a height."""
    sizes = (2, 3) if heights else (2,)
    if type(mapping) is tuple and len(mapping) in sizes \
            and all(type(i) is int and 0 <= i <= _MAX_INDEX for i in mapping) \
            and len(set(mapping)) == len(mapping):
        return mapping  # already canonical (a SensorModel's own): nothing to convert
    wanted = "two or three integer indices" if heights else "two integer indices"
    if isinstance(mapping, (str, bytes, Mapping)) or not isinstance(mapping, (Sequence, np.ndarray)):
        raise ArgumentTypeError(name, f"expected {wanted}, got {mapping!r}")
    indices = tuple(mapping)
    if len(indices) not in sizes:
        what = "two indices (x, y) or three (x, y, z)" if heights else "two indices (x, y)"
        raise ArgumentError(name, f"must be {what}, got {len(indices)}: {indices!r}")
    checked = tuple(as_int(i, name, high=_MAX_INDEX) for i in indices)
    if len(set(checked)) != len(checked):
        axes = "x, y and z" if len(checked) == 3 else "x and y"
        raise ArgumentError(name, f"{axes} must be different indices, got {checked}")
    return checked


def velocity_indices(velocity_mapping: Any, position_mapping: tuple[int, ...],
                     name: str = "velocity_mapping") -> tuple[int, ...]:
    """The velocity's state indices, as many as ``position_mapping``'s and apart from them."""
    velocity = as_position_mapping(velocity_mapping, name, heights=True)
    if len(velocity) != len(position_mapping):
        raise ArgumentError(name, f"must have as many indices as position_mapping "
                                  f"{tuple(position_mapping)}, got {velocity}")
    if set(velocity) & set(position_mapping):
        raise ArgumentError(name, f"{velocity} shares an index with position_mapping "
                                  f"{tuple(position_mapping)}")
    return velocity


#: NumPy dtype kinds read as real numbers: booleans, integers, floats.
_REAL_KINDS = "biuf"


def as_array(array: Any, name: str, ndim: int, shape_text: str | None = None) -> np.ndarray:
    """A C-contiguous, aligned float64 array of `ndim` dimensions from `array`, or a clear
    error naming it. Unaligned input (a view into a byte buffer) is copied: the core reads
    it as f64."""
    if type(array) is np.ndarray and array.dtype == np.float64 and array.ndim == ndim \
            and array.flags.c_contiguous and array.flags.aligned:
        return array  # the common case, as np.require would return it: no checks to run
    try:
        values = np.asarray(array)
    except Exception as err:  # ragged lists and the like
        raise ArgumentTypeError(name, f"cannot be read as a numeric array ({err})") from None
    if values.dtype.kind not in _REAL_KINDS:  # (timedelta64 counts as an integer to NumPy)
        raise ArgumentTypeError(name, f"must be a real numeric array, got dtype {values.dtype}")
    if values.ndim != ndim:
        raise ShapeError(name, f"must be {shape_text or f'a {ndim}-D array'}, got shape {values.shape}")
    return np.require(values, dtype=np.float64, requirements=["C", "A"])


def as_rows(array: Any, name: str, *, ncols: int | None = None) -> np.ndarray:
    """A C-contiguous, aligned (N, D) float64 array from `array`, or a clear error naming it;
    with ``ncols`` an empty sequence is the (0, ncols) array (a scan without detections)."""
    if ncols is not None and isinstance(array, (list, tuple)) and len(array) == 0:
        return np.empty((0, ncols))
    rows = as_array(array, name, 2, "a 2-D array of rows")
    if ncols is not None and rows.shape[1] != ncols:
        raise ShapeError(name, f"must have {ncols} columns, got shape {rows.shape}")
    return rows


def as_columns(array: Any, name: str) -> np.ndarray:
    """A (D, N) float64 array the core reads in place, one column per state (Stone Soup's
    particles): C- or Fortran-ordered and aligned as given (particles are either, Fortran
    after resampling picks columns), anything else copied C-ordered; or a clear error."""
    if isinstance(array, np.ndarray) and array.dtype == np.float64 and array.ndim == 2 \
            and array.flags.aligned and (array.flags.c_contiguous or array.flags.f_contiguous):
        return np.asarray(array)  # a StateVectors becomes a plain view: no copy
    return as_array(array, name, 2, "a (D, N) array, one column per particle")


def frozen_copy(array: np.ndarray) -> np.ndarray:
    """A private read-only copy of an array a component keeps: later edits of the caller's
    array cannot reach it, and edits of the stored one fail loudly."""
    array = np.array(array, dtype=np.float64, order="C", copy=True)
    array.setflags(write=False)
    return array


def check_out(out: Any, n: int, **inputs: np.ndarray) -> np.ndarray | None:
    """Validates a caller's `out=` buffer (float64, C-contiguous, aligned, writeable, length
    n, sharing no memory with the call's `inputs`)."""
    if out is None:
        return None
    if not isinstance(out, np.ndarray):
        raise ArgumentTypeError("out", f"must be a numpy.ndarray, got {type(out).__name__}")
    if out.dtype != np.float64:
        raise ArgumentTypeError("out", f"must have dtype float64, got {out.dtype}")
    if out.shape != (n,):
        raise ShapeError("out", f"must have shape ({n},), got {out.shape}")
    if not out.flags.c_contiguous:
        raise ArgumentError("out", "must be C-contiguous")
    if not out.flags.aligned:
        raise ArgumentError("out", "must be aligned (allocate it with numpy.empty)")
    if not out.flags.writeable:
        raise ArgumentError("out", "must be writeable")
    for name, array in inputs.items():
        # Inputs are contiguous here, so overlapping bounds mean shared memory.
        if np.may_share_memory(out, array):
            raise ArgumentError("out", f"overlaps {name}, an input of the same call; pass a separate buffer")
    return out
