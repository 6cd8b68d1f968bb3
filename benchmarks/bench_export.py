"""Speed of `mst export` and `mst check` (issue: export and check). Prints a table; asserts nothing.

    python benchmarks/bench_export.py [--repeats N]

* wall time of `mst export --stl --step` on the three-layer reference design, interpreter
  start included (goal <= 6 s median);
* wall time of `mst check` on what it wrote (goal <= 2 s median);
* where export spends its time, from one in-process run (build123d import, build + fuse,
  mesh + STL, STEP).
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from user_env import as_installed

ROOT = Path(__file__).resolve().parents[1]
DESIGN = ROOT / "configs" / "mohammadi2021-forward.yaml"


def mst_cmd() -> list[str]:
    exe = Path(sys.executable).with_name("mst")
    return [str(exe) if exe.exists() else "mst"]


def wall_times(args_for_run, repeats: int) -> list[float]:
    times = []
    for i in range(repeats):
        cmd = mst_cmd() + args_for_run(i)
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True)
        times.append(time.perf_counter() - t0)
    return times


def stages() -> list[tuple[str, float]]:
    """Split of one export, in a fresh interpreter (so the import cost is real)."""
    code = f"""
import time, tempfile
from pathlib import Path
t = time.perf_counter(); out = []
import build123d
out.append(("import build123d", time.perf_counter() - t)); t = time.perf_counter()
from mst_cli.io.schema import load_design_document
from mst_cli.cad.assembly import build_sensor
from mst_cli.cad import mesh_io
doc, g = load_design_document({str(DESIGN)!r})
cad = build_sensor(g)
out.append(("build + fuse the body", time.perf_counter() - t)); t = time.perf_counter()
v, f = mesh_io.tessellate(cad.body, 0.01); data = mesh_io.stl_bytes(v, f)
out.append(("mesh + STL bytes", time.perf_counter() - t)); t = time.perf_counter()
with tempfile.TemporaryDirectory() as d:
    mesh_io.write_step(cad.assembly(doc.name), Path(d) / "s.step")
out.append(("STEP assembly", time.perf_counter() - t))
for name, s in out: print(name + "|" + repr(s))
"""
    res = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
    return [(line.split("|")[0], float(line.split("|")[1])) for line in res.stdout.splitlines()]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    as_installed()                 # commands start from bytecode, as an installed copy does

    with tempfile.TemporaryDirectory() as tmp:
        exp = wall_times(lambda i: ["export", str(DESIGN), "--stl", "--step", "--out", f"{tmp}/o{i}"],
                         args.repeats)
        chk = wall_times(lambda i: ["check", f"{tmp}/o{i}"], args.repeats)
    split = stages()
    e_med, c_med = statistics.median(exp), statistics.median(chk)
    rows = [
        ("mst export --stl --step, 3 layers, median [s]", f"{e_med:.2f}", "<= 6", f"{e_med / 6.0:.2f}"),
        ("mst export, min / max [s]", f"{min(exp):.2f} / {max(exp):.2f}", "", ""),
        ("mst check, median [s]", f"{c_med:.2f}", "<= 2", f"{c_med / 2.0:.2f}"),
        ("mst check, min / max [s]", f"{min(chk):.2f} / {max(chk):.2f}", "", ""),
    ] + [(f"  export stage: {name} [s]", f"{s:.2f}", "", "") for name, s in split]
    print(f"# bench_export ({args.repeats} repeats, {sys.platform}, python {sys.version.split()[0]})")
    print(f"| {'measure':<46} | {'value':>11} | {'goal':>5} | {'value/goal':>10} |")
    print(f"|{'-' * 48}|{'-' * 13}|{'-' * 7}|{'-' * 12}|")
    for name, value, goal, ratio in rows:
        print(f"| {name:<46} | {value:>11} | {goal:>5} | {ratio:>10} |")


if __name__ == "__main__":
    main()
