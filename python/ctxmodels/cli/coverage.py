"""``ctxmodels coverage``: a sensor model's P_D map around a pose, or at a real coastal site."""
from __future__ import annotations

import math
import os
import sys
from pathlib import Path

from .validation import MAX_COORDINATE, MAX_RESOLUTION, check_coverage, integer, number


def add_coverage_command(commands) -> None:
    from ..experiment.scenarios import SIMULATED_SCENARIOS
    cov = commands.add_parser(
        "coverage", help="draw a sensor model's P_D coverage map",
        description="Draws P_D around a sensor pose for the paper's radar and lidar models "
                    "(optionally with a scenario's islands: land mask and radar shadow), or for "
                    "sensor models saved as Stone Soup YAML (--model); a radar horizon is drawn "
                    "as a ring, a radar equation's P_D against range per Swerling case. With "
                    "--site, a radar (or the --model files) at a real coastal site, on the "
                    "GSHHG shorelines (downloaded once from the package index): its land, the "
                    "shadows behind headlands and islands, and its horizon.")
    cov.add_argument("--sensors", nargs="+", default=["radar", "lidar"], choices=["radar", "lidar"])
    cov.add_argument("--model", nargs="+", metavar="YAML",
                     help="SensorModel files (Stone Soup YAML) instead of the paper's models")
    cov.add_argument("--scenario", choices=list(SIMULATED_SCENARIOS), default=None,
                     help="draw with this scenario's land (e.g. islands)")
    cov.add_argument("--site", nargs=2, type=number(-180.0, 180.0), default=None,
                     metavar=("LON", "LAT"),
                     help="a real site, longitude and latitude in degrees (WGS 84): the maps "
                          "are in metres east and north of it, with its land")
    cov.add_argument("--antenna-height", type=number(0, MAX_COORDINATE, above=True), default=None,
                     help="with --site: the radar's antenna above the sea, metres (default 20); "
                          "its horizon over targets at --height")
    cov.add_argument("--clearance", type=number(0, MAX_COORDINATE), default=None,
                     help="with --site: land within this many metres of the antenna does not "
                          "block its view (a mast, a cliff top; default 500, 0 for a site at sea)")
    cov.add_argument("--coastline", choices=["c", "l", "i", "h", "f"], default=None,
                     help="with --site: GSHHG resolution, crude to full (default f)")
    cov.add_argument("--pose", nargs=3, type=number(-MAX_COORDINATE, MAX_COORDINATE),
                     default=(0.0, 0.0, 90.0),
                     metavar=("X", "Y", "HEADING_DEG"),
                     help="platform pose: metres, metres, degrees counter-clockwise from +x "
                          "(default 0 0 90: facing +y)")
    cov.add_argument("--extent", nargs="+", type=number(0, MAX_COORDINATE, above=True),
                     default=None,
                     help="half-widths of the maps in metres, one row each (default 1800 100; "
                          "with --site 25000)")
    cov.add_argument("--height", type=number(-MAX_COORDINATE, MAX_COORDINATE), default=0.0,
                     help="height of the targets in the maps of 3-D models (those whose "
                          "position_mapping has a z), metres (default 0)")
    cov.add_argument("--ceiling", type=number(0, MAX_COORDINATE, above=True), default=None,
                     help="top of a 3-D model's range–height section, metres (default: a "
                          "tenth of the first extent)")
    cov.add_argument("--resolution", type=integer(2, MAX_RESOLUTION), default=400,
                     help=f"grid points per side, 2–{MAX_RESOLUTION} (default 400)")
    cov.add_argument("--title", default="", help="figure title")
    cov.add_argument("--output", default="coverage.png",
                     help="PNG file to write (its folder must exist)")
    cov.set_defaults(run=_coverage, check=check_coverage, error=cov.error)



def _coverage(args) -> int:
    from ..experiment.coverage_plots import plot_coverage
    from ..experiment.scenarios import make_scenario
    from ..experiment.sensors import paper_sensor_models
    land = []
    if args.site:
        models, land = _at_site(args)
    else:
        if args.scenario:
            land = make_scenario(args.scenario, 0, 1.0).land
        models = args.models  # loaded and checked by check_coverage
        if models is None:
            models = paper_sensor_models(land=land)
            models = {name: models[name] for name in args.sensors}
    pose = (args.pose[0], args.pose[1], math.radians(args.pose[2]))
    output = Path(args.output)
    # Drawn beside the target, then renamed: an interrupted run leaves no truncated image.
    partial = output.with_name(f".{output.stem}.{os.getpid()}.partial{output.suffix}")
    try:
        plot_coverage(partial, models, pose, extents=args.extent, land=land,
                      resolution=args.resolution, title=args.title, height=args.height,
                      ceiling=args.ceiling)
        os.replace(partial, output)
    finally:
        partial.unlink(missing_ok=True)
    print(f"wrote {output}", file=sys.stderr)
    return 0


def _at_site(args):
    """The site's models (a radar, or the --model files with the site's land and line of
    sight added) and its land outlines."""
    from ..clutter import ClutterDensityModel
    from ..detection import DetectionProbabilityModel
    from ..downloads import DownloadError
    from ..geo.site import coastal_site
    from ..horizon import RadarHorizon
    from ..range_bands import RangeBands
    from ..sensor import SensorModel
    try:
        site = coastal_site(tuple(args.site), max(args.extent), resolution=args.coastline)
    except DownloadError as err:
        sys.exit(f"ctxmodels coverage: {err}")
    sight = site.line_of_sight(args.clearance)
    where = (f"on land, {site.shore_distance:,.0f} m from the shore" if site.on_land
             else "at sea" if site.land is not None else "at sea, no land within the maps")
    print(f"site {args.site[0]:g}, {args.site[1]:g}: {where} on the GSHHG '{args.coastline}' "
          f"shoreline; land within {args.clearance:g} m of the antenna blocks nothing",
          file=sys.stderr)
    if site.on_land and site.shore_distance > args.clearance:
        print(f"note: the shore is farther than --clearance ({args.clearance:g} m): every ray "
              f"meets land and the site sees nothing", file=sys.stderr)
    site_factors = [] if site.land is None else [site.land, sight]
    if args.models is None:
        radar = DetectionProbabilityModel(factors=[
            RangeBands(edges=(max(args.extent),), values=(1.0, 0.0)),
            RadarHorizon(antenna_height=args.antenna_height, target_height=max(args.height, 0.0)),
            *site_factors])
        clutter = ClutterDensityModel(factors=[1e-6])  # (not drawn)
        models = {"site radar": SensorModel(detection=radar, clutter=clutter, name="site radar")}
    else:
        models = {}
        for name, model in args.models.items():
            given = {key: getattr(model, key) for key in type(model).properties}
            given["detection"] = DetectionProbabilityModel(
                factors=[*model.detection.factors, *site_factors])
            models[name] = SensorModel(**given)
    lon, lat = args.site
    args.title = args.title or (
        f"site {abs(lat):.4f}° {'N' if lat >= 0 else 'S'}, {abs(lon):.4f}° {'E' if lon >= 0 else 'W'}, "
        f"antenna {args.antenna_height:g} m\nGSHHG '{args.coastline}' shoreline; x east, y north")
    polygons = () if site.land is None else site.land.polygons
    outlines = [ring for polygon in polygons for ring in [polygon["shell"], *polygon["holes"]]]
    return models, outlines
