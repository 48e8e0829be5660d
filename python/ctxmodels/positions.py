"""Where a scan's detections are: world positions through each detection's own measurement
model, and the measured ranges that range bands read.

The trackers need both every scan (λ, births, learning). A scan's detections are grouped by
measurement-model *value* (:func:`~ctxmodels.model_key.scan_model_groups`); what a group's
model contributes to the inverse — the pseudo-inverse and x/y rows of a linear model, the
inverse rotation and offset of a bearing–range one — is kept per value, so scans that bring
an equal model (a new object per scan, or the same one) do not rebuild it. The arithmetic on
the scan's vectors is the same every time.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.measurement.nonlinear import (CartesianToBearingRange,
                                                    CartesianToElevationBearingRange)

from .model_key import scan_model_groups
from .pose import Pose


def _position_indices(model, position_mapping, i) -> list[int]:
    """The x/y indices of ``model``'s state space: ``position_mapping``, which the model must
    map (measure) both of; anything else would read some other state entry as a position."""
    mapping = [int(m) for m in getattr(model, "mapping", ())]
    wanted = [int(m) for m in position_mapping]
    if all(m in mapping for m in wanted):
        return wanted
    raise ValueError(f"detections: detection {i}'s measurement model {type(model).__name__} "
                     f"maps state indices {tuple(mapping)}, which do not include the sensor's "
                     f"position_mapping {tuple(wanted)}; give the SensorModel the x/y indices "
                     "of the state its detections' models measure")


def detection_positions(detections: Sequence, position_mapping=(0, 2)) -> np.ndarray:
    """World (x, y) of each detection, (M, 2) — (x, y, z), (M, 3), for a mapping with a
    height index — from each detection's *own* measurement
    model: through its ``inverse_function`` (bearing–range and other non-linear models) or
    the pseudo-inverse of a linear model's matrix, read at the ``position_mapping`` indices
    of that model's state space. A model that does not map both of those indices (a 6-D
    model with ``mapping=(0, 3)`` against ``(0, 2)``, a 1-D model), or a detection whose
    vector does not have the model's ``ndim_meas`` rows, raises ValueError: the state space
    of the detections must be the one the sensor's ``position_mapping`` describes. Linear
    detections sharing a model are converted in one matrix product."""
    positions = np.empty((len(detections), len(position_mapping)))
    for key, model, indices, vectors in _model_groups(detections, "position (needed for λ)"):
        inverse = _group_inverse(key, model, position_mapping, indices[0])
        if inverse is not None and len(indices) == len(detections):
            return np.ascontiguousarray(inverse(vectors()), dtype=np.float64)  # (one group)
        if inverse is not None:
            positions[indices] = inverse(vectors())
        elif hasattr(model, "inverse_function"):
            for i in indices:
                state = np.asarray(model.inverse_function(detections[i]),
                                   dtype=np.float64).ravel()
                positions[i] = state[_position_indices(model, position_mapping, i)]
        else:
            raise ValueError(f"detections: detection {indices[0]}'s measurement model "
                             f"{type(model).__name__} has no inverse_function")
    return positions


class _LinearInverse:
    """A linear model's positions: its matrix's pseudo-inverse, read at the x/y rows."""

    __slots__ = ("pinv", "xy")

    def __init__(self, model, xy: list):
        self.pinv, self.xy = _pseudo_inverse(model.matrix()), xy

    def __call__(self, vectors: np.ndarray) -> np.ndarray:
        return (self.pinv @ vectors.T)[self.xy].T


class _BearingRangeInverse:
    """A 2-D bearing–range model's positions: ``inverse_function`` for all rows at once
    (see :func:`_bearing_range_inverse`), read at the x/y columns."""

    __slots__ = ("rotation", "offset", "mapping", "ndim_state", "xy")

    def __init__(self, model, xy: list):
        self.rotation = _inverse_rotation(model.rotation_matrix)
        self.offset = np.asarray(model.translation_offset, dtype=np.float64)[:2, 0]
        self.mapping, self.ndim_state = list(model.mapping[:2]), model.ndim_state
        self.xy = xy

    def __call__(self, polar: np.ndarray) -> np.ndarray:
        return _bearing_range_inverse(self, polar)[:, self.xy]


#: Group inverses by (model value, position mapping); a model keyed by identity has none.
_GROUP_INVERSES: dict = {}


def _group_inverse(key, model, mapping, first: int):
    """The batched inverse of a group's model for ``mapping`` (None: the model's own
    ``inverse_function``, detection by detection), kept per model value (``key``, from
    :func:`~ctxmodels.model_key.measurement_model_key`: equal keys are bit-identical
    models, so the inverse is the same). ``first``: the group's first detection, named in
    errors."""
    cache_key = None
    if type(key) is tuple:
        try:
            cache_key = (key, tuple(int(m) for m in mapping))
        except (TypeError, ValueError):  # (raised below, as without the cache)
            pass
    found = _GROUP_INVERSES.get(cache_key) if cache_key is not None else None
    if found is not None:
        return found
    if isinstance(model, LinearGaussian):
        inverse = _LinearInverse(model, _position_indices(model, mapping, first))
    elif _batched_bearing_range(model):
        inverse = _BearingRangeInverse(model, _position_indices(model, mapping, first))
    else:
        return None
    if cache_key is not None:
        if len(_GROUP_INVERSES) >= 64:
            _GROUP_INVERSES.clear()
        _GROUP_INVERSES[cache_key] = inverse
    return inverse


def _model_groups(detections: Sequence, needed_for: str):
    """The detections grouped by measurement model *value*
    (:func:`~ctxmodels.model_key.measurement_model_key`: equal models in different objects
    form one group, its first model the representative), in first-appearance order: ``(model,
    indices, vectors)`` with ``vectors()`` their measurement vectors as float rows (checked
    against the model's ``ndim_meas``; taken from the collection's stacked ``vectors`` when
    it carries them, as :class:`~ctxmodels.stonesoup.ordering.OrderedDetections` does),
    after the group's key."""
    n = len(detections)
    stacked = getattr(detections, "vectors", None)
    for key, (model, indices) in scan_model_groups(detections).items():
        if model is None:
            raise ValueError(f"detections: detection {indices[0]} has no measurement model, "
                             f"so its {needed_for} is unknown")
        ndim_meas = getattr(model, "ndim_meas", None)

        def vectors(indices=indices, ndim_meas=ndim_meas):
            if stacked is not None and stacked.shape == (n, ndim_meas):
                return stacked if len(indices) == n else stacked[indices]
            return _measurement_vectors(detections, indices, ndim_meas)
        yield key, model, indices, vectors


