"""``ctxmodels coverage``: a sensor model's P_D map around a pose."""
from __future__ import annotations

import math
import os
import sys
from pathlib import Path

from .validation import MAX_COORDINATE, MAX_RESOLUTION, check_coverage, integer, number


def add_coverage_command(commands) -> None:
    from ..experiment.scenarios import SCENARIOS
    cov = commands.add_parser(
        "coverage", help="draw a sensor model's P_D coverage map",
        description="Draws P_D around a sensor pose for the paper's radar and lidar models "
                    "(optionally with a scenario's islands: land mask and radar shadow), or for "
                    "sensor models saved as Stone Soup YAML (--model); a radar horizon is drawn "
                    "as a ring, a radar equation's P_D against range per Swerling case.")
    cov.add_argument("--sensors", nargs="+", default=["radar", "lidar"], choices=["radar", "lidar"])
    cov.add_argument("--model", nargs="+", metavar="YAML",
                     help="SensorModel files (Stone Soup YAML) instead of the paper's models")
    cov.add_argument("--scenario", choices=list(SCENARIOS), default=None,
                     help="draw with this scenario's land (e.g. islands)")
    cov.add_argument("--pose", nargs=3, type=number(-MAX_COORDINATE, MAX_COORDINATE),
                     default=(0.0, 0.0, 90.0),
                     metavar=("X", "Y", "HEADING_DEG"),
                     help="platform pose: metres, metres, degrees counter-clockwise from +x "
                          "(default 0 0 90: facing +y)")
    cov.add_argument("--extent", nargs="+", type=number(0, MAX_COORDINATE, above=True),
                     default=[1800.0, 100.0],
                     help="half-widths of the maps in metres, one row each (default 1800 100)")
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
