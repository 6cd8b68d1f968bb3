"""Synthetic files for the benchmarks that time `mst` on them: a design's own fields along its
curve (centred presses), with the chip's noise, and the installed `mst` to run."""

import sys
from pathlib import Path

import numpy as np


def fields_along_curve(design: Path, n: int, top: float, noise_uT: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(forces (n,) in N, uniform over 0 to ``top`` x the range, the fields there (n, 3) in uT plus
    Gaussian noise of ``noise_uT``), from the design's forward model; ``seed`` seeds both draws."""
    from mst_cli.model.response import simulate
    from mst_cli.sensor.document import load_document

    doc = load_document(design)
    resp = simulate(doc.geometry(), doc.material, noise_uT_rms=doc.noise_uT_rms)
    rng = np.random.default_rng(seed)
    F = rng.uniform(0.0, top * resp.max_force_N, n)
    B = np.stack([np.interp(F, resp.force_N, resp.B_T[:, i]) for i in range(3)], -1) * 1e6
    return F, B + rng.normal(0.0, noise_uT, B.shape)


def mst_exe() -> str:
    """The `mst` beside this interpreter (the venv's), else the one on the PATH."""
    exe = Path(sys.executable).with_name("mst")
    return str(exe) if exe.exists() else "mst"
