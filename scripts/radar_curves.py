"""The radar equation's P_D against per-pulse SNR for each Swerling case, one pulse and ten
pulses summed, P_FA 1e-6 (docs/figures/radar_pd_curves.png, shown in the guide), with the
textbooks' single-pulse SNRs for P_D 0.9 marked.

    python scripts/radar_curves.py [--output PATH]
"""
import argparse
from pathlib import Path

import numpy as np

from ctxmodels import RadarEquation
from ctxmodels.experiment.canvas import new_figure

ROOT = Path(__file__).resolve().parents[1]
#: Single-pulse SNR (dB) for P_D 0.9 at P_FA 1e-6 in the radar textbooks, per Swerling case.
PUBLISHED = {0: 13.2, 1: 21.1, 2: 21.1, 3: 17.3, 4: 17.3}
COLOURS = ["#000000", "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728"]


def curves(snr_db: np.ndarray, pulses: int, pfa: float = 1e-6) -> dict[int, np.ndarray]:
    """P_D at each SNR (dB) per Swerling case: the SNR set at range 1 m, read there."""
    return {case: np.array([RadarEquation(reference_snr=db, reference_range=1.0,
                                          false_alarm_probability=pfa, swerling=case,
                                          pulses=pulses)([1.0])[0] for db in snr_db])
            for case in range(5)}


def figure():
    snr_db = np.linspace(-5.0, 30.0, 141)
    fig = new_figure(figsize=(10, 4.2), layout="constrained")
    axes = fig.subplots(1, 2, sharey=True)
    for ax, pulses in zip(axes, (1, 10)):
        for case, pd in curves(snr_db, pulses).items():
            ax.plot(snr_db, pd, color=COLOURS[case], lw=1.6,
                    ls="-" if case in (0, 1, 3) else "--", label=f"Swerling {case}")
        if pulses == 1:
            for case, db in PUBLISHED.items():
                if case in (2, 4):
                    continue  # the same points as 1 and 3 with one pulse
                ax.plot([db], [0.9], "o", mfc="none", mec=COLOURS[case], ms=9)
            ax.plot([], [], "o", mfc="none", mec="grey", label="textbook SNR for P_D 0.9")
        ax.set_title("one pulse, P_FA 1e-6" if pulses == 1 else f"{pulses} pulses summed, P_FA 1e-6")
        ax.set_xlabel("per-pulse SNR (dB)")
        ax.grid(alpha=0.3)
        ax.set_xlim(snr_db[0], snr_db[-1])
    axes[0].set_ylabel("P_D")
    axes[0].legend(loc="upper left", fontsize=8)
    return fig


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", type=Path, default=ROOT / "docs" / "figures" / "radar_pd_curves.png")
    args = parser.parse_args()
    figure().savefig(args.output, dpi=110)
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
