"""``ctxmodels sweep``: the findings over a grid of simulated-sensor settings (see
:mod:`ctxmodels.experiment.sweep`)."""
from __future__ import annotations

import sys

from .cli_validation import (MAX_BEARING_STD_DEG, MAX_LIDAR_CLUTTER, MAX_RADAR_CLUTTER,
                             UsageError, check_experiment, number)

#: ``--quick``: a smoke run of the whole grid.
QUICK_SEEDS, QUICK_DURATION = 2, 30.0


def add_sweep_command(commands) -> None:
    from .cli import study_options
    from .experiment.sweep import (DEFAULT_BEARING_STD_DEG, DEFAULT_FAR_CLUTTER,
                                   DEFAULT_LIDAR_CLUTTER, SWEEP_SEEDS)
    sweep = commands.add_parser(
        "sweep", help="the findings over a grid of simulated radar and lidar settings",
        description="Runs the experiment's study once per simulated-sensor setting: a radar "
                    "map (far clutter × bearing noise, lidar at its default) and a lidar line "
                    "(clutter rate, radar at its default). The trackers never change; only the "
                    "simulated truth does. Writes sweep.md/.json and one heatmap per finding "
                    "and map (paired ΔHOTA; cells whose 95 % interval excludes 0 framed). The "
                    "default grid is 11 studies of 5 seeds: about 11 × 2.5 min on 2 cores.")
    study_options(sweep, "sweep", SWEEP_SEEDS, QUICK_SEEDS, QUICK_DURATION)
    grid = sweep.add_argument_group("grid (simulated truth only)")
    grid.add_argument("--radar-far-clutter", nargs="+", type=number(0, MAX_RADAR_CLUTTER),
                      default=list(DEFAULT_FAR_CLUTTER), metavar="N",
                      help="radar clutter returns per scan beyond 1000 m (default 3.2 10 32: "
                           "the uniform λ 1e-3, between, the paper's context λ 1e-2 per rad·m)")
    grid.add_argument("--radar-bearing-std", nargs="+",
                      type=number(0, MAX_BEARING_STD_DEG, above=True),
                      default=list(DEFAULT_BEARING_STD_DEG), metavar="DEG",
                      help="radar bearing noise σ in degrees (default 0.3 0.6 1)")
    grid.add_argument("--lidar-clutter", nargs="+", type=number(0, MAX_LIDAR_CLUTTER),
                      default=list(DEFAULT_LIDAR_CLUTTER), metavar="N",
                      help="lidar clutter segments per scan within 80 m (default 0 3 10)")
    sweep.set_defaults(run=_sweep, check=_check_sweep, error=sweep.error)


def _check_sweep(args) -> None:
    from .cli import OutputFolder
    check_experiment(args)
    near = 5.0  # the radar's default near clutter stays
    if max(args.radar_far_clutter) + near > MAX_RADAR_CLUTTER:
        raise UsageError(f"argument --radar-far-clutter: near (5) + far must be ≤ "
                         f"{MAX_RADAR_CLUTTER:g} per scan")
    args.folder = OutputFolder(args.output)  # last: no folder is created for a bad command


def _sweep(args) -> int:
    from .experiment.runner import ExperimentConfig
    from .experiment.sweep import SweepConfig, run_sweep
    folder = args.folder
    base = ExperimentConfig(scenarios=args.scenarios, trackers=args.trackers,
                            seeds=list(range(args.seed_start, args.seed_start + args.seeds)),
                            duration=args.duration, workers=args.workers, plot_seed=None)
    config = SweepConfig(base, tuple(dict.fromkeys(args.radar_far_clutter)),
                         tuple(dict.fromkeys(args.radar_bearing_std)),
                         tuple(dict.fromkeys(args.lidar_clutter)))
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
