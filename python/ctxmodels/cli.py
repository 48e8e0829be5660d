"""Command line: ``ctxmodels experiment`` (the paper's comparison) and ``ctxmodels coverage``
(a sensor model's P_D map). ``ctxmodels <command> --help`` explains every option."""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

#: Figures the experiment draws for its plot seed: scenario → trackers (paper Fig. 4).
FIGURES = {
    "mixed-range": ("jpda", "gmphd-uniform", "gmphd-context"),
    "formation": ("jpda", "gmphd-uniform", "gmphd-context"),
    "islands": ("gmphd-context", "gmphd-sight"),
}


def _experiment(args) -> int:
    from .experiment.runner import ExperimentConfig, run_experiment
    from .experiment.trackers import TRACKERS
    if args.trackers == ["all"]:
        args.trackers = list(TRACKERS)
    radar, lidar = _simulated_sensors(args)
    config = ExperimentConfig(scenarios=args.scenarios, trackers=args.trackers,
                              seeds=list(range(args.seed_start, args.seed_start + args.seeds)),
                              duration=args.duration, stock=args.stock, workers=args.workers,
                              static_distractors=not args.static_as_false,
                              plot_seed=None if args.no_plots else args.seed_start,
                              radar=radar, lidar=lidar)
    print(f"ctxmodels experiment: {len(config.jobs())} runs "
          f"({len(args.scenarios)} scenarios × trackers × {args.seeds} seeds), "
          f"{args.duration:g} s each, {config.workers or 'all'} workers", file=sys.stderr)
    results = run_experiment(config, progress=not args.quiet)
    print(results.table_markdown())
    paths = results.save(args.output)
    if not args.no_plots:
        paths.update(_draw(results, Path(args.output)))
    print("\nwrote " + ", ".join(str(p) for p in paths.values()), file=sys.stderr)
    return 0


def _simulated_sensors(args):
    """The simulation's sensor settings from the sensitivity options (None: defaults)."""
    import dataclasses

    from .experiment.scenarios import LidarConfig, RadarConfig
    radar_changes, lidar_changes = {}, {}
    if args.radar_clutter is not None:
        near, far = args.radar_clutter
        radar_changes.update(clutter_per_scan_near=near, clutter_per_scan_far=far)
    if args.radar_bearing_std is not None:
        radar_changes["bearing_std"] = math.radians(args.radar_bearing_std)
    if args.lidar_clutter is not None:
        lidar_changes["clutter_per_scan"] = args.lidar_clutter
    radar = dataclasses.replace(RadarConfig(), **radar_changes) if radar_changes else None
    lidar = dataclasses.replace(LidarConfig(), **lidar_changes) if lidar_changes else None
    return radar, lidar


def _non_negative(text: str) -> float:
    value = float(text)
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(f"expected a finite number ≥ 0, got {text!r}")
    return value


def _positive(text: str) -> float:
    value = _non_negative(text)
    if value == 0:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def _draw(results, folder: Path) -> dict:
    from .experiment.plots import Polyline, plot_coverage, plot_tracks
    from .experiment.scenarios import make_scenario
    from .experiment.sensors import paper_sensor_models
    from .experiment.trackers import TRACKERS
    written = {}
    config = results.config
    for scenario in config.scenarios:
        run = make_scenario(scenario, config.plot_seed, config.duration)
        epoch = run.radar_times[0]
        truths = [Polyline.from_states(t.states, epoch, label=t.id)
                  for t in sorted(run.truths, key=lambda t: t.id)]
        ego = Polyline([(t - epoch).total_seconds() for t in run.ego.timestamps],
                       run.ego.positions)
        for result in results.results:
            job = result.job
            if job.scenario != scenario or job.seed != config.plot_seed or \
                    job.tracker not in FIGURES.get(scenario, ()):
                continue
            tracks = [Polyline(times, xy) for times, xy in result.tracks]
            path = folder / f"tracks_{scenario}_{job.tracker}.png"
            plot_tracks(path, f"{scenario}: {TRACKERS[job.tracker].label} (seed {job.seed})",
                        tracks, truths, ego, float(run.ego.headings[-1]), land=run.land,
                        static_positions=run.static_positions)
            written[path.stem] = path
        pose = run.ego.pose_at(run.radar_times[0])
        path = folder / f"coverage_{scenario}.png"
        plot_coverage(path, paper_sensor_models(land=run.land), tuple(pose), land=run.land,
                      title=f"P_D of the context-aware models, {scenario}, first radar scan")
        written[path.stem] = path
    return written


def _coverage(args) -> int:
    from .experiment.plots import plot_coverage
    from .experiment.scenarios import make_scenario
    from .experiment.sensors import paper_sensor_models
    land = []
    if args.scenario:
        land = make_scenario(args.scenario, 0, 1.0).land
    if args.model:
        from stonesoup.serialise import YAML
        models = {}
        for file in args.model:
            model = YAML().load(Path(file).read_text())
            models[getattr(model, "name", "") or Path(file).stem] = model
    else:
        models = paper_sensor_models(land=land)
        models = {name: models[name] for name in args.sensors}
    pose = (args.pose[0], args.pose[1], math.radians(args.pose[2]))
    plot_coverage(args.output, models, pose, extents=args.extent, land=land,
                  resolution=args.resolution, title=args.title)
    print(f"wrote {args.output}", file=sys.stderr)
    return 0


