"""How long `mst calibrate` takes on a large load test: the wall time of the command on 40,000
samples of the bundled forward design (its own model, 2 uT noise), median of --repeats runs in
fresh processes. Prints a markdown table; asserts nothing. (The hostile-input suite checks that
such a file calibrates with a progress line; its time lives here, as speed goals do.)

    python benchmarks/bench_calibrate.py [--samples 40000] [--repeats 3]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from design_curve import fields_along_curve, mst_exe
from user_env import as_installed

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"


def load_test(path: Path, n: int) -> None:
    """``n`` samples over the design's range, its own field plus 2 uT of noise (seed 2), by force."""
    F, B = fields_along_curve(FORWARD, n, 1.0, 2.0, seed=2)
    order = np.argsort(F)
    rows = "".join(f"{a:.4f},{x:.3f},{y:.3f},{z:.3f}\n" for a, (x, y, z) in zip(F[order], B[order]))
    path.write_text("force_N,Bx_uT,By_uT,Bz_uT\n" + rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=40_000)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    as_installed()
    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp) / "big.csv"
        load_test(data, args.samples)
        times = []
        for i in range(args.repeats):
            cmd = [mst_exe(), "calibrate", str(FORWARD), str(data)]
            t0 = time.perf_counter()
            done = subprocess.run([*cmd, "--out", f"{tmp}/o{i}", "--no-plot"], capture_output=True, text=True)
            times.append(time.perf_counter() - t0)
            if done.returncode != 0:
                sys.exit(done.stderr)
    print(
        f"| samples | runs | median s | min s |\n|---|---|---|---|\n| {args.samples:,} | {args.repeats} | "
        f"{statistics.median(times):.1f} | {min(times):.1f} |"
    )


if __name__ == "__main__":
    main()
