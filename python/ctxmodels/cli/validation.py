"""Argument checks for ``ctxmodels``: every user error is refused as a one-line usage error
(exit code 2) before any work starts. The bounds below are stated in ``--help``."""
from __future__ import annotations

import argparse
import math
import os
from pathlib import Path

#: Upper bound of --seeds: the job list is built in memory up front.
MAX_SEEDS = 10_000
#: The simulation's clock ticks in microseconds: a shorter run holds no scan at all.
MIN_DURATION = 1e-6
#: Bounds of the simulated sensors (sensitivity options). The simulator draws every scan of
#: a run up front, ~1 kB per detection: at these rates a full 480 s run holds at most
#: ~0.4 M radar clutter returns (384 scans) and ~0.5 M lidar ones (4 800 scans), well under
#: 1 GB per worker process — while already ~30× the defaults (5 + 32 radar, 3 lidar).
MAX_RADAR_CLUTTER = 1000.0  # NEAR + FAR, mean returns per radar scan
MAX_LIDAR_CLUTTER = 100.0  # mean segments per lidar scan
MAX_BEARING_STD_DEG = 45.0  # beyond this a bearing says nothing (the radar sees ±147.5°)
#: Coverage maps: grid points per side (16 M P_D evaluations per map at most), and the
#: largest map half-width and pose coordinate (m), far inside the core's numeric range.
MAX_RESOLUTION = 4000
MAX_COORDINATE = 1e7


class UsageError(Exception):
    """A bad argument found after parsing; the CLI reports it with ``parser.error``."""


def _interval(low, high, above: bool) -> str:
    if math.isinf(high):
        return f"{'>' if above else '≥'} {low:g}"
    return f"in {'(' if above else '['}{low:g}, {high:g}]"


