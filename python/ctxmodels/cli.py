"""Command line: ``ctxmodels experiment`` (the paper's comparison) and ``ctxmodels coverage``
(a sensor model's P_D map). ``ctxmodels <command> --help`` explains every option."""
from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import shutil
import sys
import tempfile
from pathlib import Path

from .cli_validation import (MAX_BEARING_STD_DEG, MAX_COORDINATE, MAX_LIDAR_CLUTTER,
                             MAX_RADAR_CLUTTER, MAX_RESOLUTION, MAX_SEEDS, MIN_DURATION,
                             UsageError, check_coverage, check_experiment,
                             check_writable_folder, integer, number)

def _experiment(args) -> int:
    folder = args.folder
    try:
        return _run_experiment(args, folder)
    except BaseException:
        folder.discard()  # an early Ctrl-C or error leaves no empty output folder behind
        raise


def _run_experiment(args, folder) -> int:
    from .experiment.runner import ExperimentConfig, run_experiment
    radar, lidar = _simulated_sensors(args)
    config = ExperimentConfig(scenarios=args.scenarios, trackers=args.trackers,
                              seeds=list(range(args.seed_start, args.seed_start + args.seeds)),
                              duration=args.duration, stock=args.stock, workers=args.workers,
                              static_distractors=not args.static_as_false,
                              plot_seed=None if args.no_plots else args.seed_start,
                              radar=radar, lidar=lidar, extract=args.extract)
    for tracker in dict.fromkeys(t for t, _ in args.skipped):
        print(f"ctxmodels experiment: {tracker} does not run on "
              f"{', '.join(s for t, s in args.skipped if t == tracker)}; skipped there",
              file=sys.stderr)
    length = f"{args.duration:g} s" if args.duration else "all"
    print(f"ctxmodels experiment: {len(config.jobs())} runs "
          f"({len(args.scenarios)} scenarios × trackers × {args.seeds} seeds), "
          f"{length} of each scenario, {config.workers or 'all'} workers", file=sys.stderr)
    results = None
    try:
        results = run_experiment(config, progress=not args.quiet)
        print(results.markdown())
        print(f"\nctxmodels experiment: {results.timing_line()}", file=sys.stderr)
        try:
            with folder.staging() as stage:
                staged = results.save(stage)
                if not args.no_plots:
                    from .experiment.figures import draw_experiment_figures
                    staged.update(draw_experiment_figures(results, stage))
                folder.commit(stage)
        except OSError as err:  # e.g. a full disk: the previous outputs stay as they were
            folder.discard()
            print(f"ctxmodels experiment: cannot write to {folder.path}: {err}", file=sys.stderr)
            return 1
    except KeyboardInterrupt:
        folder.discard()
        done = (f"the results were written to {folder.path}" if folder.committed else
                ("pending runs cancelled, " if results is None else "")
                + f"nothing written to {folder.path}")
        print(f"ctxmodels experiment: interrupted; {done}", file=sys.stderr)
        return 130
    except BaseException:
        folder.discard()
        raise
    print("\nwrote " + ", ".join(str(folder.path / p.name) for p in staged.values()),
          file=sys.stderr)
    return 0


