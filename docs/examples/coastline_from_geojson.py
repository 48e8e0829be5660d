"""
A coastline from GeoJSON: land mask and radar shadow
====================================================

Coastlines come as longitude/latitude polygons, usually GeoJSON. Here a small archipelago
(an island with a lagoon, and a second island) is written as a GeoJSON
``FeatureCollection``, read with :meth:`ctxmodels.LandMask.from_geojson` around a local
origin (so positions are east/north metres), and put into a radar's detection
probability twice: as land (no target is detected *on* land) and as line of sight (no
target is detected *behind* land, the radar shadow).
"""

# %%
# The GeoJSON
# -----------
# Written here by hand; in practice ``LandMask.from_geojson("coast.geojson", origin=...)``
# reads a file, or :meth:`~ctxmodels.LandMask.from_shapely` takes a shapely geometry.
import math

import matplotlib.pyplot as plt
import numpy as np

from ctxmodels import (DetectionProbabilityModel, LandMask, LineOfSight, RangeBands,
                       ClutterDensityModel, SensorModel)

origin = (10.60, 59.85)  # longitude, latitude: the radar's harbour


def ring(lon, lat, radius_m, n=36, squash=1.0):
    """A closed ring of ``n`` points around (lon, lat), ``radius_m`` metres."""
    angles = np.linspace(0, 2 * math.pi, n, endpoint=False)
    dlon = radius_m * np.cos(angles) / (111_320 * math.cos(math.radians(lat)))
    dlat = squash * radius_m * np.sin(angles) / 111_000
    points = np.column_stack([lon + dlon, lat + dlat])
    return np.vstack([points, points[:1]]).tolist()


coast = {"type": "FeatureCollection", "features": [
    {"type": "Feature", "properties": {"name": "lagoon island"},
     "geometry": {"type": "Polygon", "coordinates": [ring(10.62, 59.853, 600, squash=0.7),
                                                     ring(10.62, 59.853, 250, squash=0.7)]}},
    {"type": "Feature", "properties": {"name": "skerry"},
     "geometry": {"type": "Polygon", "coordinates": [ring(10.585, 59.842, 200)]}},
]}
land = LandMask.from_geojson(coast, origin=origin)
print(f"{len(land.polygons)} polygons, {land.vertex_count} vertices, "
      f"{sum(len(p['holes']) for p in land.polygons)} hole")

# %%
# The radar with and without the coast
# ------------------------------------
# A 0.9 P_D out to 2 km, at the origin; the same radar with the land mask and the shadow.
bands = RangeBands(edges=(2000.0,), values=(0.9, 0.0))
clutter = ClutterDensityModel(factors=[1e-4])
plain = SensorModel(detection=DetectionProbabilityModel(factors=[bands]), clutter=clutter)
coastal = SensorModel(detection=DetectionProbabilityModel(
    factors=[bands, land, LineOfSight(land=land)]), clutter=clutter)

extent = 2200.0
xs = np.linspace(-extent, extent, 300)
grid = np.array([[x, 0.0, y, 0.0] for y in xs for x in xs])
pose = (0.0, 0.0, 0.0)
maps = {name: model.context(pose).prob_detection_array(grid).reshape(len(xs), len(xs))
        for name, model in (("open sea", plain), ("with the coast", coastal))}
hidden = float(np.mean(maps["with the coast"] < maps["open sea"]))
print(f"share of the map the coast hides (land or shadow): {hidden:.1%}")

fig, axes = plt.subplots(1, 2, figsize=(9, 4.2), sharey=True, layout="constrained")
for ax, (name, pd) in zip(axes, maps.items()):
    image = ax.imshow(pd, origin="lower", extent=(-extent, extent, -extent, extent),
                      vmin=0, vmax=1, cmap="viridis")
    for polygon in land.polygons:
        for boundary in (polygon["shell"], *polygon["holes"]):
            ax.plot(*np.vstack([boundary, boundary[:1]]).T, color="white", lw=0.8)
    ax.plot(0, 0, marker="^", color="red", label="radar")
    ax.set_title(name)
    ax.set_xlabel("east (m)")
axes[0].set_ylabel("north (m)")
axes[0].legend(loc="lower left")
fig.colorbar(image, ax=axes, label="P_D")
