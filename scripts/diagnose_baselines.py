"""Why the simulated baselines miss the paper's rows (docs/calibration.md, "Why no grid point
fits"): per vessel, how often it lies inside the radar's minimum range or in its blind
sector, and per baseline tracker, its scores broken down (missed and false tracks a scan,
DetA/AssA) under both extraction rules and with static-object tracks counted as false.

    python scripts/diagnose_baselines.py [--seeds 100 101 102] [--truth calibrated]

Prints one line per (scenario, seed, vessel) and per (scenario, tracker, seed, rule).
"""
from __future__ import annotations

import argparse
import math

import numpy as np

from ctxmodels.experiment.calibration import SEEDS
from ctxmodels.experiment.paper import BASELINES, PAPER_SCENARIOS
from ctxmodels.experiment.runner import Job, run_job, simulated_run
from ctxmodels.experiment.scenarios import TRUTHS


def vessel_geometry(run) -> dict:
    """Per vessel id: (fraction of radar scans inside the minimum range, fraction in the
    blind sector, radar scans present)."""
    radar = run.radar
    ego_index = {t: i for i, t in enumerate(run.ego.timestamps)}
    half_blind = radar.blind_sector_width / 2
    out = {}
    for vid, path in sorted(run.truth_by_id.items()):
        states = {state.timestamp: state for state in path}
        inside = blind = present = 0
        for time in run.radar_times:
            state = states.get(time)
            if state is None:
                continue
            i = ego_index[time]
            dx = float(state.state_vector[0]) - run.ego.positions[i][0]
            dy = float(state.state_vector[2]) - run.ego.positions[i][1]
            bearing = math.atan2(dy, dx) - run.ego.headings[i]
            off_astern = abs(bearing % (2 * math.pi) - math.pi)  # |bearing − π|, wrapped
            present += 1
            inside += math.hypot(dx, dy) <= radar.min_range
            blind += off_astern < half_blind
        out[vid] = (inside / max(present, 1), blind / max(present, 1), present)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=list(SEEDS))
    parser.add_argument("--truth", choices=list(TRUTHS), default="calibrated")
    args = parser.parse_args()
    truth = TRUTHS[args.truth]
    for scenario in PAPER_SCENARIOS:
        for seed in args.seeds:
            run = simulated_run(scenario, seed, None, truth.radar, truth.lidar)
            for vid, (inside, blind, present) in vessel_geometry(run).items():
                print(f"{scenario:12s} seed {seed} vessel {vid}: inside min range "
                      f"{inside:.2f}, in blind sector {blind:.2f} of {present} radar scans")
    for scenario in PAPER_SCENARIOS:
        for tracker in BASELINES:
            for seed in args.seeds:
                for label, extract, distractors in (("stone-soup", "stone-soup", True),
                                                    ("weight>=0.5", "weight", True),
                                                    ("static-as-false", "stone-soup", False)):
                    r = run_job(Job(scenario, seed, tracker, radar=truth.radar,
                                    lidar=truth.lidar, extract=extract,
                                    static_distractors=distractors))
                    g = r.gospa
                    print(f"{scenario:12s} {tracker:17s} seed {seed} {label:15s} "
                          f"HOTA {100 * r.hota.hota:5.1f} (DetA {100 * r.hota.deta:5.1f}, "
                          f"AssA {100 * r.hota.assa:5.1f}) GOSPA {g.rms:5.1f} m, missed "
                          f"{np.mean(g.num_missed):.2f} and false {np.mean(g.num_false):.2f} "
                          "a scan", flush=True)


if __name__ == "__main__":
    main()
