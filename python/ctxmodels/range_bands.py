"""Range bands: a value that is piecewise constant in range from the sensor."""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from stonesoup.base import Property

from . import _core
from ._component import ModelComponent, as_array, as_float_tuple


class RangeBands(ModelComponent):
    r"""A value piecewise constant over the range :math:`r` from the sensor.

    With edges :math:`e_0 < \dots < e_{k-1}` and values :math:`v_0, \dots, v_k`,

    .. math::
        f(r) = v_i \quad \text{for } r \text{ between } e_{i-1} \text{ and } e_i,

    (:math:`e_{-1} = 0`, :math:`e_k = \infty`). Which band owns an edge is explicit:
    ``upper_owns[i]`` puts :math:`r = e_i` in the band above. The paper's lidar,
    0.95 for :math:`r < 50`, 0.2 for :math:`50 \le r < 80`, 0 beyond, is
    ``RangeBands(edges=(50, 80), values=(0.95, 0.2, 0.0))``; its radar, 0.4 for
    :math:`50 < r < 1612` only, is
    ``RangeBands(edges=(50, 1612), values=(0, 0.4, 0), upper_owns=(False, True))``.
    """

    edges: Sequence[float] = Property(doc="Strictly increasing range edges in metres, ≥ 0.")
    values: Sequence[float] = Property(doc="One value per band: ``len(edges) + 1`` values.")
    upper_owns: bool | Sequence[bool] = Property(
        default=True,
        doc="Per edge (or one flag for all): whether a range exactly on the edge belongs to "
            "the band above it (True) or below it (False). NumPy booleans are accepted and "
            "stored as Python bools (a sequence or array as a tuple of them), so the "
            "component serialises like any other.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        as_float_tuple(self.edges, "edges")  # (named before the flags are counted against it)
        flags = self.upper_owns
        if isinstance(flags, np.ndarray) and flags.ndim == 0:
            flags = flags[()]  # one flag as a 0-d array
        owners = self._owners()  # checks the flags, naming upper_owns
        # np.bool_ is not a bool: Stone Soup's YAML cannot write it, and an array of flags
        # would compare unequal to the same tuple. Store plain bools.
        self._replace("upper_owns", bool(flags) if isinstance(flags, (bool, np.bool_))
                      else tuple(owners))
        self._compiled()  # validate now, not at the first scan

    def _owners(self) -> list[bool]:
        flags = self.upper_owns
        if isinstance(flags, np.ndarray) and flags.ndim == 0:
            flags = flags[()]
        if isinstance(flags, (bool, np.bool_)):
            return [bool(flags)] * len(self.edges)
        if isinstance(flags, (str, bytes)) or not isinstance(flags, (Sequence, np.ndarray)):
            raise TypeError(f"upper_owns: expected a bool or a sequence of bools, "
                            f"got {type(flags).__name__}")
        for i, flag in enumerate(flags):
            if not isinstance(flag, (bool, np.bool_)):  # 'False' would read as True
                raise TypeError(f"upper_owns: flag {i} must be a bool, got {flag!r}")
        return [bool(flag) for flag in flags]

    def _compiled(self) -> _core.RangeBands:
        return self._cached("core", lambda: _core.RangeBands(
            list(as_float_tuple(self.edges, "edges")),
            list(as_float_tuple(self.values, "values")),
            self._owners()))

    def __call__(self, ranges) -> np.ndarray:
        """The band value at each range (array-like, metres): the band above every edge it
        has passed, so +inf gets the last band and -inf the first; NaN raises
        :class:`ValueError`."""
        r = as_array(np.atleast_1d(_numeric(ranges)).ravel(), "ranges", 1)
        return self._compiled().at(r)


def _numeric(ranges):
    try:
        return np.asarray(ranges, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise TypeError(f"ranges: cannot be read as numbers ({err})") from None