def integer(low: int, high: float = math.inf):
    """An argparse type: an integer in [low, high]."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(
                f"expected an integer {_interval(low, high, False)}, got {text!r}")
        return value
    return parse


def number(low: float = -math.inf, high: float = math.inf, above: bool = False):
    """An argparse type: a finite float ≥ low (> low when ``above``) and ≤ high."""
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
        if not (math.isfinite(value) and (value > low if above else value >= low)
                and value <= high):
            bound = "" if math.isinf(low) and math.isinf(high) else " " + _interval(low, high, above)
            raise argparse.ArgumentTypeError(f"expected a finite number{bound}, got {text!r}")
        return value
    return parse


def require_module(module: str, option: str, why: str, instead: str = "") -> None:
    """UsageError unless ``module`` can be imported (looked up, not imported): a study
    must not run for minutes and then fail on a missing figure library."""
    import importlib.util
    try:
        found = importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):
        found = False
    if not found:
        raise UsageError(f"argument {option}: {why} need{'' if why.endswith('s') else 's'} "
                         f"{module}, which is not installed: pip install \"ctxmodels[experiment]\""
                         + (f" (or {instead})" if instead else ""))


def check_experiment(args) -> None:
    """Checks what argparse cannot alone; normalises ``args.scenarios``/``args.trackers``
    and sets ``args.skipped``: the (tracker, scenario) pairs that will not run."""
    if not getattr(args, "no_plots", False):
        require_module("matplotlib", "--no-plots", "the figures", "pass --no-plots")
    from ..experiment.scenarios import SCENARIOS
    from ..experiment.trackers import applicable
    from ..trackers import TRACKERS
    args.scenarios = list(dict.fromkeys(args.scenarios))
    named: list[str] = []  # trackers the user named one by one
    if args.trackers is not None and "all" in args.trackers:
        args.trackers = list(TRACKERS)
    elif args.trackers is not None:
        args.trackers = named = list(dict.fromkeys(args.trackers))
    args.skipped = []
    for tracker in named:
        spec = TRACKERS[tracker]
        skipped = [s for s in args.scenarios if not applicable(tracker, s)]
        if len(skipped) == len(args.scenarios):
            why = " (line of sight needs a scenario's land)" if spec.line_of_sight else ""
            raise UsageError(f"argument --trackers: {tracker} cannot run on "
                             f"{', '.join(skipped)}; it runs only on "
                             f"{', '.join(s for s in SCENARIOS if applicable(tracker, s))}{why}")
        args.skipped += [(tracker, s) for s in skipped]
    if args.seeds is None:
        args.seeds = args.quick_seeds if args.quick else args.full_seeds
    if args.duration is None and args.quick:
        args.duration = args.quick_duration
    length = min(SCENARIOS[s].duration for s in args.scenarios)
    if args.duration is not None and not MIN_DURATION <= args.duration <= length:
        raise UsageError(f"argument --duration: expected seconds in [{MIN_DURATION:g}, "
                         f"{length:g}] (the scenarios are {length:g} s long), "
                         f"got {args.duration:g}")
    if getattr(args, "radar_clutter", None) is not None and sum(args.radar_clutter) > MAX_RADAR_CLUTTER:
        raise UsageError(f"argument --radar-clutter: NEAR + FAR must be ≤ "
                         f"{MAX_RADAR_CLUTTER:g} per scan, got {sum(args.radar_clutter):g}")


def check_writable_folder(folder: Path, option: str = "--output") -> bool:
    """Creates ``folder`` if needed and writes and removes a probe file in it. Returns
    whether the folder was created (so that a run that writes nothing can remove it)."""
    if folder.exists() and not folder.is_dir():
        raise UsageError(f"argument {option}: {folder} exists and is not a folder")
    created = not folder.exists()
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise UsageError(f"argument {option}: cannot create folder {folder}: "
                         f"{err.strerror or err}") from None
    probe = folder / f".ctxmodels-probe-{os.getpid()}"
    try:
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as err:
        if created:
            _remove_if_empty(folder)
        raise UsageError(f"argument {option}: cannot write in folder {folder}: "
                         f"{err.strerror or err}") from None
    return created


def _remove_if_empty(folder: Path) -> None:
    try:
        folder.rmdir()
    except OSError:
        pass


def check_coverage(args) -> None:
    """Loads the --model files into ``args.models``, checks the site options and the output
    file."""
    args.sensors = list(dict.fromkeys(args.sensors))
    _check_site(args)
    args.models = load_models(args.model) if args.model else None
    require_module("matplotlib", "--output", "a coverage map")
    output = Path(args.output)
    if output.is_dir():
        raise UsageError(f"argument --output: {output} is a folder; name a PNG file")
    if not output.suffix:  # as matplotlib does, which would add it on saving
        output = args.output = output.with_name(output.name + ".png")
        if output.is_dir():
            raise UsageError(f"argument --output: {output} is a folder; name a PNG file")
    from matplotlib.backend_bases import FigureCanvasBase
    kinds = FigureCanvasBase.get_supported_filetypes()
    if output.suffix and output.suffix[1:].lower() not in kinds:
        raise UsageError(f"argument --output: cannot write {output.suffix!r} images; "
                         f"use one of {', '.join('.' + k for k in sorted(kinds))}")
    if not output.parent.is_dir():
        raise UsageError(f"argument --output: folder {output.parent} does not exist")
    check_writable_folder(output.parent)
    _check_mathtext(args.title, "argument --title", "escape a literal dollar as \\$")
    for name in args.models or ():  # (a model's name is in its maps' titles)
        _check_mathtext(name, f"argument --model: the model named {name!r}",
                        "rename it (a literal dollar as \\$)")


def _check_site(args) -> None:
    """--site's options: only with --site, its latitude off the poles, not with --scenario
    (which brings its own land); fills in their defaults."""
    site_only = {"--antenna-height": args.antenna_height, "--clearance": args.clearance,
                 "--coastline": args.coastline}
    if args.site is None:
        given = [flag for flag, value in site_only.items() if value is not None]
        if given:
            raise UsageError(f"argument {given[0]}: only with --site")
        args.extent = args.extent or [1800.0, 100.0]
        return
    if args.scenario:
        raise UsageError("argument --site: not with --scenario (a site brings its own land)")
    lon, lat = args.site
    if not -80.0 <= lat <= 80.0:
        raise UsageError(f"argument --site: latitude must lie in [-80, 80] degrees (the GSHHG "
                         f"boxes and the local plane are for coasts off the poles), got {lat:g}")
    args.extent = args.extent or [25000.0]
    if max(args.extent) > 500_000.0:
        raise UsageError(f"argument --extent: with --site at most 500000 m (the local plane's "
                         f"reach), got {max(args.extent):g}")
    from ..errors import ArgumentError
    from ..geo.plane import MAX_DISTANCE
    from ..geo.shorelines import farthest_point
    from ..geo.site import box_around
    extent = max(args.extent)
    try:
        box = box_around((lon, lat), extent)
    except ArgumentError as err:  # across the antimeridian, or at a pole
        raise UsageError(f"argument --extent: {extent:g} m around the site: {err.detail}; "
                         f"take a smaller --extent") from None
    if farthest_point(box, (lon, lat))[1] > MAX_DISTANCE:
        raise UsageError(f"argument --extent: {extent:g} m around the site: its box of shorelines "
                         f"reaches farther than {MAX_DISTANCE / 1000:g} km from it (the local "
                         f"plane's reach); take a smaller --extent")
    args.antenna_height = 20.0 if args.antenna_height is None else args.antenna_height
    args.clearance = 500.0 if args.clearance is None else args.clearance
    args.coastline = args.coastline or "f"


def _check_mathtext(text: str, what: str, fix: str) -> None:
    """``text`` must draw: matplotlib reads $...$ as mathtext, and fails only when drawing."""
    if "$" not in text:
        return
    from matplotlib.mathtext import MathTextParser
    try:
        MathTextParser("path").parse(text)
    except Exception as err:
        first = (str(err).strip().splitlines() or [type(err).__name__])[0]
        raise UsageError(f"{what}: not valid mathtext ({first}); {fix}") from None


def load_models(files) -> dict:
    """``{name: SensorModel}`` from Stone Soup YAML files; UsageError when a file cannot be
    read or does not hold a ctxmodels SensorModel."""
    from stonesoup.serialise import YAML

    from ..sensor import SensorModel
    models = {}
    for file in files:
        try:
            text = Path(file).read_text()
        except OSError as err:
            raise UsageError(f"argument --model: cannot read {file}: {err.strerror or err}") from None
        except UnicodeDecodeError:
            raise UsageError(f"argument --model: {file} is not a text (YAML) file") from None
        try:
            model = YAML().load(text)
        except Exception as err:  # any parse or construction error is the file's fault
            first = (str(err).strip().splitlines() or [type(err).__name__])[0]
            raise UsageError(f"argument --model: {file} is not Stone Soup YAML: {first}") from None
        if not isinstance(model, SensorModel):
            raise UsageError(f"argument --model: {file} holds a {type(model).__name__}, "
                             f"not a ctxmodels SensorModel")
        name = model.name or Path(file).stem
        if name in models:
            raise UsageError(f"argument --model: {file} holds a second model named {name!r}; "
                             "each map needs its own name")
        models[name] = model
    return models
