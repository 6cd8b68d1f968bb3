"""Quality and speed of `mst design --pareto` (issue 25). Prints tables; asserts nothing.

    python benchmarks/bench_pareto.py [--count 12] [--specs 10] [--baseline DIR]

For the reference spec configs/mohammadi2021.yaml and ``--specs`` seeded random feasible
three-layer specs (bench_design's), the library call ``pareto_front(doc, count)``: its wall
time and the **hypervolume** of the front it returns, over the three objectives the front
trades (total height, worst force resolution, print robustness; all minimised).

Hypervolume, documented choice: each objective is divided by the chosen design's value
(design.objective's weights; both versions compute it the same way), so the three are unitless
and of order one; the reference point is 1.1 x the worst value of each objective over the
union of the two fronts compared (the usual nadir-plus-margin rule), so a point of either front
counts. A larger hypervolume is a better front (more of the objective space dominated).

``--baseline DIR``: the same specs by the package in DIR (a checkout of another version, e.g.
``git archive f00ed9a | tar -x -C DIR``) in a child process, side by side: time, front size
and hypervolume per spec, and the ratio new / old.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from bench_design import SPEC, docs_from, random_specs, targets_of
from user_env import as_installed


def hypervolume(points: np.ndarray, ref: np.ndarray) -> float:
    """Exact hypervolume dominated by ``points`` (k, 3), minimised, up to ``ref``: the union of
    the boxes [p, ref], by counting the cells of the grid of their coordinates."""
    p = np.asarray(points, dtype=float)
    p = p[np.all(p < ref, axis=1)]
    if len(p) == 0:
        return 0.0
    axes = [np.unique(np.concatenate([p[:, j], [ref[j]]])) for j in range(3)]
    lo = np.stack(np.meshgrid(*(a[:-1] for a in axes), indexing="ij"), axis=-1)  # cell corners
    size = np.prod(np.stack(np.meshgrid(*(np.diff(a) for a in axes), indexing="ij"), axis=-1), axis=-1)
    covered = np.any(np.all(p[:, None, None, None, :] <= lo[None], axis=-1), axis=0)
    return float(np.sum(size[covered]))


def fronts(docs, count: int) -> list[dict]:
    """Per spec: seconds, the chosen design's metrics and the front's metrics (k, 3)."""
    from mst_cli.design.pareto import pareto_front

    rows = []
    for doc in docs:
        t0 = time.perf_counter()
        chosen, front = pareto_front(doc, count)
        seconds = time.perf_counter() - t0
        chosen_metrics = [p.metrics.tolist() for p in front if p.chosen]
        rows.append(
            {
                "seconds": seconds,
                "status": chosen.status,
                "chosen": chosen_metrics[0] if chosen_metrics else None,
                "front": [p.metrics.tolist() for p in front],
            }
        )
    return rows


def baseline_rows(directory: Path, docs, count: int) -> list[dict]:
    env = dict(os.environ, PYTHONPATH=str(directory))
    out = subprocess.run(
        [sys.executable, __file__, "--worker", str(count)],
        env=env,
        input=json.dumps(targets_of(docs)),
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout)


def compare(new: dict, old: dict) -> tuple[float, float]:
    """(hypervolume of new, of old) with the documented normalisation and reference point."""
    scale = np.asarray(new["chosen"] or old["chosen"], dtype=float)
    a, b = np.asarray(new["front"]) / scale, np.asarray(old["front"]) / scale
    ref = 1.1 * np.max(np.concatenate([a, b]), axis=0)
    return hypervolume(a, ref), hypervolume(b, ref)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--count", type=int, default=12, help="designs asked of the front (--pareto N)")
    ap.add_argument("--specs", type=int, default=10, help="random feasible three-layer specs")
    ap.add_argument("--baseline", type=Path, default=None, help="a checkout of another version to compare")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    args = ap.parse_args()
    as_installed()
    if args.worker:  # child of --baseline: targets on stdin, rows as JSON on stdout
        print(json.dumps(fronts(docs_from(json.load(sys.stdin)), int(args.worker))))
        return

    from mst_cli.sensor.document import load_document

    docs = [load_document(SPEC)] + random_specs(3, args.specs, seed=2500)
    names = ["reference"] + [f"random-{k:02d}" for k in range(args.specs)]
    new = fronts(docs, args.count)
    old = baseline_rows(args.baseline.resolve(), docs, args.count) if args.baseline else None
    print(
        f"# bench_pareto: pareto_front(doc, {args.count}), library call, {sys.platform}, "
        f"python {sys.version.split()[0]}; hypervolume on objectives / chosen design, "
        "reference 1.1 x the worst of both fronts"
    )
    head = f"| {'spec':<10} | {'new s':>6} | {'new pts':>7} |"
    if old:
        head += f" {'old s':>6} | {'old pts':>7} | {'HV new':>8} | {'HV old':>8} | {'HV new/old - 1':>14} |"
    print(head)
    print("|" + "|".join("-" * (len(c)) for c in head.split("|")[1:-1]) + "|")
    ratios = []
    for k, name in enumerate(names):
        n = new[k]
        line = f"| {name:<10} | {n['seconds']:>6.2f} | {len(n['front']):>7} |"
        if old:
            o = old[k]
            if n["front"] and o["front"]:
                hv_new, hv_old = compare(n, o)
                ratios.append(hv_new / hv_old if hv_old else float("nan"))
                hv = f" {hv_new:>8.4f} | {hv_old:>8.4f} | {ratios[-1] - 1.0:>+14.1e} |"
            else:
                hv = f" {'-':>8} | {'-':>8} | {'-':>14} |"
            line += f" {o['seconds']:>6.2f} | {len(o['front']):>7} |" + hv
        print(line, flush=True)
    print()
    print(
        f"median seconds: new {statistics.median(r['seconds'] for r in new):.2f}"
        + (f", old {statistics.median(r['seconds'] for r in old):.2f}" if old else "")
    )
    if ratios:
        print(
            f"hypervolume new / old - 1: median {statistics.median(ratios) - 1:+.1e}, "
            f"min {min(ratios) - 1:+.1e}, max {max(ratios) - 1:+.1e}; specs with new >= old: "
            f"{sum(r >= 1.0 for r in ratios)}/{len(ratios)}, within 1e-6 of old or above: "
            f"{sum(r >= 1.0 - 1e-6 for r in ratios)}/{len(ratios)}"
        )


if __name__ == "__main__":
    main()
