"""The tuned JPDA's search, as docs/jpda_baselines.md declares it: every setting of
``ctxmodels.experiment.jpda_tuning.GRID`` on the calibration seeds at the calibrated truth.
Writes DIR/jpda_tuning.json (each setting's HOTA and GOSPA per scenario, and the choice)
and prints the table.

    python scripts/tune_jpda.py --output DIR [--workers N]
"""
import argparse
import dataclasses
import sys
import time
from pathlib import Path

from ctxmodels.experiment import jpda_tuning
from ctxmodels.experiment.executors import write_json


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", required=True, type=Path)
    parser.add_argument("--workers", type=int, default=None)
    args = parser.parse_args()
    if args.workers is not None and args.workers < 1:
        parser.error("argument --workers: must be ≥ 1")
    args.output.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    summary = jpda_tuning.search(args.workers)
    chosen = jpda_tuning.choose(summary)
    seconds = time.perf_counter() - started
    print("| M | T_init (s) | T_del (s) | S1 HOTA / GOSPA | S2 HOTA / GOSPA | mean HOTA | mean GOSPA |")
    print("|---|---|---|---|---|---|---|")
    for r in summary:
        s = r.setting
        cells = " | ".join(f"{h:.1f} / {g:.1f}" for h, g in r.per_scenario.values())
        mark = " **chosen**" if r is chosen else ""
        print(f"| {s.min_points} | {s.confirm_window:g} | {s.delete_window:g} | {cells} | "
              f"{r.hota:.1f}{mark} | {r.gospa:.1f} |")
    write_json(args.output / "jpda_tuning.json", {
        "grid": {k: list(v) for k, v in jpda_tuning.GRID.items()},
        "seeds": list(jpda_tuning.SEEDS),
        "settings": [{**dataclasses.asdict(r.setting), "hota": r.hota, "gospa": r.gospa,
                      "per_scenario": {k: list(v) for k, v in r.per_scenario.items()}}
                     for r in summary],
        "chosen": dataclasses.asdict(chosen.setting), "seconds": seconds})
    print(f"\n{len(summary)} settings in {seconds:.0f} s; wrote {args.output / 'jpda_tuning.json'}",
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
