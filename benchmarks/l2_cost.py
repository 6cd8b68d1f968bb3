"""What an L2 (continuum) law costs on this tree against another, and what changed. Prints tables; asserts nothing.

    python benchmarks/l2_cost.py --baseline DIR [--samples 48] [--seed 0] [--rounds 3]

DIR holds another version's ``mst_cli`` (e.g. ``mkdir DIR && git archive 188ca9d mst_cli |
tar -x -C DIR``, 0.10.0). Each tree runs in a subprocess of its own with its copy first on
PYTHONPATH, and the two alternate for --rounds rounds, so load on the shared machine hits both.

1. Per law, ``mst bench``'s cells (``sample_cells(48, 0)``), each solved uncached
   (``solve_continuum``): the median time (a cell's best round), the Newton iterations, and
   how far this tree's laws sit from the baseline's: the lock force R and compression d_lock
   (relative), and how many cells name another face as what closed (pad or wall).
2. Per stack, the reference design's three layers (configs/mohammadi2021-forward.yaml) through
   ``layer_laws`` in a fresh process, cold caches (L2's import included), each tree: in turn
   (MST_WORKERS=1) and side by side (the default: a forked worker per core; a baseline before
   0.11 solves in turn either way).
3. One linear solve of a path mesh's tangent block (the first cell's, at rest, in this tree):
   the banded solve L2 uses since 0.11 against SciPy's SuperLU (spsolve, its own column
   ordering every call, as before), median of 200, and their largest relative difference.
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

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"


def child_laws(samples: int, seed: int) -> list[dict]:
    from mst_cli.bench.sampling import sample_cells
    from mst_cli.model.material import Material
    from mst_cli.model.mechanics.continuum import solve_continuum

    rows = []
    for cell in sample_cells(samples, seed):
        t0 = time.perf_counter()
        res = solve_continuum(cell, Material())
        rows.append(
            {"s": time.perf_counter() - t0, "R": float(res.force_N[-1]), "d": res.d_contact_mm}
            | {"it": res.newton_iterations, "at": res.contact_at}
        )
    return rows


def child_stack() -> float:
    from mst_cli.model.mechanics import layer_laws
    from mst_cli.sensor.document import load_document

    doc = load_document(FORWARD)
    geometry = doc.geometry()
    t0 = time.perf_counter()
    layer_laws(geometry.layers, doc.material, "continuum")
    return time.perf_counter() - t0


def block_solve_times(samples: int, seed: int) -> tuple[int, float, float, float]:
    """(unknowns, banded ms, spsolve ms, max relative difference) on the first cell's path mesh."""
    import numpy as np
    from scipy.sparse.linalg import spsolve

    from mst_cli.bench.sampling import sample_cells
    from mst_cli.model.material import Material
    from mst_cli.model.mechanics import continuum

    cell = sample_cells(samples, seed)[0]
    prob = continuum.ContactProblem(cell, Material(), continuum.MeshOptions(levels=0))
    _, K = prob.assemble(np.zeros(prob.basis.N))
    block = prob.free_block()
    rhs = np.random.default_rng(0).standard_normal(block.free.size)

    def median_ms(solve) -> float:
        times = []
        for _ in range(200):
            t0 = time.perf_counter()
            solve()
            times.append(time.perf_counter() - t0)
        return 1e3 * statistics.median(times)

    banded, superlu = block.solve(K, rhs), spsolve(block.csc(K), rhs)
    diff = float(np.abs(banded - superlu).max() / np.abs(superlu).max())
    return block.free.size, median_ms(lambda: block.solve(K, rhs)), median_ms(lambda: spsolve(block.csc(K), rhs)), diff


def run(tree: Path, what: list[str], workers: str | None = None):
    env = {**os.environ, "PYTHONPATH": str(tree)}
    if workers:
        env["MST_WORKERS"] = workers
    out = subprocess.run([sys.executable, __file__, "--child", *what], capture_output=True, text=True, env=env)
    if out.returncode:
        raise SystemExit(f"{tree}: {out.stderr.strip()}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--baseline", type=Path)
    ap.add_argument("--samples", type=int, default=48)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--child", nargs="*", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child is not None:
        print(json.dumps(child_stack() if args.child == ["stack"] else child_laws(*map(int, args.child))))
        return
    if args.baseline is None:
        ap.error("--baseline DIR is required")
    trees = {"this tree": ROOT, "baseline": args.baseline.resolve()}
    laws: dict[str, list] = {name: [] for name in trees}
    stacks: dict[str, list[float]] = {f"{name}, {how}": [] for name in trees for how in ("in turn", "side by side")}
    for _ in range(args.rounds):
        for name, tree in trees.items():
            laws[name].append(run(tree, [str(args.samples), str(args.seed)]))
            stacks[f"{name}, in turn"].append(run(tree, ["stack"], workers="1"))
            stacks[f"{name}, side by side"].append(run(tree, ["stack"]))
    new, old = laws["this tree"][0], laws["baseline"][0]
    best = {name: [min(r[i]["s"] for r in runs) for i in range(args.samples)] for name, runs in laws.items()}
    dR = sorted(abs(a["R"] / b["R"] - 1.0) for a, b in zip(new, old))
    dd = max(abs(a["d"] / b["d"] - 1.0) for a, b in zip(new, old))
    print(f"L2 laws of {args.samples} cells (seed {args.seed}), best of {args.rounds} rounds per cell")
    print("| tree | median ms per law | Newton iterations |\n|---|---|---|")
    for name, runs in laws.items():
        print(f"| {name} | {1e3 * statistics.median(best[name]):.0f} | {sum(r['it'] for r in runs[0])} |")
    ratio = statistics.median(a / b for a, b in zip(best["this tree"], best["baseline"]))
    print(f"median per-cell time ratio (this tree / baseline): {ratio:.2f}")
    print(f"R: max {dR[-1]:.2e}, median {statistics.median(dR):.2e} relative; d_lock: max {dd:.2e} relative")
    print(f"cells naming another face as what closed: {sum(a['at'] != b['at'] for a, b in zip(new, old))}")
    print(f"\nthe reference design's 3 layers, fresh process, median of {args.rounds}")
    print("| run | s |\n|---|---|")
    for name, times in stacks.items():
        print(f"| {name} | {statistics.median(times):.2f} |")
    n, banded_ms, superlu_ms, diff = block_solve_times(args.samples, args.seed)
    print(f"\none tangent block ({n} unknowns): banded {banded_ms:.2f} ms, SuperLU {superlu_ms:.2f} ms (median of 200)")
    print(f"largest relative difference between the two: {diff:.1e}")


if __name__ == "__main__":
    main()
