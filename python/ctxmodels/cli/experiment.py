"""``ctxmodels experiment``: the paper's comparison on the simulated scenarios."""
from __future__ import annotations

import math
import sys

from .options import study_options
from .output import OutputFolder
from .validation import (MAX_BEARING_STD_DEG, MAX_LIDAR_CLUTTER, MAX_RADAR_CLUTTER,
                         UsageError, check_experiment, number)


def add_experiment_command(commands) -> None:
    from ..experiment.extraction import EXTRACTIONS
    from ..experiment.runner import FULL_SEEDS, QUICK_DURATION, QUICK_SEEDS
    from ..experiment.scenarios import TRUTHS
    exp = commands.add_parser(
        "experiment", help="simulate the radar–lidar scenarios and compare the trackers",
        description="Simulates the paper's asynchronous radar (0.8 Hz, 50–1612 m, 65° rear "
                    "blind sector) and lidar (10 Hz, ≤ 80 m) scenarios, runs each tracker "
                    "(JPDA, GM-PHD uniform / radar-only / P_D-aware / context-aware, ...) on "
                    "each seed, and scores HOTA and RMS GOSPA at radar timestamps. With no "
                    "options it runs the full study on the calibrated truth (every tracker, "
                    "all 480 s of each scenario, 10 seeds: about 4 min on 2 cores). Prints the "
                    "table (paper Table II layout, mean and 95 % bootstrap interval over "
                    "seeds, the paper's values beside them), the paper's findings as paired "
                    "comparisons with sign, size and non-inferiority verdicts (Holm-adjusted), "
                    "track-management metrics and tracks per radar scan; writes "
                    "results.md/.csv/.json, findings.md/.json and PNG figures to --output.")
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



def _experiment(args) -> int:
    folder = args.folder
    try:
        return _run_experiment(args, folder)
    except BaseException:
        folder.discard()  # an early Ctrl-C or error leaves no empty output folder behind
        raise


def _run_experiment(args, folder) -> int:
    from ..experiment.runner import ExperimentConfig, run_experiment
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
                    from ..experiment.figures import draw_experiment_figures
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


def _check_experiment(args) -> None:
    check_experiment(args)
    from ..experiment.scenarios import SOLENT
    truth_options = {"--truth": args.truth != "calibrated",
                     "--radar-clutter": args.radar_clutter is not None,
                     "--radar-bearing-std": args.radar_bearing_std is not None,
                     "--lidar-clutter": args.lidar_clutter is not None}
    given = [flag for flag, used in truth_options.items() if used]
    if SOLENT in args.scenarios and given:
        raise UsageError(f"argument {given[0]}: changes the simulated radar and lidar of the "
                         f"paper's scenes, not the Solent's radars (fixed: "
                         f"ctxmodels.experiment.solent.radars); run the Solent apart")
    args.folder = OutputFolder(args.output)  # last: no folder is created for a bad command


def _simulated_sensors(args):
    """The simulation's sensor settings: the named truth changed by the sensitivity options
    (None: the calibrated default)."""
    import dataclasses

    from ..experiment.scenarios import TRUTHS
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
