"""
The paper's radar and lidar: detection probability and clutter maps
===================================================================

The reference paper's two sensors, written with ctxmodels' components: a long-range radar
(P_D 0.4 between 50 m and 1612 m, blind in a 65° sector astern; clutter 1e-3 below
1000 m, 1e-2 beyond) and a short-range lidar (P_D 0.95 below 50 m, 0.2 to 80 m, nothing
beyond; clutter 1e-1 for small segments, area < 10 m², else 1e-3). Each scan's
:class:`~ctxmodels.DetectorContext` evaluates them at the ego's pose for whole arrays of
states or detections at once.
"""

# %%
# The models
# ----------
import math

import matplotlib.pyplot as plt
import numpy as np

from ctxmodels import (AngularSector, ClutterDensityModel, DetectionProbabilityModel,
                       MetadataThreshold, Pose, RangeBands, SensorModel)

radar = SensorModel(
    name="radar",
    detection=DetectionProbabilityModel(factors=[
        # 50 m belongs to the band below (0), 1612 m to the band above (0): 50 < r < 1612
        RangeBands(edges=(50, 1612), values=(0.0, 0.4, 0.0), upper_owns=(False, True)),
        AngularSector.blind(centre=math.pi, width=math.radians(65)),  # astern, body frame
    ]),
    clutter=ClutterDensityModel(factors=[RangeBands(edges=(1000,), values=(1e-3, 1e-2))]))
lidar = SensorModel(
    name="lidar",
    detection=DetectionProbabilityModel(factors=[
        RangeBands(edges=(50, 80), values=(0.95, 0.2, 0.0))]),
    clutter=ClutterDensityModel(factors=[
        # every lidar detection must carry metadata["area"] (m²): no silent default
        MetadataThreshold(key="area", threshold=10, below=1e-1, at_or_above=1e-3)]))

# %%
# One scan's contexts
# -------------------
# The ego at (200, 100) heading north-east; states are Stone Soup's [x, vx, y, vy] rows.
ego = Pose(x=200.0, y=100.0, heading=math.radians(45))
radar_scan, lidar_scan = radar.context(ego), lidar.context(ego)


def ahead(distance, bearing=0.0):
    """A state ``distance`` metres from the ego at ``bearing`` off its bow."""
    angle = ego.heading + bearing
    return [ego.x + distance * math.cos(angle), 0.0, ego.y + distance * math.sin(angle), 0.0]


probe = np.array([ahead(500), ahead(500, math.pi), ahead(30), ahead(60)])
p_radar = radar_scan.prob_detection_array(probe)
p_lidar = lidar_scan.prob_detection_array(probe)
either = 1 - (1 - p_radar) * (1 - p_lidar)
for label, pr, pl, pe in zip(["500 m ahead", "500 m astern", "30 m ahead", "60 m ahead"],
                             p_radar, p_lidar, either):
    print(f"{label}: radar {pr:.2f}, lidar {pl:.2f}, either {pe:.3f}")

# λ of two lidar segments (positions and their areas)
segments = np.array([ahead(20)[::2], ahead(40)[::2]])
lam = lidar_scan.clutter_spatial_density_array(segments, np.array([[2.5], [30.0]]))
print("lidar λ for areas 2.5 and 30 m²:", ", ".join(f"{v:g}" for v in lam))

# %%
# Coverage maps
# -------------
# P_D of each sensor and of "at least one detects", on the radar's kilometre scale and on
# the lidar's hundred metres.
fig, axes = plt.subplots(2, 3, figsize=(11, 7), layout="constrained")
for row, extent in enumerate((1800.0, 100.0)):
    xs = np.linspace(-extent, extent, 301)
    grid = np.array([[ego.x + x, 0.0, ego.y + y, 0.0] for y in xs for x in xs])
    maps = [scan.prob_detection_array(grid).reshape(len(xs), len(xs))
            for scan in (radar_scan, lidar_scan)]
    maps.append(1 - (1 - maps[0]) * (1 - maps[1]))
    for ax, pd, title in zip(axes[row], maps, ("radar", "lidar", "either sensor")):
        image = ax.imshow(pd, origin="lower", vmin=0, vmax=1, cmap="viridis",
                          extent=(ego.x - extent, ego.x + extent, ego.y - extent, ego.y + extent))
        ax.arrow(ego.x, ego.y, 0.15 * extent * math.cos(ego.heading),
                 0.15 * extent * math.sin(ego.heading), color="red",
                 width=0.01 * extent)
        ax.set_title(f"{title}, ±{extent:g} m")
fig.colorbar(image, ax=axes, label="P_D")
