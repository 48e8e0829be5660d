"""Calibrates the simulated truth against the paper's baseline rows, as docs/calibration.md
declares: stage 1 (radar, on the radar-only GM-PHD's rows), then stage 2 (lidar clutter, on
the uniform GM-PHD's and the JPDA's). Writes DIR/calibration.json (every grid point's rows
and loss, and the choice) and DIR/calibration.png (the loss over both grids, the fit).

    python scripts/calibrate.py --output DIR [--workers N]     # about 15 min on 2 cores
    python scripts/calibrate.py --redraw DIR                   # the figure from the JSON
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np

from ctxmodels.experiment import calibration
from ctxmodels.experiment.executors import write_json
from ctxmodels.experiment.paper import BASELINES, PAPER_SCENARIOS, TABLE_II


def draw(record: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    grid = calibration.RADAR_GRID
    chosen = record["chosen"]["radar"]
    losses = {tuple(r["point"][k] for k in grid): r["loss"] for r in record["stage1"]}
    finite = [v for v in losses.values() if np.isfinite(v)]
    norm = LogNorm(vmin=max(min(finite), 1e-2), vmax=max(finite))
    near, sigmas = grid["clutter_near"], grid["bearing_std_deg"]
    fig = plt.figure(figsize=(max(12.0, 4.2 * len(near)), 3.4 * len(sigmas) + 4.0),
                     layout="constrained")
    panels = fig.subfigures(2, 1, height_ratios=[3.4 * len(sigmas), 4.0])
    axes = panels[0].subplots(len(sigmas), len(near), squeeze=False, sharex=True, sharey=True)
    for i, sigma in enumerate(sigmas):
        for j, c_near in enumerate(near):
            ax = axes[i][j]
            values = np.array([[losses[(p, c_near, c_far, sigma)] for c_far in grid["clutter_far"]]
                               for p in grid["prob_detection"]])
            image = ax.imshow(values, origin="lower", norm=norm, cmap="viridis_r", aspect="auto")
            ax.set_xticks(range(len(grid["clutter_far"])),
                          [f"{c:g}" for c in grid["clutter_far"]], rotation=30)
            ax.set_yticks(range(len(grid["prob_detection"])),
                          [f"{p:g}" for p in grid["prob_detection"]])
            ax.set_title(f"bearing σ {sigma:g}°, near clutter {c_near:g}", fontsize=9)
            if (c_near, sigma) == (chosen["clutter_near"], chosen["bearing_std_deg"]):
                ax.plot(grid["clutter_far"].index(chosen["clutter_far"]),
                        grid["prob_detection"].index(chosen["prob_detection"]), marker="*",
                        color="red", markersize=14, linestyle="none")
            if j == 0:
                ax.set_ylabel("radar P_D (truth)")
            if i == len(sigmas) - 1:
                ax.set_xlabel("far clutter (truth), per rad·m")
    panels[0].colorbar(image, ax=axes, label="stage-1 loss (radar-only rows)")
    panels[0].suptitle("Stage 1: the radar's truth from the radar-only GM-PHD's rows "
                       "(red star: the chosen point)")
    bottom = panels[1].subplots(1, 2)
    rates = [r["point"]["lidar_clutter_per_scan"] for r in record["stage2"]]
    bottom[0].plot(rates, [r["loss"] for r in record["stage2"]], marker="o", label="stage-2 loss")
    bottom[0].set_xscale("log")
    bottom[0].set_yscale("log")
    bottom[0].set_xticks(rates, [f"{r:g}" for r in rates])
    bottom[0].minorticks_off()
    bottom[0].set_xlabel("lidar clutter (truth), points per scan")
    bottom[0].set_ylabel("loss (uniform GM-PHD and JPDA rows)")
    bottom[0].axvline(record["chosen"]["lidar_clutter_per_scan"], color="red", linestyle="--",
                      label="chosen")
    bottom[0].legend(fontsize=8)
    bottom[0].set_title("Stage 2: the lidar's clutter")
    chosen_row = next(r for r in record["stage2"] if r["point"]["lidar_clutter_per_scan"]
                      == record["chosen"]["lidar_clutter_per_scan"])
    radar_row = next(r for r in record["stage1"] if r["point"] == chosen)
    scores = {**radar_row["scores"], **chosen_row["scores"]}
    short = {"gmphd-radar-only": "radar-only", "gmphd-uniform": "uniform", "jpda": "JPDA",
             "mixed-range": "S1", "formation": "S2"}
    labels = [f"{short[t]}\n{short[s]}" for t in BASELINES for s in PAPER_SCENARIOS]
    simulated = [scores[f"{t}/{s}"]["hota"] for t in BASELINES for s in PAPER_SCENARIOS]
    paper = [TABLE_II[t][s].hota for t in BASELINES for s in PAPER_SCENARIOS]
    x = np.arange(len(labels))
    bottom[1].bar(x - 0.2, paper, 0.4, label="paper (Table II)", color="grey")
    bottom[1].bar(x + 0.2, simulated, 0.4, label="simulated, chosen truth", color="tab:blue")
    for k, t_s in enumerate(f"{t}/{s}" for t in BASELINES for s in PAPER_SCENARIOS):
        t, s = t_s.split("/")
        bottom[1].annotate(f"{scores[t_s]['gospa']:.1f} m\n({TABLE_II[t][s].gospa:.1f})",
                           (k, max(simulated[k], paper[k]) + 2), ha="center", fontsize=7)
    bottom[1].set_xticks(x, labels, fontsize=8)
    bottom[1].set_ylabel("HOTA (%); GOSPA simulated (paper) above")
    bottom[1].set_ylim(0, 125)
    bottom[1].legend(fontsize=8, loc="upper left", ncols=2)
    bottom[1].set_title("Baseline rows at the chosen truth")
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", type=Path)
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--redraw", type=Path, help="draw DIR/calibration.png from its JSON")
    args = parser.parse_args(argv)
    if args.redraw is not None:
        import json
        draw(json.loads((args.redraw / "calibration.json").read_text()),
             args.redraw / "calibration.png")
        return 0
    if args.output is None:
        parser.error("argument --output: required (or --redraw DIR)")
    if args.workers is not None and args.workers < 1:
        parser.error("argument --workers: must be >= 1")
    args.output.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    result = calibration.calibrate(args.workers)
    record = calibration.as_json(result)
    record["seconds"] = time.perf_counter() - started
    write_json(args.output / "calibration.json", record)
    draw(record, args.output / "calibration.png")
    radar, lidar = result.truth()
    print(f"chosen radar: {result.radar} -> clutter per scan near {radar.clutter_per_scan_near:.3g}, "
          f"far {radar.clutter_per_scan_far:.3g}; lidar clutter {result.lidar_clutter:g} per scan "
          f"({record['seconds']:.0f} s)")
    for stage, rows in (("stage 1", result.radar_stage), ("stage 2", result.lidar_stage)):
        print(f"{stage}: within 2 units of the least loss:")
        for row in calibration.near_best(rows):
            print(f"  {row.loss:7.2f}  {row.point}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
