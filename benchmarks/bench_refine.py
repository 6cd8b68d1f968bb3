"""Cost of `mst design --refine` against the plain L0 design (issue 14). Prints a table; asserts nothing.

    python benchmarks/bench_refine.py [--repeats 3] [--spec configs/mohammadi2021.yaml] [--baseline DIR]

Three commands on one spec, timed in the same run so their ratios are comparable on a shared
machine: `mst design`, `mst design --refine frame`, `mst design --refine continuum` (wall time
of the command via subprocess: interpreter start and every output file included; median of
--repeats runs, interleaved so a burst of load hits every mode alike). Goal: --refine continuum
at most 4x the plain design. ``--baseline DIR`` adds the two refine commands run with DIR first
on PYTHONPATH (a copy of another version of the ``mst_cli`` package), in the same interleaved
loop, so a before/after comparison shares the machine's load.

Each mode is then run --repeats times more (interleaved), each in a fresh interpreter of its
own (cold caches, like the command), with counters on:

* dear-rung law requests (``layer_law(cell, material, frame|continuum)``) and the laws actually
  solved (the rung's per-cell cache misses, in this process or by a worker: since 0.11 a
  stack's missing continuum laws are solved side by side, mst_cli/model/mechanics/law_cache.py);
* DesignProblem._evaluate_physical calls (every evaluation goes through it, with or without the
  print-shifted stacks: one call is one batched kernel call; in an older checkout
  evaluate_physical, whose print-shifted stacks went through kernel calls of their own, not
  counted) and the candidate designs they held;
* where the time goes (medians; issue 25: the loop should spend it in the dear solves): the
  command's in-process time without plots, the part inside the dear laws' side-by-side solves
  (``LawCache.solve_many``; scikit-fem, which each worker imports, inside it) and L2's import
  (scipy), done before the run.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from user_env import as_installed

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "configs" / "mohammadi2021.yaml"
MST = Path(sys.executable).parent / "mst"  # the console script of this environment
MODES = (
    ("mst design", []),
    ("--refine frame", ["--refine", "frame"]),
    ("--refine continuum", ["--refine", "continuum"]),
)
GOAL_RATIO = 4.0  # --refine continuum / plain design
TIMES = ("in_process_s", "dear_solves_s", "l2_import_s")  # what a counted run times


def _env(pythonpath: Path | None) -> dict | None:
    if pythonpath is None:
        return None
    return {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(pythonpath), os.environ.get("PYTHONPATH")]))}


def command_times(spec: Path, repeats: int, modes) -> dict[str, list[float]]:
    times = {label: [] for label, _, _ in modes}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(repeats):
            for j, (label, flags, path) in enumerate(modes):
                t0 = time.perf_counter()
                r = subprocess.run(
                    [str(MST), "design", str(spec), *flags, "--out", f"{tmp}/o{i}-{j}", "-q"],
                    capture_output=True,
                    env=_env(path),
                )
                times[label].append(time.perf_counter() - t0)
                if r.returncode not in (0, 1):  # 1 = targets not met: still a timed run
                    raise SystemExit(f"mst design {' '.join(flags)} failed: {r.stderr.decode()}")
    return times


def count_run(spec: Path, flags: list[str]) -> dict:
    """In this interpreter: run the command once with counters; returns the counts."""
    import numpy as np

    from mst_cli.cli.app import main
    from mst_cli.design.problem import DesignProblem

    t_import = time.perf_counter()
    from mst_cli.model.mechanics import continuum, frame  # L2's import (scipy, the law cache)

    import_s = time.perf_counter() - t_import

    from mst_cli.model.mechanics.law_cache import LawCache

    dear = {"s": 0.0}
    solve_many = LawCache.solve_many

    def timed_solve_many(self, pairs):  # a stack's missing laws, side by side: the dear solves
        t = time.perf_counter()
        solve_many(self, pairs)
        dear["s"] += time.perf_counter() - t

    LawCache.solve_many = timed_solve_many

    calls = {"evaluate_calls": 0, "evaluate_points": 0}
    # an older checkout (--baseline) has no _evaluate_physical: its evaluate_physical then
    name = "_evaluate_physical" if hasattr(DesignProblem, "_evaluate_physical") else "evaluate_physical"
    original = getattr(DesignProblem, name)

    def counted(self, theta_deg, t_mm, h_mm, *more):
        calls["evaluate_calls"] += 1
        calls["evaluate_points"] += int(np.prod(np.shape(theta_deg)[:-1], dtype=int))
        return original(self, theta_deg, t_mm, h_mm, *more)

    setattr(DesignProblem, name, counted)
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        with contextlib.suppress(SystemExit):  # the command's exit code: not a count
            main(["design", str(spec), *flags, "--out", f"{tmp}/o", "-q", "--no-plot"], standalone_mode=False)
        elapsed = time.perf_counter() - t0
    # both rungs memoise their laws (an lru_cache before 0.11): a miss is a law solved (in this
    # process or by a worker), and the requests are the hits and misses less the laws a worker
    # solved (each counted again as a hit when asked for)
    caches = {"frame": frame.frame_layer, "continuum": continuum.continuum_layer}
    solved = {rung: c.cache_info().misses for rung, c in caches.items()}
    requests = {
        rung: c.cache_info().hits + c.cache_info().misses - getattr(c, "solved_in_workers", 0)
        for rung, c in caches.items()
    }
    return {
        **calls,
        "law_requests": requests,
        "laws_solved": solved,
        "in_process_s": elapsed,
        "dear_solves_s": dear["s"],
        "l2_import_s": import_s,
    }


def counts(spec: Path, modes, repeats: int) -> dict[str, dict]:
    """Each mode's counted run, ``repeats`` times interleaved: the counts of the first (they do
    not change), the median of each time."""
    runs: dict[str, list[dict]] = {label: [] for label, _, _ in modes}
    for _ in range(repeats):
        for label, flags, path in modes:
            r = subprocess.run(
                [sys.executable, __file__, "--count", json.dumps(flags), "--spec", str(spec)],
                capture_output=True,
                text=True,
                check=True,
                env=_env(path),
            )
            runs[label].append(json.loads(r.stdout.strip().splitlines()[-1]))
    return {
        label: {**rs[0], **{k: statistics.median(r[k] for r in rs) for k in TIMES if k in rs[0]}}
        for label, rs in runs.items()
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--spec", type=Path, default=SPEC)
    ap.add_argument(
        "--baseline",
        type=Path,
        default=None,
        help="a directory holding another mst_cli package: its refine rows are added",
    )
    ap.add_argument("--count", default=None, help=argparse.SUPPRESS)  # internal: one counted run
    args = ap.parse_args()
    as_installed()  # commands start from bytecode, as an installed copy does
    if args.count is not None:
        print(json.dumps(count_run(args.spec, json.loads(args.count))))
        return

    modes = [(label, flags, None) for label, flags in MODES]
    if args.baseline is not None:
        modes += [(f"{label} (baseline)", flags, args.baseline.resolve()) for label, flags in MODES[1:]]
    times = command_times(args.spec, args.repeats, modes)
    n = counts(args.spec, modes, args.repeats)
    plain = statistics.median(times[MODES[0][0]])
    print(
        f"spec {args.spec.name}, {args.repeats} runs per command (interleaved), one run of this script"
        + (f"; baseline package: {args.baseline}" if args.baseline else "")
    )
    head = (
        f"{'command':<31} {'median s':>9} {'min s':>7} {'max s':>7} {'x plain':>8} "
        f"{'dear laws solved':>16} {'law requests':>12} {'evaluate calls':>14} {'points':>9}"
    )
    print(head)
    print("-" * len(head))
    for label, flags, _ in modes:
        ts, c = times[label], n[label]
        rung = flags[1] if flags else None
        solved = c["laws_solved"][rung] if rung else 0
        req = c["law_requests"][rung] if rung else 0
        print(
            f"{label:<31} {statistics.median(ts):>9.2f} {min(ts):>7.2f} {max(ts):>7.2f} "
            f"{statistics.median(ts) / plain:>8.2f} {solved:>16d} {req:>12d} "
            f"{c['evaluate_calls']:>14d} {c['evaluate_points']:>9d}"
        )
    print_where_the_time_goes(n)
    ratio = statistics.median(times[MODES[-1][0]]) / plain
    print(
        f"goal: --refine continuum <= {GOAL_RATIO:g}x the plain design: {ratio:.2f}x "
        f"({'met' if ratio <= GOAL_RATIO else 'NOT met'})"
    )


def print_where_the_time_goes(n: dict[str, dict]) -> None:
    """The counted runs' split of the command's own time (in-process, after its imports, without
    the plots): inside the dear laws' side-by-side solves (LawCache.solve_many) and around them."""
    print("\nwhere the time goes (counted runs, medians; in-process, no plots, L2's import done before it):")
    for label, c in n.items():
        if "dear_solves_s" not in c or not c["laws_solved"].get("continuum"):
            continue
        total, dear = c["in_process_s"], c["dear_solves_s"]
        print(
            f"  {label}: {total:.2f} s, of which dear solves {dear:.2f} s ({100 * dear / total:.0f} %), "
            f"around them {total - dear:.2f} s; importing L2 (scipy) {c['l2_import_s']:.2f} s more"
        )


if __name__ == "__main__":
    main()
