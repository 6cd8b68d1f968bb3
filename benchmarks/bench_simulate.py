"""Speed of the forward model (issue: mst simulate). Prints a table; asserts nothing.

    python benchmarks/bench_simulate.py [--repeats N]

* layer evaluations per second of the vectorised L0 spring kernel (goal >= 1e6 / s);
* wall time of `mst simulate` on the three-layer reference design, interpreter start
  included (goal <= 0.8 s median);
* import time of mst_cli.cli.app, and whether it pulled in a heavy module (it must not).
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

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("build123d", "OCP", "skfem", "matplotlib.pyplot", "nlopt")


def l0_rate(n_layers: int, repeats: int) -> tuple[float, float]:
    from mst_cli.model.mechanics.spring import spring_arrays
    rng = np.random.default_rng(0)
    th = np.radians(rng.uniform(15, 60, n_layers))
    t = rng.uniform(0.4, 2.0, n_layers)
    h = rng.uniform(1.2, 6.0, n_layers)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        spring_arrays(th, t, h, t, 4, 30.0, 0.1, 12.0, 0.45)
        times.append(time.perf_counter() - t0)
    med = statistics.median(times)
    return n_layers / med, med


def simulate_wall(repeats: int) -> list[float]:
    exe = Path(sys.executable).with_name("mst")
    cmd = [str(exe) if exe.exists() else "mst", "simulate", str(ROOT / "configs/mohammadi2021-forward.yaml")]
    times = []
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(repeats):
            t0 = time.perf_counter()
            subprocess.run(cmd + ["--out", f"{tmp}/o{i}"], check=True, capture_output=True)
            times.append(time.perf_counter() - t0)
    return times


def import_cost(repeats: int) -> tuple[float, list[str]]:
    code = ("import sys, time; t = time.perf_counter(); import mst_cli.cli.app; "
            "print(time.perf_counter() - t); "
            f"print(','.join(m for m in {HEAVY!r} if m in sys.modules))")
    times, heavy = [], []
    for _ in range(repeats):
        out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
        lines = out.stdout.splitlines()
        times.append(float(lines[0]))
        heavy = [m for m in (lines[1].split(",") if len(lines) > 1 else []) if m]
    return statistics.median(times), heavy


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()

    rate, med = l0_rate(1_000_000, args.repeats)
    sim = simulate_wall(args.repeats)
    imp, heavy = import_cost(args.repeats)
    rows = [
        ("L0 layer evaluations / s (1e6 layers per call)", f"{rate:.3g}", ">= 1e6"),
        ("mst simulate, 3 layers, median wall [s]", f"{statistics.median(sim):.3f}", "<= 0.8"),
        ("mst simulate, min / max wall [s]", f"{min(sim):.3f} / {max(sim):.3f}", ""),
        ("import mst_cli.cli.app, median [s]", f"{imp:.3f}", ""),
        ("heavy modules imported by mst_cli.cli.app", ", ".join(heavy) or "none", "none"),
    ]
    print(f"# bench_simulate ({args.repeats} repeats, {sys.platform}, python {sys.version.split()[0]})")
    print(f"| {'measure':<48} | {'value':>15} | {'goal':>7} |")
    print(f"|{'-' * 50}|{'-' * 17}|{'-' * 9}|")
    for name, value, goal in rows:
        print(f"| {name:<48} | {value:>15} | {goal:>7} |")


if __name__ == "__main__":
    main()