class OutputFolder:
    """The experiment's --output folder. Checked (created, probe file written) before any
    run; written only after every run has finished: the files are made in a hidden staging
    folder inside it and then renamed into place. A run replaces the outputs of the previous
    run in the folder — the files named in its manifest — and never touches other files."""

    MANIFEST = ".ctxmodels-outputs.json"

    def __init__(self, path):
        self.path = Path(path)
        self.created = check_writable_folder(self.path)
        self.committed = False

    def previous(self) -> set[str]:
        """Names of the files the previous run wrote here (that still exist)."""
        try:
            names = json.loads((self.path / self.MANIFEST).read_text())["files"]
        except FileNotFoundError:
            # Written before manifests existed: ctxmodels' fixed names, if it left results.json.
            names = _output_names() if (self.path / "results.json").is_file() else []
        except (OSError, ValueError, KeyError, TypeError):
            names = []  # unreadable manifest: delete nothing
        if not isinstance(names, list):
            return set()
        # Plain names only: a manifest must not reach outside the folder.
        return {n for n in names if isinstance(n, str) and n not in ("", ".", "..")
                and Path(n).name == n and (self.path / n).is_file()}

    @contextlib.contextmanager
    def staging(self):
        stage = Path(tempfile.mkdtemp(prefix=".ctxmodels-staging-", dir=self.path))
        try:
            yield stage
        finally:
            shutil.rmtree(stage, ignore_errors=True)

    def commit(self, stage: Path) -> None:
        from .experiment.executors import sigint_deferred, write_atomic
        new = {p.name for p in stage.iterdir()}
        old = self.previous()
        manifest = self.path / self.MANIFEST
        with sigint_deferred():  # a Ctrl-C now would mix two runs' files
            # The manifest covers both runs while files move, so a crash loses track of none.
            write_atomic(manifest, json.dumps({"files": sorted(old | new)}, indent=1))
            for name in new:
                os.replace(stage / name, self.path / name)
            for name in old - new:
                (self.path / name).unlink(missing_ok=True)
            write_atomic(manifest, json.dumps({"files": sorted(new)}, indent=1))
            self.committed = True

    def discard(self) -> None:
        """After a run that wrote nothing: remove the folder if this run created it."""
        if self.created and not self.committed:
            with contextlib.suppress(OSError):
                self.path.rmdir()  # only when empty


def _output_names() -> list[str]:
    """Every file name ``ctxmodels experiment`` writes."""
    from .experiment.scenarios import SCENARIOS
    from .trackers import TRACKERS
    names = ["results.md", "results.csv", "results.json"]  # (no findings before manifests)
    for scenario in SCENARIOS:
        names += [f"coverage_{scenario}.png"] + [f"tracks_{scenario}_{t}.png" for t in TRACKERS]
    return names


def _check_experiment(args) -> None:
    check_experiment(args)
    args.folder = OutputFolder(args.output)  # last: no folder is created for a bad command


def _simulated_sensors(args):
    """The simulation's sensor settings: the named truth changed by the sensitivity options
    (None: the calibrated default)."""
    import dataclasses

    from .experiment.scenarios import TRUTHS
    truth = TRUTHS[args.truth]
    radar_changes, lidar_changes = {}, {}
    if args.radar_clutter is not None:
        near, far = args.radar_clutter
        radar_changes.update(clutter_per_scan_near=near, clutter_per_scan_far=far)
    if args.radar_bearing_std is not None:
        radar_changes["bearing_std"] = math.radians(args.radar_bearing_std)
    if args.lidar_clutter is not None:
        lidar_changes["clutter_per_scan"] = args.lidar_clutter
    radar = dataclasses.replace(truth.radar, **radar_changes)
    lidar = dataclasses.replace(truth.lidar, **lidar_changes)
    if args.truth == "calibrated":  # None: the defaults, as a results file names them
        radar = None if radar == truth.radar else radar
        lidar = None if lidar == truth.lidar else lidar
    return radar, lidar


def _coverage(args) -> int:
    from .experiment.coverage_plots import plot_coverage
    from .experiment.scenarios import make_scenario
    from .experiment.sensors import paper_sensor_models
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
                      resolution=args.resolution, title=args.title)
        os.replace(partial, output)
    finally:
        partial.unlink(missing_ok=True)
    print(f"wrote {output}", file=sys.stderr)
    return 0


def _list(args) -> int:
    from .experiment.scenarios import SCENARIOS
    from .trackers import TRACKERS
    print("scenarios:")
    for name, spec in SCENARIOS.items():
        print(f"  {name:14s} {getattr(spec, 'description', '')}".rstrip())
    print("trackers:")
    width = max(map(len, TRACKERS))
    for name, spec in TRACKERS.items():
        print(f"  {name:{width}s} {spec.label}: {spec.description}")
    return 0


