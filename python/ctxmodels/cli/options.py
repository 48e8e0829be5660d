"""The options ``ctxmodels experiment`` and ``ctxmodels sweep`` share."""
from __future__ import annotations

from .validation import MAX_SEEDS, MIN_DURATION, integer, number


def study_options(sub, output: str, full_seeds: int, quick_seeds: int,
                  quick_duration: float) -> None:
    """The options ``experiment`` and ``sweep`` share: what to run, on how many seeds, where
    the results go."""
    from ..experiment.scenarios import DEFAULT_SCENARIOS, SCENARIOS
    from ..trackers import TRACKERS
    sub.add_argument("--scenarios", nargs="+", default=list(DEFAULT_SCENARIOS),
                     choices=list(SCENARIOS), metavar="NAME",
                     help=f"scenarios to run, of {list(SCENARIOS)} (default: "
                          f"{' '.join(DEFAULT_SCENARIOS)}; solent downloads its shoreline and "
                          f"AIS data once, from the package index)")
    sub.add_argument("--trackers", nargs="+", default=None, metavar="NAME",
                     choices=list(TRACKERS) + ["all"],
                     help="trackers to compare, or 'all' (default: all; `ctxmodels list` "
                          "names them). Trackers "
                          "run only on the scenarios they are made for (gmphd-sight needs "
                          "land: the islands or the Solent; the JPDAs run on the paper's two "
                          "scenarios; the Solent runs five GM-PHDs); a "
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
