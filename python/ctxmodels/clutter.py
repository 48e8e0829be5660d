"""Clutter spatial density models: λ(z; S) as a product of factors per detection."""
from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from stonesoup.base import Property

from . import _core
from ._component import ModelComponent, as_array, as_float, as_rows, as_sequence, check_out
from .errors import ShapeError
from .clutter_map import ClutterMap
from .coast import CoastalClutter
from .elevation import ElevationSector
from .zone import Zone
from .pose import Pose, pose_tuple
from .range_bands import RangeBands


class MetadataThreshold(ModelComponent):
    r"""A clutter factor read from one key of a detection's ``metadata``:

    .. math::
        f(z) = \begin{cases} \text{below} & m(z) < \text{threshold} \\
                             \text{at\_or\_above} & \text{otherwise} \end{cases}

    The paper's lidar (eq. lambda-lidar) is ``MetadataThreshold(key='area', threshold=10,
    below=1e-1, at_or_above=1e-3)``: small segments are more likely clutter. A detection
    without the key gets ``missing``, or raises when ``missing`` is None.
    """

    key: str = Property(doc="The metadata key, e.g. ``'area'``.")
    threshold: float = Property(doc="Values strictly below it get ``below``.")
    below: float = Property(doc="Density for values below the threshold (> 0).")
    at_or_above: float = Property(doc="Density for values at or above the threshold (> 0).")
    missing: float | None = Property(default=None, doc="Density when the key is absent; "
                                                        "None raises instead.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if not isinstance(self.key, str):
            raise TypeError(f"key: expected a str, got {type(self.key).__name__}")

    def _compiled(self, column: int) -> _core.MetadataThreshold:
        missing = None if self.missing is None else as_float(self.missing, "missing")
        return _core.MetadataThreshold(column, as_float(self.threshold, "threshold"),
                                       as_float(self.below, "below"),
                                       as_float(self.at_or_above, "at_or_above"), missing)


ClutterFactor = (float | RangeBands | MetadataThreshold | ClutterMap | CoastalClutter | Zone
                 | ElevationSector)


class ClutterDensityModel(ModelComponent):
    r"""Clutter spatial density as the product of its factors,

    .. math::
        \lambda(z; S) = \prod_f f(z; S) > 0,

    in the units of the detection's *measurement space* — what Stone Soup's
    ``clutter_spatial_density`` means: per m² for a Cartesian (x, y) sensor, per rad·m for
    a bearing–range radar, per rad²·m for an elevation–bearing–range radar. Factors:
    constants, :class:`RangeBands` over the detection's range from the sensor,
    :class:`MetadataThreshold` rules, learned :class:`~ctxmodels.ClutterMap` s (read as they
    stand when λ is evaluated), coastal bands (:class:`~ctxmodels.CoastalClutter`), zones
    (:class:`~ctxmodels.Zone`: one value inside polygons, another outside) and, for
    detections with a height, :class:`~ctxmodels.ElevationSector` s (one value between two
    elevations above the sensor, another outside: sea clutter in the lowest degree). Every
    value must be finite and strictly positive (trackers divide by λ).

    Detections with a height (positions (M, 3), from a sensor model whose
    ``position_mapping`` has three indices) have range bands read on the slant range from
    the sensor's height, elevation sectors the world elevation above it (the sea is level
    whatever a pitched or rolled antenna's tilt); maps, coastal bands and zones read the
    plane below them. A 3-D
    radar's false alarms spread uniformly over its field of view — :math:`\bar n` per scan
    over elevations :math:`[\varepsilon_0, \varepsilon_1]`, bearings of width
    :math:`\Delta\theta` and ranges :math:`[r_0, r_1]` — have
    :math:`\lambda = \bar n / ((\varepsilon_1 - \varepsilon_0)\,\Delta\theta\,(r_1 - r_0))`
    per rad²·m.

    The paper's radar (eq. lambda-radar): ``ClutterDensityModel(factors=[
    RangeBands(edges=(1000,), values=(1e-3, 1e-2))])``.
    """

    factors: Sequence[ClutterFactor] = Property(doc="The factors whose product is λ.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._replace("factors", as_sequence(self.factors, "factors", "factors"))
        self._compiled()

    # (read every scan; the factors are fixed, so these are computed once per model)
    @property
    def metadata_keys(self) -> tuple[str, ...]:
        """The metadata keys the model reads, in column order."""
        def build():
            keys: list[str] = []
            for f in self.factors:
                if isinstance(f, MetadataThreshold) and f.key not in keys:
                    keys.append(f.key)
            return tuple(keys)
        return self._cached("metadata_keys", build)

    @property
    def uses_position(self) -> bool:
        return self._cached("uses_position", lambda: any(
            isinstance(f, (RangeBands, ClutterMap, CoastalClutter, Zone, ElevationSector))
            for f in self.factors))

    @property
    def uses_height(self) -> bool:
        """Whether λ reads the detections' heights (an :class:`ElevationSector`)."""
        return self._cached("uses_height", lambda: any(
            isinstance(f, ElevationSector) for f in self.factors))

    def _required_keys(self) -> frozenset[str]:
        """The metadata keys whose rule has no ``missing`` density."""
        return self._cached("required_keys", lambda: frozenset(
            f.key for f in self.factors if isinstance(f, MetadataThreshold) and f.missing is None))

    def _compiled(self) -> _core.ClutterModel:
        def build():
            keys = self.metadata_keys
            parts = []
            for i, f in enumerate(self.factors):
                if isinstance(f, (RangeBands, CoastalClutter, Zone, ElevationSector)):
                    parts.append(f._compiled())
                elif isinstance(f, MetadataThreshold):
                    parts.append(f._compiled(keys.index(f.key)))
                elif isinstance(f, ClutterMap):
                    parts.append(f._core)  # shared: the model reads the map's updates
                elif isinstance(f, (int, float, np.integer, np.floating)):
                    parts.append(as_float(f, f"factors[{i}]"))
                else:
                    raise TypeError(f"factors[{i}]: expected a float, RangeBands, "
                                    "MetadataThreshold, ClutterMap, CoastalClutter, Zone or "
                                    f"ElevationSector, got {type(f).__name__}")
            return _core.ClutterModel(parts)
        return self._cached("core", build)

    def metadata_array(self, metadata, n: int) -> np.ndarray:
        """(n, len(metadata_keys)) float64 from an array, a sequence of rows (values in
        ``metadata_keys`` order) or a sequence of metadata mappings; NaN where a key is absent."""
        keys = self.metadata_keys
        if metadata is None:
            return np.full((n, len(keys)), np.nan)
        if isinstance(metadata, np.ndarray):
            return as_rows(metadata, "metadata", ncols=len(keys))
        if isinstance(metadata, (str, bytes)) or not isinstance(metadata, Sequence):
            raise TypeError(f"metadata: expected an (M, K) array or a sequence of mappings, "
                            f"got {type(metadata).__name__}")
        if len(metadata) != n:
            raise ValueError(f"metadata: needs one entry per position ({n}), got {len(metadata)}")
        mappings = [isinstance(entry, Mapping) for entry in metadata]
        if not any(mappings) and n > 0:  # rows, like an (M, K) array
            return as_rows(metadata, "metadata", ncols=len(keys))
        if not all(mappings):
            i = mappings.index(False)
            raise TypeError(f"metadata: entry {i} is a {type(metadata[i]).__name__}; give every "
                            f"detection a mapping, or every detection a row")
        required = self._required_keys()
        rows = []  # (Python floats, one array at the end: a scan's rows are few and short)
        for i, entry in enumerate(metadata):
            row = []
            for key in keys:
                if key not in entry:
                    if key in required:
                        raise ValueError(f"metadata: detection {i} has no {key!r}, and the "
                                         f"clutter rule on {key!r} has no `missing` density; "
                                         f"give every detection {key!r}, or set the rule's "
                                         f"`missing`")
                    row.append(np.nan)
                    continue
                value = entry[key]
                if type(value) is not float and (isinstance(value, (bool, np.bool_)) or not
                                                 isinstance(value, (int, float, np.integer,
                                                                    np.floating))):
                    raise TypeError(f"metadata: detection {i} {key!r} must be a number, "
                                    f"got {type(value).__name__}")
                try:
                    row.append(float(value))
                except OverflowError:  # an int beyond float range
                    raise ValueError(f"metadata: detection {i} {key!r} is beyond the float "
                                     f"range") from None
            rows.append(row)
        return np.array(rows, dtype=np.float64).reshape(n, len(keys))

    def evaluate(self, pose: Pose, positions, metadata=None, *, ranges=None,
                 out=None) -> np.ndarray:
        """λ at world ``positions`` (M, 2), or (M, 3) with heights, with ``metadata`` (array,
        rows or mappings).

        ``ranges`` (M,), optional: the range from the sensor that range bands read for each
        detection instead of the range of its position, NaN where there is none — a
        bearing–range sensor's *measured* range, so a detection measured exactly on a band
        edge falls in the band that owns the edge."""
        given, positions = positions, self._rows(positions)
        n = positions.shape[0]
        metadata = self.metadata_array(metadata, n)
        # (the caller's array: a copy made of it would hide an overlap with out)
        inputs = dict(positions=given if isinstance(given, np.ndarray) else positions,
                      metadata=metadata)
        if ranges is not None:
            ranges = as_array(ranges, "ranges", 1, f"({n},) ranges")
            if ranges.shape != (n,):
                raise ValueError(f"ranges: must have {n} entries, got shape {ranges.shape}")
            inputs["ranges"] = ranges
        return self._compiled().evaluate(pose_tuple(pose), positions, metadata,
                                         check_out(out, n, **inputs), ranges)

    def _rows(self, positions) -> np.ndarray:
        """(M, 2) positions, or (M, 3) with heights (which the core reads in place)."""
        if isinstance(positions, (list, tuple)) and len(positions) == 0:
            return np.empty((0, 3 if self.uses_height else 2))
        rows = as_rows(positions, "positions")
        if rows.shape[1] not in (2, 3):
            raise ShapeError("positions", f"must have 2 columns (x, y) or 3 (x, y, z), got "
                                          f"shape {rows.shape}")
        if rows.shape[1] == 2 and self.uses_height:
            raise ShapeError("positions", "the clutter model's ElevationSector reads each "
                                          "detection's height: give (M, 3) positions (x, y, z)")
        return rows
