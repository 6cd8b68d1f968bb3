"""Speed of `mst export` and `mst check` as ratios to the floor (issues: export and check, 25).
Prints tables; asserts nothing.

    python benchmarks/bench_export.py [--repeats N]

Round-robin in one run (as bench_simulate.py): the floor ``python -c "import numpy, yaml,
click"``, `mst export --stl --3mf` (meshed with manifold3d, no CAD kernel; goal <= 3x),
`mst export --step` (the build123d assembly), `mst check` on what export wrote (goal <= 3x),
each on the three-layer reference design, interpreter start included. Then where each export
path spends its time, from one in-process run per path in a fresh interpreter.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from bench_simulate import mst_exe, round_robin
from user_env import as_installed

ROOT = Path(__file__).resolve().parents[1]
DESIGN = ROOT / "configs" / "mohammadi2021-forward.yaml"

STAGES = {
    "mesh path (--stl --3mf)": """
import manifold3d
mark("import manifold3d")
from mst_cli.sensor.document import load_design_document
from mst_cli.cad import mesh_io, mesh_body
doc, g = load_design_document({design!r})
mark("load the design")
v, f = mesh_body.print_mesh(g, 0.01)
mark("build and mesh the body")
mesh_io.stl_bytes(v, f); mesh_io.three_mf_bytes(v, f, doc.name, pause_after_z_mm=[(p.z_mm, p.why) for p in g.pauses])
mesh_io.stl_bytes(*mesh_body.insert_mesh(g)) if g.has_insert else None
mark("STL + 3MF bytes (+ insert.stl)")
""",
    "CAD path (--step)": """
import build123d
mark("import build123d")
from mst_cli.sensor.document import load_design_document
from mst_cli.cad.assembly import build_sensor
from mst_cli.cad import mesh_io
doc, g = load_design_document({design!r})
cad = build_sensor(g)
mark("build + fuse the B-rep body")
with tempfile.TemporaryDirectory() as d:
    mesh_io.write_step(cad.assembly(doc.name), Path(d) / "s.step")
mark("STEP assembly")
""",
}


def stages(body: str) -> list[tuple[str, float]]:
    """Split of one export path, in a fresh interpreter (so the import cost is real)."""
    code = (
        "import time, tempfile\nfrom pathlib import Path\nt = [time.perf_counter()]\n"
        "def mark(name):\n    now = time.perf_counter(); print(name + '|' + repr(now - t[0])); t[0] = now\n"
        + body.format(design=str(DESIGN))
    )
    res = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
    return [(line.split("|")[0], float(line.split("|")[1])) for line in res.stdout.splitlines()]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()
    as_installed()  # commands start from bytecode, as an installed copy does

    mst = mst_exe()
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([mst, "export", str(DESIGN), "--stl", "--out", f"{tmp}/ref"], check=True, capture_output=True)
        cmds = {
            'floor: python -c "import numpy, yaml, click"': ([sys.executable, "-c", "import numpy, yaml, click"], ""),
            "mst export --stl --3mf": (
                [mst, "export", str(DESIGN), "--stl", "--3mf", "--out", f"{tmp}/m{{i}}"],
                "<= 3",
            ),
            "mst export --step": ([mst, "export", str(DESIGN), "--step", "--out", f"{tmp}/s{{i}}"], ""),
            "mst check": ([mst, "check", f"{tmp}/ref"], "<= 3"),
        }
        # round_robin takes (argv, goal, env): every command in this environment
        times = round_robin({name: (argv, goal, None) for name, (argv, goal) in cmds.items()}, args.repeats)
    med = {name: statistics.median(ts) for name, ts in times.items()}
    floor = next(iter(med.values()))
    print(
        f"# bench_export ({args.repeats} rounds, {sys.platform}, python {sys.version.split()[0]}); "
        "3-layer reference design; ratios against the floor measured in the same run"
    )
    print(f"| {'command':<46} | {'median [s]':>10} | {'min / max [s]':>13} | {'x floor':>7} | {'goal':>9} |")
    print(f"|{'-' * 48}|{'-' * 12}|{'-' * 15}|{'-' * 9}|{'-' * 11}|")
    for name, (_, goal) in cmds.items():
        ts, ratio = times[name], med[name] / floor
        mark = "" if not goal else (" ok" if ratio <= float(goal.split()[-1]) else " MISS")
        print(
            f"| {name:<46} | {med[name]:>10.3f} | {min(ts):>5.3f} / {max(ts):<5.3f} | {ratio:>7.2f} "
            f"| {goal + mark:>9} |"
        )
    for path, body in STAGES.items():
        print()
        print(f"{path}, one in-process run:")
        for name, s in stages(body):
            print(f"  {name:<32} {s:7.3f} s")


if __name__ == "__main__":
    main()