def study_options(sub, output: str, full_seeds: int, quick_seeds: int,
                  quick_duration: float) -> None:
    """The options ``experiment`` and ``sweep`` share: what to run, on how many seeds, where
    the results go."""
    from .experiment.scenarios import SCENARIOS
    from .trackers import TRACKERS
    sub.add_argument("--scenarios", nargs="+", default=list(SCENARIOS), choices=list(SCENARIOS),
                     metavar="NAME", help=f"scenarios to run (default: all of {list(SCENARIOS)})")
    sub.add_argument("--trackers", nargs="+", default=None, metavar="NAME",
                     choices=list(TRACKERS) + ["all"],
                     help="trackers to compare, or 'all' (default: all; `ctxmodels list` "
                          "names them). Trackers "
                          "run only on the scenarios they are made for (gmphd-sight needs the "
                          "islands' land, the JPDAs run on the paper's two scenarios); a "
                          "named tracker that fits none of --scenarios is an error")
    sub.add_argument("--seeds", type=integer(1, MAX_SEEDS), default=None,
                     help=f"Monte Carlo seeds per scenario, 1–{MAX_SEEDS} (default "
                          f"{full_seeds}; {quick_seeds} with --quick)")
    sub.add_argument("--seed-start", type=integer(0), default=0,
                     help="first seed, ≥ 0 (default 0)")
    sub.add_argument("--duration", type=number(), default=None,
                     help=f"seconds of each scenario to simulate, {MIN_DURATION:g} (one tick "
                          "of the simulation's clock) up to the scenario's length (default: "
                          f"all of it, 480 s; {quick_duration:g} with --quick); shorter runs "
                          "cut a window from the start of the same timeline")
    sub.add_argument("--quick", action="store_true",
                     help=f"a smoke run for trying things: {quick_seeds} seeds of "
                          f"{quick_duration:g} s; --seeds and "
                          "--duration still override it")
    sub.add_argument("--workers", type=integer(1), default=None,
                     help="parallel processes, ≥ 1 (default: one per core)")
    sub.add_argument("--output", default=output,
                     help=f"output folder, created if needed (default ./{output}). Written only "
                          "when every run has finished; a run replaces the files the previous "
                          "run wrote there (listed in its .ctxmodels-outputs.json) and leaves "
                          "other files alone")
    sub.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    sub.add_argument("--quiet", action="store_true", help="no progress bar")
    sub.set_defaults(full_seeds=full_seeds, quick_seeds=quick_seeds, quick_duration=quick_duration)


