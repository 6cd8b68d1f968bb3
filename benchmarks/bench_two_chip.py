"""Speed and accuracy of the fast two-chip reader of all five unknowns (Fz, Fx, Fy, x, y),
mst_cli/estimation/two_chip_table.py, against the exact one (mst_cli/estimation/shear_reading.py).
Prints markdown tables; asserts nothing.

    python benchmarks/bench_two_chip.py [--readings 2000 --repeats 5 --presses 200 --seed 39 --chips "0,0;10,6"]
                                        [--batches 50,200,800,2000]

On the bundled sensor as printed (configs/mohammadi2021-forward.yaml, --mechanics spring), chips
at (0, 0) and (10, 6) mm (studies/shear_roundtrip.py's default layout), one core (MST_WORKERS=1):

* the layer tables' build time;
* the vectorised model's field against the exact one (general_load.field_T) on --presses random
  loads over the tables' whole range (Fz to 1.5 x the last lock, shear ratio to 0.5, the whole
  face): the trilinear tables alone and made exact by the batched Newton;
* readings per second: the fast reader on --readings readings (median of --repeats), the exact
  reader on 10;
* where a batch's time goes (--batches): the estimate of batches of 50 to 2,000 readings, its
  CPU split between the fit on the tables, the fit on the exact states and the rest (starts,
  distinct fits, the verdict). A live session estimates everything waiting at once, so it keeps
  up with a board writing r readings a second only if some batch of n readings is estimated in
  n / r seconds: the best rate over the batches is its ceiling (a batch pays numpy's cost per call
  once per fit iteration, and its slowest reading sets the iterations);
* at 0.5 and 2 uT, on --presses presses as studies/shear_roundtrip.py draws them (Fz 5 to 100 %
  of the last lock, shear up to 0.3, the middle 60 % of the face), the truth from field_T: the
  median errors, and per unknown the median |error| / sigma_CRB / 0.6745 (1 for an efficient
  Gaussian estimate) and the mean-square efficiency sum(sigma_CRB^2) / sum(error^2), the bound
  from the exact model's Jacobian at the truth; the flags;
* the compiled kernels' cost to a new process (numba's import, the first calls) with an empty
  numba cache (they compile) and with the cache that run kept (they load).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MST_WORKERS", "1")  # one core: the table build too

import numpy as np

import mst_cli.estimation.two_chip_table as two_chip_table
from mst_cli.estimation.shear_reading import ShearReader
from mst_cli.estimation.two_chip_table import NEWTON_STEPS, TwoChipReader
from mst_cli.model.general_load import field_T, loaded_stack
from mst_cli.model.load_bound import UNKNOWNS, crb_sigma, field_jacobian
from mst_cli.sensor.as_printed import as_printed
from mst_cli.sensor.document import load_design_document

DESIGN = Path(__file__).resolve().parents[1] / "configs" / "mohammadi2021-forward.yaml"
CHIPS = [(0.0, 0.0), (10.0, 6.0)]
NOISES_uT = (0.5, 2.0)


def draw(rng, n: int, top_N: float, ratio: float, half_mm) -> np.ndarray:
    """(n, 5) loads: Fz uniform over ``top_N`` x (0.05, 1), the shear up to ``ratio`` of it in a
    uniform direction, the press uniform over +-``half_mm``."""
    Fz = rng.uniform(0.05, 1.0, n) * top_N
    r = ratio * np.sqrt(rng.uniform(0.0, 1.0, n))
    a = rng.uniform(0.0, 2 * np.pi, n)
    xy = rng.uniform(-1.0, 1.0, (n, 2)) * np.asarray(half_mm)
    return np.column_stack([Fz, r * Fz * np.cos(a), r * Fz * np.sin(a), xy])


def exact(stack, theta) -> np.ndarray:
    return np.array([field_T(stack, t[0], (t[1], t[2]), (t[3], t[4]), CHIPS).ravel() for t in theta])


def model_error(reader, stack, rng, n: int) -> None:
    g, model = stack.geometry, reader.model
    theta = draw(rng, n, model.force_max_N, model.ratio_max, (0.5 * g.width_mm, 0.5 * g.depth_mm))
    truth = exact(stack, theta)
    print(f"\nThe vectorised model's field against field_T, {n} loads over the tables' range (uT):")
    print("| states | median of max over axes | 99th percentile | max |")
    print("|---|---|---|---|")
    for name, steps in (("tables, trilinear", 0), (f"tables + batched Newton (<= {NEWTON_STEPS} steps)", NEWTON_STEPS)):
        e = np.max(np.abs(model.fields_T(theta, steps) - truth), axis=1) * 1e6
        print(f"| {name} | {np.median(e):.3g} | {np.percentile(e, 99):.3g} | {e.max():.3g} |")


def speed(reader, stack, rng, n: int, repeats: int, top_N: float, half_mm) -> None:
    theta = draw(rng, n, top_N, 0.3, half_mm)
    noise = reader.noise_T
    B = reader.exact(theta)[0] + rng.normal(0.0, noise, (n, 6))  # the model's own fields (field_T's to 1e-9 T)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        reader.estimate(B)
        times.append(time.perf_counter() - t0)
    fast = n / float(np.median(times))
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        reader.estimate(B, every_start=False)
        times.append(time.perf_counter() - t0)
    centred = n / float(np.median(times))
    slow_reader = ShearReader(stack, CHIPS)
    t0 = time.perf_counter()
    slow_reader.read(B[:10], noise)
    slow = 10 / (time.perf_counter() - t0)
    t0 = time.perf_counter()
    reader.polish(B[:10], reader.estimate(B[:10]))
    polish = 10 / (time.perf_counter() - t0)
    print("\nReadings per second, one core (0.5 uT readings):")
    print("| reader | readings | readings/s |")
    print("|---|---|---|")
    print(f"| fast (two_chip_table), median of {repeats} | {n} | {fast:.0f} |")
    print(f"| fast, the centred start first (the others where no_fit) | {n} | {centred:.0f} |")
    print(f"| exact (ShearReader) | 10 | {slow:.2f} |")
    print(f"| fast then polished by the exact fit | 10 | {polish:.2f} |")


@contextlib.contextmanager
def stage_clock(reader):
    """Seconds of CPU spent in the reader's fit on its tables and on the exact states, summed
    over the calls made inside the block (the module's fit_many, wrapped for the block only)."""
    spent = {"tables": 0.0, "exact": 0.0}
    inner = two_chip_table.fit_many

    def timed(fields, *args, **kwargs):
        t0 = time.process_time()
        try:
            return inner(fields, *args, **kwargs)
        finally:
            spent["tables" if fields == reader.table else "exact"] += time.process_time() - t0

    two_chip_table.fit_many = timed
    try:
        yield spent
    finally:
        two_chip_table.fit_many = inner


def batch_costs(reader, rng, sizes: list[int], repeats: int, top_N: float, half_mm) -> None:
    """The CPU of one estimate per batch size, split by stage, and the line C + c n through it."""
    print(f"\nWhere a batch's time goes, CPU ms per reading (median of {repeats}; 2 uT readings, one core):")
    print("| batch | fit on the tables | fit on the exact states | the rest | total | readings/s |")
    print("|---|---|---|---|---|---|")
    totals = []
    for n in sizes:
        theta = draw(rng, n, top_N, 0.3, half_mm)
        B = reader.exact(theta)[0] + rng.normal(0.0, 2e-6, (n, 6))
        runs = []
        for _ in range(repeats):
            with stage_clock(reader) as spent:
                t0 = time.process_time()
                reader.estimate(B)
                total = time.process_time() - t0
            runs.append((spent["tables"], spent["exact"], total - spent["tables"] - spent["exact"], total))
        tables, exact_s, rest, total = np.median(np.array(runs), axis=0)
        totals.append(total)
        cells = " | ".join(f"{1e3 * v / n:.2f}" for v in (tables, exact_s, rest, total))
        print(f"| {n} | {cells} | {n / total:,.0f} |")
    best = max(n / t for n, t in zip(sizes, totals))
    print(
        f"\nA live session keeps up with r readings a second only if some batch of n is estimated in "
        f"n / r s: the best here is {best:,.0f} a second (2,000 needs {2000 / best:.1f}x that)."
    )


def accuracy(reader, stack, rng, n: int, top_N: float, half_mm) -> None:
    theta = draw(rng, n, top_N, 0.3, half_mm)
    clean = exact(stack, theta)
    crb1 = np.array([crb_sigma(field_jacobian(stack, t, CHIPS), 1.0) for t in theta])
    print(f"\nRound trips, {n} presses (shear <= 0.3, middle 60 % of the face), truth field_T:")
    print("| noise uT | Fz err | pos err mm | " + " | ".join(f"{u} med/CRB, MSE eff" for u in UNKNOWNS) + " | flags |")
    print("|---" * (4 + len(UNKNOWNS)) + "|")
    for noise_uT in NOISES_uT:
        noise = noise_uT * 1e-6
        r = TwoChipReader(stack, CHIPS, noise, model=reader.model)
        est = r.estimate(clean + rng.normal(0.0, noise, clean.shape))
        err = est.theta - theta
        crb = crb1 * noise
        med = np.median(np.abs(err) / crb, axis=0) / 0.6745
        eff = np.sum(crb**2, axis=0) / np.sum(err**2, axis=0)
        flags = ", ".join(f"{f} {c}" for f, c in zip(*np.unique(est.flag, return_counts=True)))
        cells = " | ".join(f"{m:.2f}, {e:.2f}" for m, e in zip(med, eff))
        print(
            f"| {noise_uT:g} | {100 * np.median(np.abs(err[:, 0]) / theta[:, 0]):.2f} % "
            f"| {np.median(np.hypot(err[:, 3], err[:, 4])):.3f} | {cells} | {flags} |"
        )


KERNELS_FIRST_CALL = """
import time
import numpy as np
t0 = time.perf_counter()
import numba
tn = time.perf_counter()
from mst_cli.estimation.layer_tables import LayerTable
from mst_cli.model.mechanics.tilt import LayerTiltLaw, PiecewiseForce
from mst_cli.model.mechanics.tilt_batch import newton_many, residual_many
t1 = time.perf_counter()
law = LayerTiltLaw(PiecewiseForce(np.array([0.0, 1.0]), np.array([0.0, 2.0]), 2.0, 50.0), 5.0, 20.0, 2.0, 1.0, 30.0)
newton_many(law, np.ones(1), np.zeros((1, 2)), np.zeros((1, 3)), 3)
residual_many(law, np.zeros((1, 3)), np.zeros((1, 3)))
nodes = np.array([0.0, 1.0])
LayerTable(nodes, nodes, nodes, np.zeros((2, 2, 2, 3))).read(np.ones(1), np.ones(1), np.ones(1))
print(f"{tn - t0:.3f} {t1 - tn:.3f} {time.perf_counter() - t1:.3f}")
"""


def kernel_times() -> None:
    """The compiled kernels' cost to a new process: importing numba and the kernels' modules, and
    their first calls, with an empty numba cache (they compile) and then with that cache (they load)."""
    cache = tempfile.mkdtemp(prefix="mst-numba-")
    env = {**os.environ, "NUMBA_CACHE_DIR": cache}
    rows = []
    for label in ("empty cache: compiled", "cache kept: loaded"):
        out = subprocess.run([sys.executable, "-c", KERNELS_FIRST_CALL], env=env, capture_output=True, text=True)
        numba_s, modules_s, first_s = (float(v) for v in out.stdout.split())
        rows.append(f"| {label} | {numba_s:.2f} | {modules_s:.2f} | {first_s:.2f} |")
    shutil.rmtree(cache, ignore_errors=True)
    print("\nThe compiled kernels in a new process (s):")
    print("| numba cache | import numba | import the kernels' modules | first calls |")
    print("|---|---|---|---|")
    print("\n".join(rows))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--readings", type=int, default=2000)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--presses", type=int, default=200)
    ap.add_argument("--seed", type=int, default=39)
    ap.add_argument("--mechanics", default="spring", choices=("spring", "frame", "continuum"))
    ap.add_argument("--chips", default="0,0;10,6", help="the chips' x,y in mm, ';' between chips")
    ap.add_argument(
        "--batches", default="50,200,800,2000", help="batch sizes of the stage split, ',' between ('' skips it)"
    )
    args = ap.parse_args()
    CHIPS[:] = [tuple(float(v) for v in c.split(",")) for c in args.chips.split(";")]  # every function's layout
    doc, _ = load_design_document(DESIGN)
    printed = as_printed(doc)
    stack = loaded_stack(printed.geometry(), printed.material, args.mechanics)
    g = stack.geometry
    top = max(t.lock_force_N for t in stack.tilt)
    half = (0.3 * g.width_mm, 0.3 * g.depth_mm)
    rng = np.random.default_rng(args.seed)
    t0 = time.perf_counter()
    reader = TwoChipReader(stack, CHIPS, NOISES_uT[0] * 1e-6)
    build = time.perf_counter() - t0
    shape = [t.state.shape[:3] for t in reader.model.tables]
    print(f"{DESIGN.name} as printed, {args.mechanics}, chips {CHIPS} mm, range {top:.1f} N (last lock)")
    print(f"\nTables built in {build:.1f} s on one core; nodes (F, |ox|, |oy|) per layer: {shape}")
    model_error(reader, stack, rng, args.presses)
    speed(reader, stack, rng, args.readings, args.repeats, top, half)
    if args.batches:
        batch_costs(reader, rng, [int(b) for b in args.batches.split(",")], args.repeats, top, half)
    accuracy(reader, stack, rng, args.presses, top, half)
    kernel_times()


if __name__ == "__main__":
    main()
