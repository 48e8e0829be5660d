"""
A clutter map learned online, next to the truth
================================================

A radar whose clutter nobody wrote down: sea clutter ten times denser beyond 1 km than
inside it (the paper's radar), and returns from an island's coast, 0.01 per metre of
coastline per scan. A :class:`~ctxmodels.ClutterMap` over the radar's bearing–range space
(5° × 50 m cells, prior λ 1e-3 per rad·m worth 10 scans, forgetting 0.99 per scan) learns
the intensity from the scans alone; here every detection is clutter (no targets), so each
scan's detections go straight into :meth:`~ctxmodels.ClutterMap.update`. With targets, a
:class:`~ctxmodels.stonesoup.ClutterMapLearner` leaves out the ones the tracks explain.
"""

# %%
# The truth and the scans
# -----------------------
import math

import matplotlib.pyplot as plt
import numpy as np

from ctxmodels import ClutterDensityModel, ClutterMap, Pose

rng = np.random.default_rng(3)
pose = Pose(x=0.0, y=0.0, heading=0.0)
near, far = 1e-3, 1e-2  # sea clutter per rad·m inside and beyond 1 km


def sea_clutter():
    """Uniform in bearing and range within each band (a density per rad·m)."""
    points = []
    for (r0, r1), density in (((0.0, 1000.0), near), ((1000.0, 1650.0), far)):
        n = rng.poisson(density * 2 * math.pi * (r1 - r0))
        bearing, rng_ = rng.uniform(-math.pi, math.pi, n), rng.uniform(r0, r1, n)
        points.append(np.column_stack([rng_ * np.cos(bearing), rng_ * np.sin(bearing)]))
    return np.concatenate(points)


# An island of radius 120 m, 600 m north-east: its coast returns with 1° and 5 m noise
centre, radius = np.array([420.0, 420.0]), 120.0


def coast_returns():
    n = rng.poisson(0.01 * 2 * math.pi * radius)
    angle = rng.uniform(0, 2 * math.pi, n)
    points = centre + radius * np.column_stack([np.cos(angle), np.sin(angle)])
    bearing = np.arctan2(points[:, 1], points[:, 0]) + rng.normal(0, math.radians(1), n)
    range_ = np.hypot(points[:, 0], points[:, 1]) + rng.normal(0, 5, n)
    return np.column_stack([range_ * np.cos(bearing), range_ * np.sin(bearing)])


learned = ClutterMap(space="bearing-range",
                     edges=(np.linspace(-math.pi, math.pi, 73), np.arange(0.0, 1651.0, 50.0)),
                     prior_intensity=1e-3, prior_scans=10.0, forgetting=0.99)
clutter = ClutterDensityModel(factors=[learned])  # what a sensor model would hold

for _ in range(400):  # 8 minutes at 0.8 Hz
    learned.update(pose, np.concatenate([sea_clutter(), coast_returns()]))

# %%
# Learned against the truth, cell by cell
# ---------------------------------------
# The true intensity of a cell: the sea clutter's, plus the coast returns falling in it —
# estimated here by counting a large sample of them (the coast is thin, a cell is not).
bearings, ranges = (np.asarray(e) for e in learned.edges)
volumes = np.outer(np.diff(bearings), np.diff(ranges))
centres_r = 0.5 * (ranges[1:] + ranges[:-1])
truth = np.where(centres_r >= 1000.0, far, near)[None, :].repeat(len(bearings) - 1, axis=0)
sample = np.concatenate([coast_returns() for _ in range(4000)])
cells = (np.searchsorted(bearings, np.arctan2(sample[:, 1], sample[:, 0]), side="right") - 1,
         np.searchsorted(ranges, np.hypot(*sample.T), side="right") - 1)
coast = np.zeros_like(truth)
np.add.at(coast, cells, 1.0 / 4000)
truth = truth + coast / volumes

estimate = learned.intensity_grid()
memory = (1 - 0.99 ** 400) / 0.01  # scans of evidence, against the prior's 10
expected = (truth * memory + 1e-3 * 10) / (memory + 10)  # the posterior mean's target
sea = coast == 0
for name, band in (("sea inside 1 km", sea & (centres_r < 1000)),
                   ("sea beyond 1 km", sea & (centres_r >= 1000))):
    print(f"{name}: learned/expected {estimate[band].mean() / expected[band].mean():.2f}")
on_coast = coast * 400 >= 5  # cells with ≥ 5 coast returns expected over the run
print(f"coast cells: {on_coast.sum()}, learned/expected "
      f"{estimate[on_coast].sum() / expected[on_coast].sum():.2f}, "
      f"λ there {estimate[on_coast].mean() / near:.0f}× the sea's")

# %%
# The maps
# --------
fig, axes = plt.subplots(1, 2, figsize=(11, 5), subplot_kw={"projection": "polar"},
                         constrained_layout=True)
theta, rho = np.meshgrid(bearings, ranges, indexing="ij")
for ax, values, title in ((axes[0], truth, "truth"), (axes[1], estimate, "learned (400 scans)")):
    mesh = ax.pcolormesh(theta, rho, np.log10(values), vmin=-3.5, vmax=-0.5, cmap="viridis")
    ax.set_title(f"{title}: log10 λ per rad·m")
    ax.set_theta_zero_location("E")
    ax.set_ylim(0, 1650)
    ax.set_rticks([500, 1000, 1500])
    ax.set_rlabel_position(200)
fig.colorbar(mesh, ax=axes, shrink=0.8)
plt.show()