def parser() -> argparse.ArgumentParser:
    from .cli_sweep import add_sweep_command
    from .experiment.extraction import EXTRACTIONS
    from .experiment.runner import FULL_SEEDS, QUICK_DURATION, QUICK_SEEDS
    from .experiment.scenarios import SCENARIOS, TRUTHS
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
                    "each seed, and scores HOTA and RMS GOSPA at radar timestamps. With no "
                    "options it runs the full study on the calibrated truth (every tracker, "
                    "all 480 s of each scenario, 10 seeds: about 5 min on 2 cores). Prints the "
                    "table (paper Table II layout, mean and 95 % bootstrap interval over "
                    "seeds, the paper's values beside them), the paper's findings as paired "
                    "comparisons with sign, size and non-inferiority verdicts (Holm-adjusted), "
                    "track-management metrics and tracks per radar scan; writes results.md/.csv/.json, findings.md/.json and PNG "
                    "figures to --output.")
    study_options(exp, "results", FULL_SEEDS, QUICK_SEEDS, QUICK_DURATION)
    exp.add_argument("--stock", action="store_true",
                     help="run the trackers' component path (stock Stone Soup components in "
                          "ctxmodels' stock-derived trackers) instead of the array trackers "
                          "(the same tracks to rounding, far slower; for verification)")
    exp.add_argument("--static-as-false", action="store_true",
                     help="count tracks on static sea markers and islets as false tracks "
                          "(default: they are distractors, neither hits nor false tracks)")
    exp.add_argument("--extract", choices=list(EXTRACTIONS), default="stone-soup",
                     help="which GM-PHD states are scored: 'stone-soup' (default) every state "
                          "of every reported track, as Stone Soup's tracker reports them; "
                          "'weight' only states of weight ≥ 0.5")
    sim = exp.add_argument_group(
        "simulated sensors (sensitivity studies: these change the simulated truth only, "
        "never the trackers' models)")
    sim.add_argument("--truth", choices=list(TRUTHS), default="calibrated",
                     help="the simulated truth the options below start from: 'calibrated' "
                          "(default; docs/calibration.md) or 'stress' (radar P_D 0.4, far "
                          "clutter 1e-2 per rad·m, bearing σ 1°, 3 lidar clutter points a "
                          "scan: the trackers' settings copied into the truth)")
    # Bounded so that the simulated scans (drawn up front) cannot exhaust memory.
    sim.add_argument("--radar-clutter", nargs=2, type=number(0, MAX_RADAR_CLUTTER),
                     metavar=("NEAR", "FAR"), default=None,
                     help="mean radar clutter returns per scan inside / beyond 1000 m (default "
                          "4.89 9.45, i.e. 1e-3 and 3e-3 per rad·m; 5 32 is 1e-3 and 1e-2, "
                          "the paper's context-aware λ; 5 3.2 makes the uniform λ = 1e-3 "
                          "true everywhere); each ≥ 0, "
                          f"NEAR + FAR ≤ {MAX_RADAR_CLUTTER:g}")
    sim.add_argument("--lidar-clutter", type=number(0, MAX_LIDAR_CLUTTER), metavar="N",
                     default=None,
                     help="mean lidar clutter segments per scan within 80 m (default 0.3; "
                          f"0–{MAX_LIDAR_CLUTTER:g})")
    sim.add_argument("--radar-bearing-std", type=number(0, MAX_BEARING_STD_DEG, above=True),
                     metavar="DEG", default=None,
                     help=f"radar bearing noise σ in degrees (default 0.5; > 0, ≤ "
                          f"{MAX_BEARING_STD_DEG:g})")
    exp.set_defaults(run=_experiment, check=_check_experiment, error=exp.error)

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
    cov.add_argument("--pose", nargs=3, type=number(-MAX_COORDINATE, MAX_COORDINATE),
                     default=(0.0, 0.0, 90.0),
                     metavar=("X", "Y", "HEADING_DEG"),
                     help="platform pose: metres, metres, degrees counter-clockwise from +x "
                          "(default 0 0 90: facing +y)")
    cov.add_argument("--extent", nargs="+", type=number(0, MAX_COORDINATE, above=True),
                     default=[1800.0, 100.0],
                     help="half-widths of the maps in metres, one row each (default 1800 100)")
    cov.add_argument("--resolution", type=integer(2, MAX_RESOLUTION), default=400,
                     help=f"grid points per side, 2–{MAX_RESOLUTION} (default 400)")
    cov.add_argument("--title", default="", help="figure title")
    cov.add_argument("--output", default="coverage.png",
                     help="PNG file to write (its folder must exist)")
    cov.set_defaults(run=_coverage, check=check_coverage, error=cov.error)

    add_sweep_command(commands)

    lst = commands.add_parser("list", help="list the scenarios and trackers")
    lst.set_defaults(run=_list, check=lambda args: None, error=lst.error)
    return main


def main(argv=None) -> int:
    """Runs a command; returns its exit code. User errors exit with code 2 and a usage
    message (SystemExit) before any work starts; Ctrl-C returns 130 without a traceback."""
    try:
        args = parser().parse_args(argv)
        try:
            args.check(args)
        except UsageError as err:
            args.error(str(err))
        return args.run(args)
    except KeyboardInterrupt:
        print("ctxmodels: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