def _list(args) -> int:
    from .experiment.scenarios import SCENARIOS
    from .experiment.trackers import TRACKERS
    print("scenarios:")
    for name, spec in SCENARIOS.items():
        print(f"  {name:14s} {getattr(spec, 'description', '')}".rstrip())
    print("trackers:")
    for name, spec in TRACKERS.items():
        print(f"  {name:18s} {spec.label}: {spec.description}")
    return 0


def parser() -> argparse.ArgumentParser:
    from .experiment.scenarios import SCENARIOS
    main = argparse.ArgumentParser(
        prog="ctxmodels",
        description="Context-aware sensor models for Stone Soup trackers: run the paper's "
                    "radar–lidar comparison or draw a sensor's detection-probability map.")
    commands = main.add_subparsers(dest="command", required=True)

    exp = commands.add_parser(
        "experiment", help="simulate the radar–lidar scenarios and compare the trackers",
        description="Simulates the paper's asynchronous radar (0.8 Hz, 50–1612 m, 65° rear "
                    "blind sector) and lidar (10 Hz, ≤ 80 m) scenarios, runs each tracker "
                    "(JPDA, GM-PHD uniform / radar-only / P_D-aware / context-aware, ...) on "
                    "each seed, and scores HOTA and RMS GOSPA at radar timestamps. Prints the "
                    "table (paper Table II layout, mean ± 95 %% interval over seeds) and "
                    "writes results.md/.csv/.json and PNG figures to --output.")
    exp.add_argument("--scenarios", nargs="+", default=list(SCENARIOS), choices=list(SCENARIOS),
                     metavar="NAME", help=f"scenarios to run (default: all of {list(SCENARIOS)})")
    exp.add_argument("--trackers", nargs="+", default=None, metavar="NAME",
                     help="trackers to compare, or 'all' (default: the paper's five and the "
                          "line-of-sight GM-PHD; `ctxmodels list` names them all)")
    exp.add_argument("--seeds", type=int, default=2, help="Monte Carlo seeds per scenario (default 2)")
    exp.add_argument("--seed-start", type=int, default=0, help="first seed (default 0)")
    exp.add_argument("--duration", type=float, default=60.0,
                     help="seconds of each scenario to simulate (default 60, which keeps the "
                          "default run within ~5 min on 2 cores). The scenarios are 480 s long; "
                          "on 2 cores `--duration 480 --seeds 3` of the GM-PHD trackers takes "
                          "~22 min, while one 480 s JPDA run alone takes over 15 min (it "
                          "confirms hundreds of clutter tracks)")
    exp.add_argument("--workers", type=int, default=None,
                     help="parallel processes (default: one per core)")
    exp.add_argument("--output", default="results", help="output folder (default ./results)")
    exp.add_argument("--stock", action="store_true",
                     help="run the stock Stone Soup GM-PHD components instead of ctxmodels' "
                          "fast drop-ins (same results, slower; for verification)")
    exp.add_argument("--static-as-false", action="store_true",
                     help="count tracks on static sea markers and islets as false tracks "
                          "(default: they are distractors, neither hits nor false tracks)")
    exp.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    exp.add_argument("--quiet", action="store_true", help="no progress bar")
    sim = exp.add_argument_group(
        "simulated sensors (sensitivity studies: these change the simulated truth only, "
        "never the trackers' models)")
    sim.add_argument("--radar-clutter", nargs=2, type=_non_negative, metavar=("NEAR", "FAR"),
                     default=None,
                     help="mean radar clutter returns per scan inside / beyond 1000 m (default "
                          "5 32, i.e. 1e-3 and 1e-2 per rad·m: the paper's context-aware λ; "
                          "5 3.2 makes the uniform λ = 1e-3 true everywhere)")
    sim.add_argument("--lidar-clutter", type=_non_negative, metavar="N", default=None,
                     help="mean lidar clutter segments per scan within 80 m (default 3)")
    sim.add_argument("--radar-bearing-std", type=_positive, metavar="DEG", default=None,
                     help="radar bearing noise σ in degrees (default 1)")
    exp.set_defaults(run=_experiment)

    cov = commands.add_parser(
        "coverage", help="draw a sensor model's P_D coverage map",
        description="Draws P_D around a sensor pose for the paper's radar and lidar models "
                    "(optionally with a scenario's islands: land mask and radar shadow), or for "
                    "sensor models saved as Stone Soup YAML (--model).")
    cov.add_argument("--sensors", nargs="+", default=["radar", "lidar"], choices=["radar", "lidar"])
    cov.add_argument("--model", nargs="+", metavar="YAML",
                     help="SensorModel files (Stone Soup YAML) instead of the paper's models")
    cov.add_argument("--scenario", choices=list(SCENARIOS), default=None,
                     help="draw with this scenario's land (e.g. islands)")
    cov.add_argument("--pose", nargs=3, type=float, default=(0.0, 0.0, 90.0),
                     metavar=("X", "Y", "HEADING_DEG"),
                     help="platform pose: metres, metres, degrees counter-clockwise from +x "
                          "(default 0 0 90: facing +y)")
    cov.add_argument("--extent", nargs="+", type=float, default=[1800.0, 100.0],
                     help="half-widths of the maps in metres, one row each (default 1800 100)")
    cov.add_argument("--resolution", type=int, default=400, help="grid points per side")
    cov.add_argument("--title", default="", help="figure title")
    cov.add_argument("--output", default="coverage.png", help="PNG file to write")
    cov.set_defaults(run=_coverage)

    lst = commands.add_parser("list", help="list the scenarios and trackers")
    lst.set_defaults(run=_list)
    return main


def main(argv=None) -> int:
    args = parser().parse_args(argv)
    return args.run(args)


if __name__ == "__main__":
    sys.exit(main())