def _measurement_vectors(detections: Sequence, indices: list, ndim_meas) -> np.ndarray:
    """The measurement vectors of ``detections[indices]`` as float rows (K, m); ValueError
    naming the first detection whose vector is not ``ndim_meas`` long (if given)."""
    vectors = [detections[i].state_vector for i in indices]
    try:
        stacked = np.array(vectors, dtype=np.float64)
    except (TypeError, ValueError):
        stacked = None
    if stacked is not None and stacked.ndim == 3 and stacked.shape[2] == 1:
        stacked = stacked[..., 0]
    if stacked is not None and stacked.ndim == 2 \
            and (ndim_meas is None or stacked.shape[1] == ndim_meas):
        return stacked
    for i, vector in zip(indices, vectors):
        shape = np.shape(vector)
        if ndim_meas is not None and shape not in ((ndim_meas, 1), (ndim_meas,)):
            raise ValueError(f"detections: detection {i} has a state vector of shape {shape}, "
                             f"but its measurement model {type(detections[i].measurement_model).__name__} "
                             f"measures {ndim_meas} values")
    raise ValueError(f"detections: detections {indices} have state vectors of different "
                     "shapes or non-numeric values")


_PSEUDO_INVERSES: dict = {}


def _pseudo_inverse(matrix) -> np.ndarray:
    """``pinv`` of a linear model's matrix."""
    return _inverted_by_value(_PSEUDO_INVERSES, matrix, np.linalg.pinv)


def _inverted_by_value(cache: dict, matrix, invert, limit: int = 64) -> np.ndarray:
    """``invert(matrix)``, cached in ``cache`` by the matrix's value: scans often bring a new
    model object with the same matrix (a moving sensor's few recurring headings)."""
    matrix = np.ascontiguousarray(matrix, dtype=np.float64)
    key = (matrix.shape, matrix.tobytes())
    inverse = cache.get(key)
    if inverse is None:
        if len(cache) >= limit:
            cache.clear()
        inverse = cache[key] = invert(matrix)
    return inverse


