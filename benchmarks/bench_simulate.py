"""Speed of the quick commands as ratios against a floor (issues 14, 25). Prints tables; asserts nothing.

    python benchmarks/bench_simulate.py [--repeats N] [--no-pareto] [--no-refine] [--baseline DIR]

Every command runs as a subprocess, interpreter start included, and every figure is a
ratio to the **floor** measured in the same run: ``python -c "import numpy, yaml, click"``,
the interpreter and the three libraries no command can avoid. The commands run round-robin
(one of each per round, after one warm-up round that is not counted), so a machine shared
with other work slows them all alike and the ratios hold where absolute seconds do not.

* ``mst --help``, ``mst simulate --no-plot`` (goal <= 1.5x the floor), ``mst simulate``
  (with response.png: the picture's cost is the difference), ``mst simulate --json``,
  ``mst design`` on configs/mohammadi2021.yaml with --no-plot --quiet (goal <= 2x),
  ``mst design --pareto 12`` on the same spec (goal <= 10x), ``mst design --refine continuum``
  on the same spec (goal <= 6x), ``mst check`` (goal <= 3x),
  ``mst export --stl --3mf`` (meshes, no CAD kernel; goal <= 3x) and ``mst export --step``
  (build123d's import is most of it);
* which heavy libraries each quick command imported (none for simulate; nlopt for design);
* the vectorised L0 kernel's layer evaluations per second (goal >= 1e6 / s).

``--baseline DIR`` (a checkout of another version, e.g. ``git archive 04dbf0a | tar -x -C DIR``)
adds the rows with a goal run again with DIR first on PYTHONPATH, marked "(baseline)", in the
same round robin: a before/after comparison in one run.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from user_env import as_installed, libraries

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"
SPEC = ROOT / "configs" / "mohammadi2021.yaml"
HEAVY = ("matplotlib", "scipy", "skfem", "magpylib", "nlopt", "build123d", "OCP", "trimesh", "manifold3d")


def mst_exe() -> str:
    exe = Path(sys.executable).with_name("mst")
    return str(exe) if exe.exists() else "mst"


def layers_spec(tmp: Path) -> Path:
    """The reference spec designed for its layers alone (model.load_path: layers): the design
    loop without the members, a row of its own beside the reference spec as it stands (the whole
    part, the issue's goal)."""
    path = tmp / "mohammadi2021-layers.yaml"
    if not path.exists():
        path.write_text(SPEC.read_text() + "model:\n  load_path: layers\n")
    return path


def commands(tmp: Path, export_dir: Path, with_pareto: bool, with_refine: bool) -> dict[str, tuple[list[str], str]]:
    """name -> (argv with {i} for the round, goal). Each round writes into its own folder."""
    mst = mst_exe()
    cmds = {
        'floor: python -c "import numpy, yaml, click"': ([sys.executable, "-c", "import numpy, yaml, click"], ""),
        "mst --help": ([mst, "--help"], ""),
        "mst simulate --no-plot": ([mst, "simulate", str(FORWARD), "--out", f"{tmp}/np{{i}}", "--no-plot"], "<= 1.5"),
        "mst simulate (draws response.png)": ([mst, "simulate", str(FORWARD), "--out", f"{tmp}/p{{i}}"], ""),
        "mst simulate --json": ([mst, "simulate", str(FORWARD), "--out", f"{tmp}/j{{i}}", "--json"], ""),
        "mst design mohammadi2021 (whole part) --no-plot -q": (
            [mst, "design", str(SPEC), "--out", f"{tmp}/w{{i}}", "--no-plot", "--quiet"],
            "<= 2",
        ),
        "mst design mohammadi2021 (layers alone) --no-plot -q": (
            [mst, "design", str(layers_spec(tmp)), "--out", f"{tmp}/d{{i}}", "--no-plot", "--quiet"],
            "",
        ),
        "mst check (3 layers)": ([mst, "check", str(export_dir)], "<= 3"),
        "mst export --stl --3mf (3 layers)": (
            [mst, "export", str(FORWARD), "--stl", "--3mf", "--out", f"{tmp}/e{{i}}"],
            "<= 3",
        ),
        "mst export --step (3 layers)": ([mst, "export", str(FORWARD), "--step", "--out", f"{tmp}/s{{i}}"], ""),
    }
    if with_pareto:
        cmds["mst design mohammadi2021 --pareto 12 --no-plot -q"] = (
            [mst, "design", str(SPEC), "--pareto", "12", "--out", f"{tmp}/f{{i}}", "--no-plot", "--quiet"],
            "<= 10",
        )
    if with_refine:
        cmds["mst design mohammadi2021 --refine continuum --no-plot -q"] = (
            [mst, "design", str(SPEC), "--refine", "continuum", "--out", f"{tmp}/r{{i}}", "--no-plot", "--quiet"],
            "<= 6",
        )
    return cmds


def with_baseline(cmds: dict, baseline: Path) -> dict[str, tuple[list[str], str, dict | None]]:
    """Every command with a goal once more, run with ``baseline`` first on PYTHONPATH."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(baseline), os.environ.get("PYTHONPATH")]))}
    out = {}
    for name, (argv, goal) in cmds.items():
        out[name] = (argv, goal, None)
        if goal:
            out[f"{name} (baseline)"] = ([a.replace("{i}", "b{i}") if "{i}" in a else a for a in argv], goal, env)
    return out


def round_robin(cmds: dict, repeats: int) -> dict[str, list[float]]:
    times = {name: [] for name in cmds}
    for i in range(-1, repeats):  # round -1 warms the caches and is not counted
        for name, (argv, _, env) in cmds.items():
            run = [a.replace("{i}", str(i + 1)) for a in argv]
            t0 = time.perf_counter()
            subprocess.run(run, check=True, capture_output=True, env=env)
            if i >= 0:
                times[name].append(time.perf_counter() - t0)
    return times


def heavy_imports(args: list[str]) -> list[str]:
    """The heavy libraries a command imports, run in-process in a fresh interpreter."""
    code = (
        "import sys\nfrom mst_cli.cli.app import main\n"
        f"sys.argv = ['mst'] + {args!r}\n"
        "try:\n    main()\nexcept SystemExit:\n    pass\n"
        f"print(','.join(m for m in {HEAVY!r} if m in sys.modules), file=sys.stderr)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    last = out.stderr.strip().splitlines()[-1] if out.stderr.strip() else ""
    return [m for m in last.split(",") if m]


def l0_rate(n_layers: int, repeats: int) -> float:
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
    return n_layers / statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=9)
    ap.add_argument("--no-pareto", action="store_true", help="skip mst design --pareto 12 (seconds a run)")
    ap.add_argument("--no-refine", action="store_true", help="skip mst design --refine continuum (seconds a run)")
    ap.add_argument("--baseline", type=Path, default=None, help="a checkout of another version to compare")
    args = ap.parse_args()
    as_installed()  # commands start from bytecode, as an installed copy does

    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        export_dir = tmp / "export"
        subprocess.run(
            [mst_exe(), "export", str(FORWARD), "--stl", "--out", str(export_dir)], check=True, capture_output=True
        )
        cmds = commands(tmp, export_dir, not args.no_pareto, not args.no_refine)
        cmds = (
            with_baseline(cmds, args.baseline.resolve())
            if args.baseline
            else {name: (argv, goal, None) for name, (argv, goal) in cmds.items()}
        )
        times = round_robin(cmds, args.repeats)
        heavy = {
            "mst simulate --no-plot": heavy_imports(["simulate", str(FORWARD), "--out", f"{tmp}/h1", "--no-plot"]),
            "mst simulate --json": heavy_imports(["simulate", str(FORWARD), "--out", f"{tmp}/h2", "--json"]),
            "mst design --no-plot": heavy_imports(["design", str(SPEC), "--out", f"{tmp}/h3", "--no-plot", "-q"]),
            "mst simulate": heavy_imports(["simulate", str(FORWARD), "--out", f"{tmp}/h4"]),
            "mst check": heavy_imports(["check", str(export_dir)]),
            "mst export --stl --3mf": heavy_imports(["export", str(FORWARD), "--stl", "--3mf", "--out", f"{tmp}/h5"]),
        }
    rate = l0_rate(1_000_000, 5)

    med = {name: statistics.median(ts) for name, ts in times.items()}
    floor = next(iter(med.values()))
    print(
        f"# bench_simulate ({args.repeats} rounds, {sys.platform}, {libraries()}); "
        f"ratios against the floor measured in the same run"
    )
    width = max(len(name) for name in cmds)
    print(f"| {'command':<{width}} | {'median [s]':>10} | {'min / max [s]':>13} | {'x floor':>7} | {'goal':>11} |")
    print(f"|{'-' * (width + 2)}|{'-' * 12}|{'-' * 15}|{'-' * 9}|{'-' * 13}|")
    for name, (_, goal, _) in cmds.items():
        ts = times[name]
        ratio = med[name] / floor
        mark = "" if not goal else (" ok" if ratio <= float(goal.split()[-1]) else " MISS")
        print(
            f"| {name:<{width}} | {med[name]:>10.3f} | {min(ts):>5.3f} / {max(ts):<5.3f} | {ratio:>7.2f} "
            f"| {goal + mark:>11} |"
        )
    drawn, bare = med["mst simulate (draws response.png)"], med["mst simulate --no-plot"]
    print()
    print(
        f"response.png costs {drawn - bare:.3f} s: {100 * (drawn - bare) / drawn:.0f} % of 'mst simulate' "
        f"({drawn / floor:.2f}x the floor with it, {bare / floor:.2f}x without)"
    )
    print()
    print(f"| {'command':<26} | {'heavy libraries imported':<30} |")
    print(f"|{'-' * 28}|{'-' * 32}|")
    for name, mods in heavy.items():
        print(f"| {name:<26} | {', '.join(mods) or 'none':<30} |")
    print()
    print(f"L0 layer evaluations / s (1e6 layers per call): {rate:.3g} (goal >= 1e6)")


if __name__ == "__main__":
    main()
