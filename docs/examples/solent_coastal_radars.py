"""
Two coastal radars over the Solent: a real coast, real ships
============================================================

Two radars watch the eastern Solent: a long-range one on the Isle of Wight's eastern tip
(the Foreland at Bembridge: 20 km, a scan every 2.5 s) and a short-range one on the shore
at Southsea Castle, Portsmouth (10 km, a scan a second). The Isle of Wight hides the
Channel from Southsea. A tracker that assumes one P_D for every scan takes each of
Southsea's empty scans as a miss of every ship south of the island — ships only the
Foreland can see — and deletes them.

The coast is the GSHHG shoreline and the ships are the AIS log of 12 January 2016 that
Stone Soup publishes (:mod:`ctxmodels.geo`; both are downloaded once from the package
index). The radars' scans are the study's simulation (its scenario 4,
:mod:`ctxmodels.experiment.solent`): the real ships, detected where each radar can see them.
"""

# %%
# What each radar can see
# -----------------------
# Each radar stands on the shore; the land within 500 m of its antenna does not block its
# view (``LineOfSight(clearance=500)``), the rest of the coast casts its shadow.
import matplotlib.pyplot as plt
import numpy as np

from ctxmodels import Pose
from ctxmodels.experiment.solent import scene
from ctxmodels.experiment.solent.run import make_solent
from ctxmodels.experiment.solent.trackers import site_models

models = site_models("context")  # range bands, horizon, land, line of sight
platform = Pose(x=0.0, y=0.0, heading=0.0)  # Southsea Castle; each radar is mounted at its site
xs, ys = np.linspace(-22e3, 24e3, 230), np.linspace(-31e3, 9e3, 200)
gx, gy = np.meshgrid(xs, ys)
grid = np.column_stack([gx.ravel(), np.zeros(gx.size), gy.ravel(), np.zeros(gx.size)])
fig, axes = plt.subplots(1, 2, figsize=(11, 4.6), layout="constrained")
for ax, (name, model) in zip(axes, models.items()):
    pd = model.detection.evaluate(model.sensor_pose(platform), grid).reshape(gx.shape)
    ax.imshow(pd, origin="lower", extent=(xs[0] / 1e3, xs[-1] / 1e3, ys[0] / 1e3, ys[-1] / 1e3),
              vmin=0, vmax=1, cmap="viridis")
    for polygon in scene.land():
        ring = np.vstack([polygon["shell"], polygon["shell"][:1]]) / 1e3
        ax.plot(ring[:, 0], ring[:, 1], color="w", lw=0.5)
    ax.set_xlim(xs[0] / 1e3, xs[-1] / 1e3)
    ax.set_ylim(ys[0] / 1e3, ys[-1] / 1e3)
    ax.set_title(f"P_D of the {name} radar")
    ax.set_xlabel("east (km)")
    ax.set_ylabel("north (km)")

# %%
# The same ships, three trackers
# ------------------------------
# A GM-PHD that applies P_D 0.7 everywhere, one that knows each radar's range bands, and
# one that knows the coast's shadows too (the study's ``gmphd-uniform``, ``gmphd-pd-aware``
# and ``gmphd-sight``: :func:`~ctxmodels.trackers.paper_tracker` on the two radars' scans,
# each radar's :class:`~ctxmodels.SensorModel` mounted at its site), on one seeded run of the
# study's ten-minute window, scored as the study scores it.
from ctxmodels.experiment.runner import track_scans  # noqa: E402
from ctxmodels.experiment.scoring import score_run  # noqa: E402
from ctxmodels.experiment.solent.trackers import build_solent_tracker  # noqa: E402
from ctxmodels.stonesoup.ordering import in_track_order  # noqa: E402
from ctxmodels.trackers import TRACKERS  # noqa: E402

run = make_solent(seed=7)
for name in ("gmphd-uniform", "gmphd-pd-aware", "gmphd-sight"):
    _, _, tracks = track_scans(build_solent_tracker(TRACKERS[name], run))
    score = score_run(run, [t for t in in_track_order(tracks) if len(t)])
    tracked = score.management.matched_truth_frames / score.management.truth_frames
    print(f"{TRACKERS[name].label}: ships tracked {100 * tracked:.0f} % of the time, "
          f"HOTA {100 * score.hota.hota:.1f} %")

# %%
# The uniform tracker follows only what Southsea sees: every Southsea scan counts as a miss
# of each ship south of the island, which only the Foreland can see. Knowing each radar's
# coverage keeps them.
