"""Where a quick ``mst design`` spends its time, in one process (issue 44 item 6). Prints a table.

    python benchmarks/profile_design.py [--spec configs/mohammadi2021.yaml] [--repeats 7] [--baseline DIR]

Each repeat is a fresh interpreter (as an installed copy runs, ``user_env.py``) that imports
numpy, yaml and click (the floor's libraries), then mst's command line, then the design layer,
and runs ``mst design SPEC --no-plot --quiet`` with wall clocks around its parts: the spec's
loading, the start's table of cells and its layer-by-layer passes (``design.seed``), the design
kernel's calls (``DesignProblem._evaluate_physical``, the seed's one included), the whole search
(``solver.solve``), the forward model's verification and the files. The least of the repeats
is printed for each part, so one row's figure may come from another repeat than its neighbour's.
``--baseline DIR`` runs a checkout of another version (``git archive <commit> | tar -x -C DIR``)
with DIR first on PYTHONPATH, in the same round robin.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import subprocess
import sys
import time
from pathlib import Path

from user_env import as_installed, libraries

ROOT = Path(__file__).resolve().parents[1]


def child(spec: str, out: str) -> dict:
    """The parts' seconds of one run in this process."""
    t0 = time.perf_counter()
    import click  # noqa: F401
    import numpy  # noqa: F401
    import yaml  # noqa: F401

    t1 = time.perf_counter()
    from mst_cli.cli.app import main

    t2 = time.perf_counter()
    import mst_cli.api._common as common
    import mst_cli.design.document as document
    import mst_cli.design.problem as problem
    import mst_cli.design.run as run
    import mst_cli.design.seed as seed

    t3 = time.perf_counter()
    parts: dict[str, float] = {"kernel calls": 0}

    def timed(owner, name: str, label: str) -> None:
        original = getattr(owner, name)

        def wrapper(*args, **kwargs):
            start = time.perf_counter()
            try:
                return original(*args, **kwargs)
            finally:
                parts[label] = parts.get(label, 0.0) + time.perf_counter() - start
                if label == "design kernel":
                    parts["kernel calls"] += 1

        setattr(owner, name, wrapper)

    timed(common, "load", "load the spec")
    timed(seed.CellTable, "__init__", "start: table of cells")
    timed(seed, "seed_start", "start: layer passes")
    timed(problem.DesignProblem, "_evaluate_physical", "design kernel")
    timed(document, "solve", "search (start and kernel included)")
    timed(document, "verify_design", "verify (forward model)")
    timed(run.DesignRun, "write", "write the files")
    sys.argv = ["mst", "design", spec, "--out", out, "--no-plot", "--quiet"]
    with contextlib.suppress(SystemExit):  # the command's exit code
        main()
    t4 = time.perf_counter()
    return {
        "numpy, yaml, click": t1 - t0,
        "mst's command line (import)": t2 - t1,
        "the design layer (import)": t3 - t2,
        "the run": t4 - t3,
        **parts,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spec", default=str(ROOT / "configs" / "mohammadi2021.yaml"))
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--baseline", type=Path, default=None)
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(json.dumps(child(*args.child)))
        return
    as_installed()
    trees = {"this tree": str(ROOT)} | ({"baseline": str(args.baseline.resolve())} if args.baseline else {})
    runs: dict[str, list[dict]] = {name: [] for name in trees}
    out = Path(os.environ.get("TMPDIR", "/tmp")) / f"profile_design_{os.getpid()}"
    for i in range(args.repeats + 1):  # the first round warms the bytecode and the disk cache
        for name, tree in trees.items():
            env = {**os.environ, "PYTHONPATH": os.pathsep.join([tree, str(ROOT / "benchmarks")])}
            cmd = [sys.executable, __file__, "--child", args.spec, f"{out}/{name.replace(' ', '_')}{i}"]
            done = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
            if i:
                runs[name].append(json.loads(done.stdout.strip().splitlines()[-1]))
    names = list(trees)
    print(f"# profile_design ({libraries()})")
    print(f"{'part (least of ' + str(args.repeats) + ' runs)':<40}" + "".join(f"{n:>14}" for n in names))
    first = runs[names[0]][0]
    for key in [k for k in first if k != "kernel calls"] + ["kernel calls"]:
        cells = []
        for n in names:
            least = min(r.get(key, 0.0) for r in runs[n])
            cells.append(f"{least:>14.0f}" if key == "kernel calls" else f"{1e3 * least:>11.1f} ms")
        print(f"{key:<40}" + "".join(cells))


if __name__ == "__main__":
    main()
