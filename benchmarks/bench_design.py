"""Speed and success rate of `mst design` (issue 3). Prints tables; asserts nothing.

    python benchmarks/bench_design.py [--specs 50] [--repeats 5] [--cobyla-specs 10]

* the reference spec configs/mohammadi2021.yaml: median wall time of the `mst design` command
  (interpreter start and every output file included; goal <= 2 s) and of the library call;
* for 1 to 6 layers: success rate over N seeded random *feasible* specs (targets taken from
  the forward model of random valid designs; goal >= 98 %), median wall time and median
  forward evaluations per design, for the default local method (LD_SLSQP with batched
  finite-difference gradients) and, on fewer specs, the derivative-free LN_COBYLA.

A design counts as a success when `design_document` reports every target met and an
independent re-check -- the forward model on design.yaml as loaded back -- agrees.
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
import yaml

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "configs" / "mohammadi2021.yaml"
MST = Path(sys.executable).parent / "mst"      # the console script of this environment


def cli_times(repeats: int) -> list[float]:
    times = []
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(repeats):
            t0 = time.perf_counter()
            r = subprocess.run([str(MST), "design", str(SPEC), "--out",
                                f"{tmp}/o{i}", "-q"], capture_output=True)
            times.append(time.perf_counter() - t0)
            if r.returncode != 0:
                raise SystemExit(f"mst design failed: {r.stderr.decode()}")
    return times


def random_specs(n_layers: int, count: int, seed: int):
    from mst_cli.design.problem import DesignProblem
    from mst_cli.io.schema import LayerEntry, load_document
    from mst_cli.model.response import simulate

    base = load_document(SPEC)
    probe_doc = base.with_layers([LayerEntry(target_sensitivity_per_N=1.0, target_range_N=i + 1.0)
                                  for i in range(n_layers)])
    probe = DesignProblem(probe_doc)
    theta, t, h = probe.sample_feasible(np.random.default_rng(seed), count)
    docs = []
    for j in range(count):
        cells = [probe.family.cell(*x) for x in zip(theta[j], t[j], h[j])]
        resp = simulate(probe_doc.geometry(cells), probe_doc.material)
        docs.append(base.with_layers([LayerEntry(target_sensitivity_per_N=r.sensitivity_secant_per_N,
                                                 target_range_N=r.force_to_N) for r in resp.regimes]))
    return docs


def recheck(result) -> bool:
    """Forward model on design.yaml as a user would load it, against the spec's targets."""
    from mst_cli.io.schema import parse_document
    from mst_cli.model.response import simulate

    doc = parse_document(yaml.safe_load(yaml.safe_dump(result.design_yaml_dict(), sort_keys=False)))
    geometry = doc.geometry()
    if geometry.violations(doc.printer):
        return False
    resp = simulate(geometry, doc.material)
    tol = doc.design["tolerance_rel"]
    for i, la in enumerate(doc.layers):
        reg = resp.regimes[i]
        if reg.layer != i + 1:
            return False
        if abs(reg.sensitivity_secant_per_N / la.target_sensitivity_per_N - 1) > tol:
            return False
        if abs(reg.force_to_N / la.target_range_N - 1) > tol:
            return False
    return True


def sweep(n_layers: int, docs, local: str):
    from mst_cli.design import design_document

    times, evals, ok = [], [], 0
    for k, doc in enumerate(docs):
        t0 = time.perf_counter()
        result = design_document(doc, seed=k, local=local)
        times.append(time.perf_counter() - t0)
        evals.append(result.evaluations)
        ok += int(result.status == "met" and recheck(result))
    return ok / len(docs), statistics.median(times), max(times), statistics.median(evals)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--specs", type=int, default=50, help="random feasible specs per layer count")
    ap.add_argument("--cobyla-specs", type=int, default=10, help="of those, designed with LN_COBYLA too")
    ap.add_argument("--repeats", type=int, default=5, help="runs of the mst design command")
    args = ap.parse_args()

    from mst_cli.design import design_document
    from mst_cli.io.schema import load_document

    cli = cli_times(args.repeats)
    doc = load_document(SPEC)
    lib = []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        res = design_document(doc)
        lib.append(time.perf_counter() - t0)
    print(f"reference spec {SPEC.name}: `mst design` command median {statistics.median(cli):.2f} s "
          f"(min {min(cli):.2f}, max {max(cli):.2f}, {args.repeats} runs, interpreter start and all "
          f"outputs included; goal <= 2 s)")
    print(f"  library design_document median {statistics.median(lib):.3f} s, {res.evaluations} "
          f"evaluations, status {res.status}, print-error RMS {res.print_error['rms_log_change']:.4f}")
    print()
    print(f"{'layers':>6} {'method':>7} {'specs':>5} {'success':>8} {'median s':>9} {'max s':>7} "
          f"{'median evals':>12}")
    for n in range(1, 7):
        docs = random_specs(n, args.specs, seed=1000 + n)
        for local, count in (("slsqp", args.specs), ("cobyla", args.cobyla_specs)):
            if count <= 0:
                continue
            rate, med, worst, ev = sweep(n, docs[:count], local)
            print(f"{n:>6} {local:>7} {count:>5} {100 * rate:>7.1f}% {med:>9.3f} {worst:>7.2f} {ev:>12.0f}",
                  flush=True)


if __name__ == "__main__":
    main()
