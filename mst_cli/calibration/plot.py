"""``calibration.png``: the load test against the design's and the calibrated curves, and the
residuals against the chip's noise. matplotlib is imported inside (about 0.45 s): a run with
``--no-plot`` never pays for it."""

from __future__ import annotations

from pathlib import Path

import numpy as np

BRANCH_COLOURS = {"loading": "C0", "unloading": "C1", "hold": "C2", "load test": "k"}


def plot_calibration(
    path: Path,
    F: np.ndarray,
    B_meas_T: np.ndarray,
    design_model: tuple[np.ndarray, np.ndarray],
    cal_model: tuple[np.ndarray, np.ndarray],
    residual_T: np.ndarray,
    sigma_T: float,
    title: str,
    branch: np.ndarray | None = None,
) -> None:
    """Measured |B| against force with the design's and the calibrated curves; residuals. With
    ``branch`` (loading / unloading / hold per row) each branch in its own colour."""
    from matplotlib.figure import Figure  # deferred: matplotlib is 0.45 s; --no-plot never imports it

    fig = Figure(figsize=(10, 4.2))
    ax1, ax2 = fig.subplots(1, 2)
    fig.subplots_adjust(left=0.08, right=0.98, bottom=0.12, top=0.9, wspace=0.25)
    labels = np.full(len(F), "load test", dtype=object) if branch is None else np.asarray(branch, dtype=object)
    for name in dict.fromkeys(labels):
        rows = labels == name
        ax1.plot(F[rows], B_meas_T[rows] * 1e3, ".", color=BRANCH_COLOURS.get(name, "k"), ms=4, label=name)
    for (Fm, Bm), label, style in ((design_model, "design", "C3--"), (cal_model, "calibrated", "C0-")):
        ax1.plot(Fm, Bm * 1e3, style, label=label)
    ax1.set_xlabel("force F [N]")
    ax1.set_ylabel("|B| at the chip [mT]")
    ax1.legend(loc="upper left")
    ax1.grid(alpha=0.3)
    ax2.axhspan(-2 * sigma_T * 1e6, 2 * sigma_T * 1e6, color="C0", alpha=0.12, label="+-2 sigma noise")
    for name in dict.fromkeys(labels):
        rows = labels == name
        ax2.plot(
            F[rows],
            residual_T[rows] * 1e6,
            ".",
            color=BRANCH_COLOURS.get(name, "C0"),
            label=f"{name}: measured - calibrated",
        )
    ax2.set_xlabel("force F [N]")
    ax2.set_ylabel("residual |B| [uT]")
    ax2.legend(loc="upper left", fontsize=8)
    ax2.grid(alpha=0.3)
    fig.suptitle(title)
    fig.savefig(path, dpi=110, format="png")
