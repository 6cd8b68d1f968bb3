"""A table built once per model (issue 45): ``mst read --estimate shear`` (or offset) of a design
without a calibration, called again and again with another ``--out`` each time. The first call
builds the table and keeps it in the cache (``MST_CACHE_DIR``, a fresh folder here); the later
calls find it by its hash. Prints each call's wall time, whether it built, and the ratio of the
median later call to the first.

    python benchmarks/bench_table_cache.py [--readings 2000] [--calls 3] [--estimate shear]
"""

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from design_curve import fields_along_curve, mst_exe
from user_env import as_installed

ROOT = Path(__file__).resolve().parents[1]
DESIGN = ROOT / "configs" / "mohammadi2021-forward.yaml"


def readings(path: Path, n: int) -> None:
    """``n`` readings along the design's curve (the field of centred presses, 1 uT of noise)."""
    _, B = fields_along_curve(DESIGN, n, 0.9, 1.0, seed=1)
    path.write_text("Bx_uT,By_uT,Bz_uT\n" + "".join(f"{x:.3f},{y:.3f},{z:.3f}\n" for x, y, z in B))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--readings", type=int, default=2000)
    ap.add_argument("--calls", type=int, default=3)
    ap.add_argument("--estimate", choices=("shear", "offset"), default="shear")
    args = ap.parse_args()
    as_installed()
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        os.environ["MST_CACHE_DIR"] = str(d / "cache")
        readings(d / "r.csv", args.readings)
        print(f"mst read {DESIGN.name} ({args.readings} readings) --estimate {args.estimate} --out <each call its own>")
        print(f"{'call':>4}  {'seconds':>8}  table")
        times = []
        for call in range(args.calls):
            cmd = [mst_exe(), "read", str(DESIGN), str(d / "r.csv")]
            cmd += ["--estimate", args.estimate, "--out", str(d / f"out{call}")]
            t0 = time.perf_counter()
            p = subprocess.run(cmd, capture_output=True, text=True)
            times.append(time.perf_counter() - t0)
            if p.returncode != 0:
                sys.exit(f"call {call + 1} failed: {p.stderr.strip()}")
            what = "built and kept" if "built the" in p.stderr else "reused from the cache"
            print(f"{call + 1:>4}  {times[-1]:8.2f}  {what}")
        if len(times) > 1:
            later = statistics.median(times[1:])
            print(f"median later call {later:.2f} s = {later / times[0]:.3f} x the first")


if __name__ == "__main__":
    main()
