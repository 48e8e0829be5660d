r"""A clutter-intensity map learned online: a clutter factor whose values come from the
detections that no track explains, scan after scan.

Each cell :math:`c` of a grid in the sensor's measurement space (volume :math:`V_c`: rad·m
for a bearing–range cell, m² for an x/y cell) holds a Gamma posterior over its clutter
intensity (expected clutter points per unit measurement volume per scan). A
Gamma(:math:`\lambda_0 s_0 V_c,\ s_0 V_c`) prior — intensity :math:`\lambda_0`, worth
:math:`s_0` scans — updated with Poisson counts :math:`n_{c,j}` at scans :math:`j`, each
discounted by :math:`\gamma` per scan since (exponential forgetting), has the posterior mean

.. math::
    \hat\lambda_c = \frac{\lambda_0 s_0 + N_c / V_c}{s_0 + S}, \qquad
    N_c = \sum_j \gamma^{k-j} n_{c,j}, \qquad S = \sum_j \gamma^{k-j},

which is the factor's value for a detection in cell :math:`c` (:math:`\lambda_0` outside
the grid).

Every update counts one scan of exposure for every cell: the map assumes the sensor
reports clutter over its whole grid at each scan (a blind sector's cells then drift
towards low λ, where no detection arrives to be weighed by it) — except inside *gates*,
discs around the tracks' positions: their detections are the tracks', not clutter, and
their area is taken out of their cell's exposure that scan (:math:`S_c = S - D_c`, with
:math:`D_c` the discounted gated fractions). So a track, true or false, neither adds
clutter evidence nor passes for a place where clutter was looked for and not found: no
feedback from the tracker's own mistakes into the map. An update costs
O(detections + gates) in the Rust core (the forgetting is a running scale, not a pass over
cells). :class:`~ctxmodels.stonesoup.ClutterMapLearner` feeds a map from a tracker's output.

*Pooling* shares evidence between cells expected to have similar clutter. With
``pooling='range'`` (a bearing–range map) each range ring — the cells of one range cell, at
every bearing — has a posterior of its own with the :math:`\lambda_0` prior,

.. math::
    \hat\lambda_g = \frac{\lambda_0 s_0 V_g + \sum_{c \in g} N_c}
                          {s_0 V_g + \sum_{c \in g} V_c S_c}, \qquad V_g = \sum_{c \in g} V_c,

and each of its cells shrinks towards :math:`\hat\lambda_g` instead of :math:`\lambda_0`,
with weight :math:`s_p` (:attr:`~ClutterMap.pooling_scans`) scans:
:math:`\hat\lambda_c = (\hat\lambda_g s_p + N_c / V_c) / (s_p + S_c)` (an empirical-Bayes
plug-in). Sea clutter depends mostly on range (the grazing angle), so a ring learns the
level of tens of cells in a few scans, and a cell with much evidence of its own (a coast)
still departs from it; but a cell that cannot see clutter (a blind sector) pulls its ring
down, so leave such cells out of the grid.

With ``pooling_scans=None`` the weight is estimated per pool, from how much its cells
differ (a Gamma–Poisson hierarchy, :math:`\lambda_c \sim` Gamma with mean
:math:`\hat\lambda_g` and variance :math:`\tau_g^2`): each cell's prior weight is
:math:`\hat\lambda_g / (\tau_g^2 V_c)` scans, with the method-of-moments estimate

.. math::
    \tau_g^2 = \max\Bigl(0, \frac{\sum_{c \in g} (N_c - \hat\lambda_g V_c S_c)^2
        - \hat\lambda_g V_c S^{(2)}_c}{\sum_{c \in g} (V_c S_c)^2}\Bigr),

the spread of the cells' counts beyond what Poisson counts would show
(:math:`S^{(2)}_c = \sum_j \gamma^{2(k-j)}` scaled by the cell's exposed share, the variance
of a discounted count per unit mean). Cells that agree (open sea) then take their pool's
level — a far cell that sees one clutter point in 20 scans is no longer left to its own
noise.

A pool can hold cells that are not of it: a buoy's or a moored vessel's persistent returns,
a stretch of coast, a patch that land hides. Moments are not robust to them (one buoy's
cell in a ring of 59 made :math:`\tau_g^2` ten times :math:`\hat\lambda_g^2`, freeing every
cell of the ring, and lifted the ring's level by 40 %), so a cell whose counts the level
of its pool's cells cannot explain *leaves the pool*: when the Chernoff bound on the
Poisson tail, :math:`\exp(-(n \ln(n/\mu) - n + \mu))`, in effective counts
(:math:`n = N_c S / S^{(2)}`, :math:`\mu = \hat\lambda_g V_c S_c S / S^{(2)}`), falls below
1 % divided by the pool's number of cells (so chance sets a cell of a homogeneous pool
apart less than 1 % of the time). A cell apart is estimated alone, with the
:math:`\lambda_0` prior; the pool's level and spread are those of the cells that stay. A
coast's cells then follow their own counts while the quiet cells of their ring keep its
level.
Counts weighted by clutter
probabilities vary less than Poisson counts of the same mean (:math:`\sum w^2 \le \sum w`),
which underestimates :math:`\tau_g^2`: the cells are then shrunk more, towards their pool.
Differences a tracker puts there itself — a target's partly counted returns, clutter
hidden under a false track — count as spread, as a coast does. The residuals are taken
about :math:`\hat\lambda_g`, prior and the cell's own counts included, uncorrected: in a
pool's first scans the prior's pull adds to :math:`\tau_g^2`, and in a pool of few cells
the own-count share takes from it; the test for leaving uses the level of every cell of the
pool, which the cells apart lift, so it errs towards keeping a cell. ``pooling='grid'``
pools the whole grid (any space). Without pooling (the default) every cell shrinks towards
:math:`\lambda_0` alone. Pooled, an update also recomputes the pools' sums from the cells (vectorised passes,
O(cells)), so that a restored map is exactly the saved one.

The map is *state*, not a value like the other components: it changes with each
:meth:`ClutterMap.update`, and every :class:`~ctxmodels.ClutterDensityModel` built with it
reads it as it stands when evaluated. Update it after a scan's tracking, with that scan's
detections: within a scan the map is then fixed, and λ does not depend on the order of the
detections. Its state (:attr:`counts`, :attr:`deficit`, :attr:`exposure`, :attr:`scale`)
pickles and round-trips through Stone Soup's YAML exactly.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from stonesoup.base import Property

from . import _core
from ._component import LearnedComponent, as_array, as_float, as_rows
from .pose import Pose, pose_tuple

SPACES = ("bearing-range", "body-xy", "world-xy")
POOLINGS = ("none", "range", "grid")


class ClutterMap(LearnedComponent):
    """An online clutter-intensity map (see the module docs); a factor of
    :class:`~ctxmodels.ClutterDensityModel`."""

    space: str = Property(
        doc="'bearing-range' (a bearing–range sensor's measurement space: bearing in the "
            "sensor's frame, radians, then range, m; λ per rad·m), 'body-xy' (x along the "
            "sensor's heading, y to its left, m; λ per m²) or 'world-xy' (m; λ per m²).")
    edges: Sequence[Sequence[float]] = Property(
        doc="The grid's edges on each axis, strictly increasing: (bearings within [-π, π], "
            "ranges >= 0) or (x, y). Cells are half-open, [e_i, e_(i+1)).")
    prior_intensity: float = Property(doc=r"Prior intensity :math:`\lambda_0` (> 0), also "
                                          "the value outside the grid.")
    prior_scans: float = Property(default=10.0, doc=r"Prior weight :math:`s_0` in scans (> 0), "
                                                    "of a cell or, pooled, of a pool.")
    forgetting: float = Property(default=0.99, doc=r"Forgetting factor :math:`\gamma` per "
                                                   "scan, in (0, 1]; memory ≈ 1/(1 − γ) scans.")
    pooling: str = Property(
        default="none", doc="'none' (every cell on its own), 'range' (a bearing-range map's "
                            "range rings: the cells of one range cell, every bearing) or 'grid' "
                            "(the whole grid): see the module docs.")
    pooling_scans: float | None = Property(
        default=10.0, doc=r"Pooled: the weight :math:`s_p` of a cell's pool in its prior, "
                          "scans (> 0); None estimates it per pool from how much the "
                          "pool's cells differ (see the module docs). Ignored without "
                          "pooling.")
    counts: np.ndarray = Property(
        default=None, doc="State: the discounted clutter counts per cell, (n0, n1), times "
                          ":attr:`scale`. None: a fresh map. Read back, it is the current state.")
    deficit: np.ndarray = Property(
        default=None, doc="State: the discounted gated fractions per cell, (n0, n1), times "
                          ":attr:`scale`. None: none.")
    exposure: float = Property(default=0.0, doc="State: the discounted number of scans, "
                                                "times :attr:`scale`.")
    scale: float = Property(default=1.0, doc="State: the running scale of the forgetting.")

    STATE = (("counts", None), ("deficit", None), ("exposure", 0.0), ("scale", 1.0))

    @counts.getter
    def counts(self) -> np.ndarray:
        return self._core.state()[0].reshape(self._core.shape)

    @deficit.getter
    def deficit(self) -> np.ndarray:
        return self._core.state()[1].reshape(self._core.shape)

    @exposure.getter
    def exposure(self) -> float:
        return self._core.state()[2]

    @scale.getter
    def scale(self) -> float:
        return self._core.state()[3]

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        edges = self.edges
        if isinstance(edges, (str, bytes)) or not isinstance(edges, Sequence) or len(edges) != 2:
            raise ValueError("edges: expected two sequences of edges, one per axis")
        self.edges = tuple(tuple(as_array(axis, "edges", 1, "edges along one axis").tolist())
                           for axis in edges)
        self._start()

    def _build(self, counts, deficit, exposure, scale) -> _core.ClutterMap:
        if self.space not in SPACES:
            raise ValueError(f"space: must be one of {SPACES}, got {self.space!r}")
        if self.pooling not in POOLINGS:
            raise ValueError(f"pooling: must be one of {POOLINGS}, got {self.pooling!r}")
        axes = self.edges
        shape = (max(len(axes[0]) - 1, 0), max(len(axes[1]) - 1, 0))
        counts, deficit = (_cells(values, name, shape) for values, name in
                           ((counts, "counts"), (deficit, "deficit")))
        # (finite=False: the core names non-finite values with the rule they break)
        number = lambda value, name: as_float(value, name, finite=False)  # noqa: E731
        return _core.ClutterMap(self.space, list(axes[0]), list(axes[1]),
                                number(self.prior_intensity, "prior_intensity"),
                                number(self.prior_scans, "prior_scans"),
                                number(self.forgetting, "forgetting"), counts, deficit,
                                number(exposure, "exposure"), number(scale, "scale"),
                                self.pooling,
                                None if self.pooling_scans is None
                                else number(self.pooling_scans, "pooling_scans"))

    def update(self, pose: Pose | Sequence[float], positions, ranges=None, gates=None,
               weights=None) -> None:
        r"""One scan: the world ``positions`` (M, 2) of its detections, for a bearing–range
        map their measured ``ranges`` (M,) (NaN or None: from the position), and ``gates``
        (G, 3: world x, y, radius in m) around the tracks' positions, whose detections are
        not clutter and whose area is not exposed. An empty scan counts too: it is evidence
        of little clutter. ``weights`` (M,) in [0, 1], optional: each detection counts as
        that fraction of a clutter point — its probability of being clutter, where the
        tracker gives one (a PHD update's :math:`\lambda / (\lambda + \sum P_D w g)`, a
        JPDA's no-target association) — so the map learns the expected clutter count."""
        positions = as_rows(positions, "positions", ncols=2)
        if ranges is not None:
            ranges = as_array(ranges, "ranges", 1, "(M,) ranges")
        if gates is not None:
            gates = as_rows(gates, "gates", ncols=3)
        if weights is not None:
            weights = as_array(weights, "weights", 1, "(M,) weights")
        self._core.update(pose_tuple(pose), positions, ranges, gates, weights)

    def intensity(self, pose: Pose | Sequence[float], positions, ranges=None) -> np.ndarray:
        """The map's λ at world ``positions`` (M, 2) seen from ``pose``."""
        positions = as_rows(positions, "positions", ncols=2)
        if ranges is not None:
            ranges = as_array(ranges, "ranges", 1, "(M,) ranges")
        return self._core.intensity(pose_tuple(pose), positions, ranges)

    def intensity_grid(self) -> np.ndarray:
        """The posterior mean λ of every cell, (n0, n1)."""
        return self._core.intensities().reshape(self._core.shape)



def _cells(values, argument: str, shape) -> list | None:
    if values is None:
        return None
    values = as_array(values, argument, 2, f"a {shape} array")
    if values.shape != shape:
        raise ValueError(f"{argument}: must have shape {shape}, got {values.shape}")
    return values.ravel().tolist()


__all__ = ["ClutterMap"]