def _batched_bearing_range(model) -> bool:
    """A 2-D bearing–range model whose inverse :func:`_bearing_range_inverse` computes."""
    return (isinstance(model, CartesianToBearingRange)
            and type(model).inverse_function is CartesianToBearingRange.inverse_function
            and len(model.mapping) == 2
            and model.rotation_offset[0] == 0 and model.rotation_offset[1] == 0)


def _bearing_range_inverse(inverse: _BearingRangeInverse, polar: np.ndarray) -> np.ndarray:
    """``model.inverse_function`` of K (bearing, range) rows at once, (K, ndim_state): the
    polar-to-Cartesian point rotated back to the world and shifted by the offset."""
    bearing, rng = polar[:, 0], polar[:, 1]
    xyz = np.array([rng * np.cos(bearing), rng * np.sin(bearing), np.zeros(len(polar))])
    xy = (inverse.rotation @ xyz)[0:2]
    states = np.zeros((len(polar), inverse.ndim_state))
    states[:, inverse.mapping] = (xy + inverse.offset[:, np.newaxis]).T
    return states


_INVERSE_ROTATIONS: dict = {}


def _inverse_rotation(rotation) -> np.ndarray:
    """``inv`` of a model's rotation matrix."""
    return _inverted_by_value(_INVERSE_ROTATIONS, rotation, np.linalg.inv, limit=256)


def measured_ranges(detections: Sequence) -> np.ndarray:
    """Each detection's measured range from its sensor, (M,): the range element of a 2-D
    bearing–range measurement (Stone Soup's :class:`CartesianToBearingRange`) or of a 3-D
    elevation–bearing–range one (:class:`CartesianToElevationBearingRange`, a slant
    range), measured from the model's ``translation_offset``; NaN for any other detection."""
    n = len(detections)
    groups = scan_model_groups(detections)
    stacked = getattr(detections, "vectors", None)
    if stacked is not None and len(groups) == 1:
        row = _range_row(next(iter(groups.values()))[0])
        if row is not None and stacked.shape == (n, row + 1):
            return stacked[:, row].copy()  # one polar model (value) per scan: the usual case
    ranges = np.full(n, np.nan)
    for model, indices in groups.values():
        row = _range_row(model)
        if row is not None:
            for i in indices:
                ranges[i] = float(np.asarray(detections[i].state_vector,
                                             dtype=np.float64).ravel()[row])
    return ranges


def _range_row(model) -> int | None:
    """The row of a polar measurement that holds the range; None for other models."""
    if isinstance(model, CartesianToBearingRange) and len(model.mapping) == 2:
        return 1
    if isinstance(model, CartesianToElevationBearingRange) and len(model.mapping) == 3:
        return 2
    return None


#: How far (relative) a measured range may lie from the range of the detection's position
#: from the context's pose and still be read as the same range: far above the round trip's
#: ulps, far below any physical lever arm.
_RANGE_AGREEMENT = 1e-9


def ranges_for_bands(detections: Sequence, positions: np.ndarray, pose: Pose) -> np.ndarray:
    """The ranges λ's range bands read, (M,): a detection's measured range
    (:func:`measured_ranges`) where it agrees with the range of its position from ``pose``
    to within a relative :data:`_RANGE_AGREEMENT` and is ≥ 0, NaN (use the position)
    elsewhere. So a detection measured exactly on a band edge falls in the band that owns
    the edge, instead of wherever the polar → Cartesian → range round trip (an ulp either
    way) puts it; a detection measured from elsewhere (another lever arm) keeps the range
    from the context's pose."""
    measured = measured_ranges(detections)
    from_pose = np.hypot(positions[:, 0] - pose.x, positions[:, 1] - pose.y)
    if positions.shape[1] == 3:  # detections with a height: the slant range
        from_pose = np.hypot(from_pose, positions[:, 2] - pose.z)
    with np.errstate(invalid="ignore"):
        agree = (measured >= 0) & (np.abs(measured - from_pose)
                                   <= _RANGE_AGREEMENT * np.maximum(1.0, from_pose))
    return np.where(agree, measured, np.nan)


__all__ = ["detection_positions", "measured_ranges", "ranges_for_bands"]
