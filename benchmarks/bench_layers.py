"""Cost of the layer count (issue 14): simulate and design for 1, 3, 6 and 12 layers, and what
the physics allows past the schema's cap.

    python benchmarks/bench_layers.py [--repeats N] [--design-repeats N] [--command-repeats N]

Every time is a median of its repeats in this one run; every ratio is to the 3-layer time of
the same row kind (the goal: 12 layers at most 2x 3 layers, simulate and design).

* ``simulate``: the library call :func:`mst_cli.model.response.simulate` (L0 spring, exact
  axial field) and the command ``mst simulate --no-plot`` (interpreter start included);
* ``design``: :func:`mst_cli.design.design_document` (L0, seed 0) and ``mst design --no-plot
  --quiet``, on a spec whose targets are the S_i and R_i of a printable n-layer design
  simulated first, so every spec is reachable.

The file schema allows up to 12 layers (``MAX_LAYERS``); the command rows run the command
in-process in a fresh interpreter with the cap lifted for that process only, so ``--layers``
may go past it. The synthetic designs run from soft to stiff (t 0.45 -> 1.6 mm,
theta 20 -> 40 deg, cavity 0.8 mm), so the layers lock bottom to top with more than the
design's 10 % lock margin.

The last table answers "does the physics allow 12 layers": for each count, the shortest
stack of printable cells (cell rules, t/L inside L0's fitted range, h <= 8 mm) that locks
bottom to top with the 10 % margin from 0.5 N up, found greedily on a 1 deg x 0.02 mm x
0.02 mm grid, simulated with the reference magnet (6 x 2 mm N42) on the default board.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import yaml
from user_env import as_installed

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "configs" / "mohammadi2021.yaml"
BASELINE_LAYERS = 3
FIRST_LOCK_N = 0.5  # the softest layer of the shortest stacks locks at or above this
RUN_UNCAPPED = (
    "import sys\nimport mst_cli.sensor.document as schema\n"
    "schema.MAX_LAYERS = max(schema.MAX_LAYERS, 12)   # this process only\n"
    "from mst_cli.cli.app import main\nsys.argv[0] = 'mst'\nmain()\n"
)


def synthetic_layers(n: int) -> list[tuple[float, float, float]]:
    """(theta_deg, t_mm, h_mm) of n printable layers, softest at the bottom."""
    x = np.linspace(0.0, 1.0, n) if n > 1 else np.array([0.5])
    t = 0.45 * (1.6 / 0.45) ** x  # geometric: k ~ (t/L)^3 rises evenly in log
    theta = 20.0 + 20.0 * x
    h = 2.0 * t + 0.8  # cavity 0.8 mm: two nozzles, stroke 0.7 mm
    return [(round(float(a), 3), round(float(b), 3), round(float(c), 3)) for a, b, c in zip(theta, t, h)]


def build(n: int):
    """(spec document, geometry, response) for n layers; the spec's targets are the design's S, R."""
    from mst_cli.model.response import simulate
    from mst_cli.sensor.document import load_document
    from mst_cli.sensor.sections import LayerEntry

    base = load_document(SPEC)
    cells = tuple(base.family.cell(*layer) for layer in synthetic_layers(n))
    geometry = base.geometry(cells)
    bad = geometry.violations(base.printer)
    if bad:
        raise SystemExit(f"synthetic {n}-layer design breaks a cell rule: layer {bad[0][0] + 1} {bad[0][1]}")
    resp = simulate(geometry, base.material, noise_uT_rms=base.noise_uT_rms)
    order = [r.layer for r in resp.regimes]
    if order != list(range(1, n + 1)):
        raise SystemExit(f"synthetic {n}-layer design locks in order {order}, not bottom to top")
    layers = tuple(
        LayerEntry(target_sensitivity_per_N=r.sensitivity_secant_per_N, target_range_N=r.force_to_N)
        for r in resp.regimes
    )
    return replace(base, name=f"synthetic-{n}", layers=layers), geometry, resp


def write_files(n: int, resp, folder: Path) -> tuple[Path, Path]:
    """design-n.yaml and spec-n.yaml for the commands (the reference spec's other sections)."""
    raw = yaml.safe_load(SPEC.read_text())
    design, spec = dict(raw, name=f"design-{n}"), dict(raw, name=f"spec-{n}")
    design["layers"] = [{"theta_deg": a, "t_mm": b, "h_mm": c} for a, b, c in synthetic_layers(n)]
    spec["layers"] = [
        {"target_sensitivity_per_N": float(r.sensitivity_secant_per_N), "target_range_N": float(r.force_to_N)}
        for r in resp.regimes
    ]
    paths = folder / f"design-{n}.yaml", folder / f"spec-{n}.yaml"
    for path, data in zip(paths, (design, spec)):
        path.write_text(yaml.safe_dump(data, sort_keys=False))
    return paths


def median_time(fn, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def command_times(argvs: dict, repeats: int) -> dict:
    """Median wall time of each command, run round-robin so shared-machine load hits all alike."""
    times = {key: [] for key in argvs}
    for i in range(-1, repeats):  # round -1 warms the caches, not counted
        for key, argv in argvs.items():
            t0 = time.perf_counter()
            subprocess.run(
                [sys.executable, "-c", RUN_UNCAPPED, *[a.replace("{i}", str(i + 1)) for a in argv]],
                check=True,
                capture_output=True,
            )
            if i >= 0:
                times[key].append(time.perf_counter() - t0)
    return {key: statistics.median(ts) for key, ts in times.items()}


def shortest_stacks(counts):
    """Per count: (geometry, response) of the shortest printable stack that locks in file order
    with the design's lock margin (greedy: each layer the shortest cell that locks late enough)."""
    from mst_cli.model.cell import cell_margins_mm, wall_centreline_length_mm
    from mst_cli.model.mechanics import correction
    from mst_cli.model.mechanics.spring import spring_arrays
    from mst_cli.model.response import simulate
    from mst_cli.sensor.document import load_document

    base = load_document(SPEC)
    fam, pr, mat = base.family, base.printer, base.material
    margin = 1.0 + base.design["lock_margin_rel"]
    th, t, cav = np.meshgrid(
        np.radians(np.arange(5.0, 75.01, 1.0)), np.arange(0.4, 3.001, 0.02), np.arange(0.4, 4.001, 0.02), indexing="ij"
    )
    h = 2.0 * t + cav
    ok = (
        cell_margins_mm(th, t, h, fam.width_mm, fam.contact_allowance_mm, pr.min_wall_mm, pr.min_gap_mm, pr.nozzle_mm)
        >= 0
    ).all(-1)
    ok &= (h <= 8.0) & (t / wall_centreline_length_mm(th, t, h) <= correction.fitted_t_over_L_max())
    th, t, h = th[ok], t[ok], h[ok]
    R = spring_arrays(
        th, t, h, fam.depth_mm, fam.width_mm, fam.contact_allowance_mm, mat.youngs_modulus_MPa, mat.poisson_ratio
    )[2]
    out = {}
    for n in counts:
        cells, need = [], FIRST_LOCK_N
        for _ in range(n):
            j = np.flatnonzero(R >= need)
            j = j[np.lexsort((R[j], h[j]))[0]]  # shortest, then the softest of those
            cells.append(fam.cell(float(np.degrees(th[j])), float(t[j]), float(h[j])))
            need = margin * R[j]
        geometry = base.geometry(tuple(cells))
        out[n] = geometry, simulate(geometry, mat, noise_uT_rms=base.noise_uT_rms)
    return out, int(ok.sum())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=21, help="repeats of each simulate library call")
    ap.add_argument("--design-repeats", type=int, default=3, help="repeats of each design library call")
    ap.add_argument("--command-repeats", type=int, default=5, help="rounds of the commands")
    ap.add_argument("--layers", default="1,3,6,12")
    args = ap.parse_args()
    as_installed()  # commands start from bytecode, as an installed copy does
    counts = sorted(set([int(v) for v in args.layers.split(",")] + [BASELINE_LAYERS]))

    from mst_cli.design import design_document
    from mst_cli.model.chip import SATURATION_T
    from mst_cli.model.response import simulate

    rows, argvs = {}, {}
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        for n in counts:
            spec, geometry, resp = build(n)
            simulate(geometry, spec.material)  # warm the imports and caches
            sim_s = median_time(lambda g=geometry, m=spec.material: simulate(g, m), args.repeats)
            results = []
            design_s = median_time(
                lambda s=spec, out=results: out.append(design_document(s, seed=0)), args.design_repeats
            )
            res = results[-1]
            worst = max(max(abs(t["sensitivity_error_rel"]), abs(t["range_error_rel"])) for t in res.targets)
            rows[n] = dict(
                sim_s=sim_s,
                design_s=design_s,
                status=res.exit_code,
                worst=worst,
                evaluations=res.evaluations,
                samples=len(resp.force_N),
            )
            design_file, spec_file = write_files(n, resp, tmp)
            argvs[("simulate", n)] = ["simulate", str(design_file), "--out", f"{tmp}/s{n}-{{i}}", "--no-plot"]
            argvs[("design", n)] = ["design", str(spec_file), "--out", f"{tmp}/d{n}-{{i}}", "--no-plot", "--quiet"]
        cmd = command_times(argvs, args.command_repeats)
    stacks, printable = shortest_stacks(counts + [7, 8, 10])

    b = rows[BASELINE_LAYERS]
    cb = {kind: cmd[(kind, BASELINE_LAYERS)] for kind in ("simulate", "design")}
    print(
        f"# bench_layers ({args.repeats} simulate / {args.design_repeats} design library repeats, "
        f"{args.command_repeats} command rounds; {sys.platform}, python {sys.version.split()[0]})"
    )
    print(
        "| layers | force samples | simulate() [ms] | x 3 | mst simulate --no-plot [s] | x 3 "
        "| design_document() [s] | x 3 | mst design --no-plot [s] | x 3 | design: exit, worst miss, evaluations |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for n, r in rows.items():
        cs, cd = cmd[("simulate", n)], cmd[("design", n)]
        print(
            f"| {n} | {r['samples']} | {r['sim_s'] * 1e3:.2f} | {r['sim_s'] / b['sim_s']:.2f} "
            f"| {cs:.3f} | {cs / cb['simulate']:.2f} | {r['design_s']:.3f} | {r['design_s'] / b['design_s']:.2f} "
            f"| {cd:.3f} | {cd / cb['design']:.2f} | {r['status']}, {100 * r['worst']:.2f} %, {r['evaluations']} |"
        )
    print("goal: the 12-layer row at most 2x the 3-layer row (x 3 <= 2)")
    print()
    print(
        f"Shortest printable stacks that lock in file order with the 10 % margin, from {FIRST_LOCK_N:g} N "
        f"({printable} printable cells on the grid); Ø6 x 2 mm N42, default board:"
    )
    print(
        "| layers | part height [mm] | gap0 -> at last lock [mm] | B0 [mT] | B at last lock [mT] "
        "| last lock [N] | S first..last [1/N] | worst dF [mN] |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for n, (g, resp) in sorted(stacks.items()):
        S = [r.sensitivity_secant_per_N for r in resp.regimes]
        dF = max(r.force_resolution_N for r in resp.regimes) * 1e3
        locks_in_order = [r.layer for r in resp.regimes] == list(range(1, n + 1))
        print(
            f"| {n} | {g.total_height_mm:.2f} | {g.gap0_mm:.2f} -> {resp.gap_min_mm:.2f} | {resp.B0_T * 1e3:.3f} "
            f"| {resp.B_full_T * 1e3:.3f} (limit {0.9 * SATURATION_T * 1e3:.0f}) | {resp.max_force_N:.3g} "
            f"| {S[0]:.3g}..{S[-1]:.3g} | {dF:.3g}{'' if locks_in_order else ' (OUT OF ORDER)'} |"
        )


if __name__ == "__main__":
    main()
