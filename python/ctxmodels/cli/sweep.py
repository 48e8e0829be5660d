"""``ctxmodels sweep``: the findings over a grid of simulated-sensor settings (see
:mod:`ctxmodels.experiment.sweep`)."""
from __future__ import annotations

import sys

from .options import study_options
from .output import OutputFolder
from .validation import (MAX_BEARING_STD_DEG, MAX_LIDAR_CLUTTER, UsageError, check_experiment,
                         number)

#: The largest far clutter density (per rad·m): the calibrated near clutter plus this much
#: beyond 1000 m stays within MAX_RADAR_CLUTTER returns a scan (scans are drawn up front).
MAX_FAR_DENSITY = 0.3

#: ``--quick``: a smoke run of the whole grid.
QUICK_SEEDS, QUICK_DURATION = 2, 30.0


def add_sweep_command(commands) -> None:
    from ..experiment.sweep import (DEFAULT_BEARING_STD_DEG, DEFAULT_FAR_CLUTTER,
                                   DEFAULT_LIDAR_CLUTTER, DEFAULT_RADAR_PD, SWEEP_SEEDS)
    sweep = commands.add_parser(
        "sweep", help="the findings over a grid of simulated radar and lidar settings",
        description="Runs the experiment's study once per simulated-sensor setting around "
                    "the calibrated truth: a radar map (true P_D × far clutter), a bearing "
                    "line and a lidar line (the other values calibrated), and the 'stress' "
                    "truth. The trackers never change; only the simulated truth does. Writes "
                    "sweep.md/.json and one heatmap per finding and map (paired ΔHOTA; cells "
                    "whose 95 % interval excludes 0 framed). The default grid is 13 studies "
                    "of 5 seeds.")
    study_options(sweep, "sweep", SWEEP_SEEDS, QUICK_SEEDS, QUICK_DURATION)
    grid = sweep.add_argument_group("grid (simulated truth only)")
    grid.add_argument("--radar-pd", nargs="+", type=number(0, 1, above=True),
                      default=list(DEFAULT_RADAR_PD), metavar="P",
                      help="the radar's true P_D, in (0, 1] (default 0.4 0.7 0.9: the "
                           "trackers' 0.4, the calibrated 0.7, a high one)")
    grid.add_argument("--radar-far-clutter", nargs="+", type=number(0, MAX_FAR_DENSITY),
                      default=list(DEFAULT_FAR_CLUTTER), metavar="DENSITY",
                      help="radar clutter per rad·m beyond 1000 m (default 1e-3 3e-3 1e-2: the "
                           "uniform λ, the calibrated value, the paper's context λ), "
                           f"≤ {MAX_FAR_DENSITY:g}")
    grid.add_argument("--radar-bearing-std", nargs="+",
                      type=number(0, MAX_BEARING_STD_DEG, above=True),
                      default=list(DEFAULT_BEARING_STD_DEG), metavar="DEG",
                      help="radar bearing noise σ in degrees (default 0.5 1)")
    grid.add_argument("--lidar-clutter", nargs="+", type=number(0, MAX_LIDAR_CLUTTER),
                      default=list(DEFAULT_LIDAR_CLUTTER), metavar="N",
                      help="lidar clutter points per scan within 80 m (default 0.3 3 10)")
    grid.add_argument("--no-stress", action="store_true",
                      help="leave out the 'stress' truth's cell")
    sweep.set_defaults(run=_sweep, check=_check_sweep, error=sweep.error)


def _check_sweep(args) -> None:
    from ..experiment.scenarios import SOLENT
    if SOLENT in args.scenarios:
        raise UsageError("argument --scenarios: the sweep varies the simulated radar and lidar "
                         "of the paper's scenes; the Solent's radars are fixed (run it with "
                         "ctxmodels experiment)")
    check_experiment(args)
    args.folder = OutputFolder(args.output)  # last: no folder is created for a bad command


def _sweep(args) -> int:
    from ..experiment.runner import ExperimentConfig
    from ..experiment.sweep import SweepConfig, run_sweep
    folder = args.folder
    base = ExperimentConfig(scenarios=args.scenarios, trackers=args.trackers,
                            seeds=list(range(args.seed_start, args.seed_start + args.seeds)),
                            duration=args.duration, workers=args.workers, plot_seed=None)
    config = SweepConfig(base, tuple(dict.fromkeys(args.radar_pd)),
                         tuple(dict.fromkeys(args.radar_far_clutter)),
                         tuple(dict.fromkeys(args.radar_bearing_std)),
                         tuple(dict.fromkeys(args.lidar_clutter)), stress=not args.no_stress)
    cells = config.cells()
    runs = sum(len(config.experiment(c).jobs()) for c in cells)
    print(f"ctxmodels sweep: {len(cells)} settings, {runs} runs", file=sys.stderr)
    try:
        results = run_sweep(config, progress=not args.quiet)
        print(results.markdown())
        with folder.staging() as stage:
            staged = results.save(stage, plots=not args.no_plots)
            folder.commit(stage)
    except KeyboardInterrupt:
        folder.discard()
        print(f"ctxmodels sweep: interrupted; nothing written to {folder.path}", file=sys.stderr)
        return 130
    except OSError as err:
        folder.discard()
        print(f"ctxmodels sweep: cannot write to {folder.path}: {err}", file=sys.stderr)
        return 1
    except BaseException:
        folder.discard()
        raise
    print(f"\nctxmodels sweep: {len(cells)} settings, wall time {results.wall_seconds:.0f} s; "
          f"wrote {len(staged)} files to {folder.path}", file=sys.stderr)
    return 0
