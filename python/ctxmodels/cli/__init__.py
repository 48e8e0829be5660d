"""The command line: ``ctxmodels experiment`` (the paper's comparison), ``ctxmodels sweep``
(its findings over a grid of simulated settings), ``ctxmodels coverage`` (a sensor model's
P_D map) and ``ctxmodels list``. ``ctxmodels <command> --help`` explains every option.
Each command is a module here; :mod:`.validation` checks the arguments before any work."""
from __future__ import annotations

import argparse
import sys

from .validation import UsageError


def parser() -> argparse.ArgumentParser:
    from .coverage import add_coverage_command
    from .experiment import add_experiment_command
    from .sweep import add_sweep_command
    main = argparse.ArgumentParser(
        prog="ctxmodels",
        description="Context-aware sensor models for Stone Soup trackers: run the paper's "
                    "radar–lidar comparison or draw a sensor's detection-probability map.")
    commands = main.add_subparsers(dest="command", required=True)
    add_experiment_command(commands)
    add_coverage_command(commands)
    add_sweep_command(commands)
    lst = commands.add_parser("list", help="list the scenarios and trackers")
    lst.set_defaults(run=_list, check=lambda args: None, error=lst.error)
    return main


def _list(args) -> int:
    from ..experiment.scenarios import SCENARIOS
    from ..trackers import TRACKERS
    print("scenarios:")
    for name, spec in SCENARIOS.items():
        print(f"  {name:14s} {getattr(spec, 'description', '')}".rstrip())
    print("trackers:")
    width = max(map(len, TRACKERS))
    for name, spec in TRACKERS.items():
        print(f"  {name:{width}s} {spec.label}: {spec.description}")
    return 0


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
