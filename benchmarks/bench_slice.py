"""Speed of `mst slice` (issue 9). Prints a markdown table; asserts nothing.

    python benchmarks/bench_slice.py [--repeats N]

On the reference export (configs/mohammadi2021-forward.yaml, `mst export --stl --3mf`):

* PrusaSlicer's own slice time (as `mst slice` runs it: the profile as given, then again
  with automatic support on, which `mst slice` uses to prove no support is needed);
* parsing its G-code (:func:`mst_cli.cad.gcode.parse_gcode`);
* the free-span analysis (:func:`mst_cli.cad.layer_measure.free_spans`, per move and with joined moves);
* the wall time of the whole `mst slice` command, interpreter start included (with and
  without drawing print.png);

and the free-span analysis on a synthetic 100-layer G-code (a 30 x 20 mm solid hatch plus 100
random strokes per layer; the timed unit test that used to live in tests/test_slice.py).
Every figure is the median of --repeats runs (min / max alongside). Needs prusa-slicer.
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
from user_env import as_installed

ROOT = Path(__file__).resolve().parents[1]
DESIGN = ROOT / "configs" / "mohammadi2021-forward.yaml"
W = 0.45


def mst_cmd() -> list[str]:
    exe = Path(sys.executable).with_name("mst")
    return [str(exe) if exe.exists() else "mst"]


def timed(fn, repeats: int) -> tuple[list[float], object]:
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return times, out


def synthetic_gcode(n_layers: int = 100, seed: int = 1) -> str:
    """100 layers of 0.2 mm: a 30 x 20 mm hatch at 0.45 mm pitch plus 100 random strokes each."""
    rng = np.random.default_rng(seed)
    out, e = ["G90", "M83", "G92 E0"], 0.0
    for k in range(1, n_layers + 1):
        ys = np.arange(W / 2, 20 - W / 2 + 1e-9, W)
        segs = [(W / 2, y, 30 - W / 2, y) for y in ys] + [tuple(v) for v in rng.uniform(0, 20, (100, 4))]
        out += [
            ";LAYER_CHANGE",
            f";Z:{0.2 * k:.1f}",
            ";HEIGHT:0.2",
            f"G1 Z{0.2 * k:.1f}",
            ";TYPE:Solid infill",
            f";WIDTH:{W}",
        ]
        for x0, y0, x1, y1 in segs:
            out.append(f"G1 X{x0:.3f} Y{y0:.3f} F600")
            de = 0.03 * np.hypot(x1 - x0, y1 - y0)
            e += de
            out.append(f"G1 X{x1:.3f} Y{y1:.3f} E{de:.5f}")
    out.append("; estimated printing time (normal mode) = 1h 2m 3s")
    return "\n".join(out) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    as_installed()  # commands start from bytecode, as an installed copy does
    n = max(1, args.repeats)

    from mst_cli.cad import gcode as G
    from mst_cli.cad import layer_measure as M
    from mst_cli.cad import slicer as S

    exe = S.find_prusa_slicer()
    profile = S.bundled_profile()
    settings = S.check_profile(profile, exe)
    centre = S.bed_centre(settings)
    rows = []

    def row(name, times, unit="s", note=""):
        rows.append((name, f"{statistics.median(times):.3f}", f"{min(times):.3f} / {max(times):.3f}", note))

    with tempfile.TemporaryDirectory(prefix="bench-slice-") as tmp:
        tmp = Path(tmp)
        export = tmp / "ref"
        subprocess.run(
            mst_cmd() + ["export", str(DESIGN), "--stl", "--3mf", "--out", str(export)], check=True, capture_output=True
        )
        model = export / "sensor.3mf"
        t_plain, run = timed(lambda: S.slice_model(exe, model, profile, tmp / "a.gcode", centre), n)
        t_support, _ = timed(
            lambda: S.slice_model(
                exe, model, profile, tmp / "b.gcode", centre, ("--support-material", "--support-material-auto")
            ),
            n,
        )
        text = run.gcode_path.read_text()
        t_parse, g = timed(lambda: G.parse_gcode(text), n)
        t_span, spans = timed(lambda: M.free_spans(g), n)
        t_joined, _ = timed(lambda: M.free_spans(g, join_moves=True), n)
        moves = sum(len(lay.segments) for lay in g.layers)
        t_cli, _ = timed(
            lambda: subprocess.run(
                mst_cmd() + ["slice", str(export), "--out", str(tmp / "c")], check=True, capture_output=True
            ),
            n,
        )
        t_cli_np, _ = timed(
            lambda: subprocess.run(
                mst_cmd() + ["slice", str(export), "--no-plot", "--out", str(tmp / "d")],
                check=True,
                capture_output=True,
            ),
            n,
        )

    ref = f"{len(g.layers)} layers, {moves} moves, {len(text) / 1e6:.1f} MB"
    row("PrusaSlicer slice, reference 3MF [s]", t_plain, note=ref)
    row("PrusaSlicer slice with auto support [s]", t_support)
    row("parse G-code [s]", t_parse)
    row("free spans, per move [s]", t_span, note=f"longest {spans.longest.length_mm:.2f} mm")
    row("free spans, joined moves [s]", t_joined)
    row("mst slice (wall, with print.png) [s]", t_cli, note="interpreter start, 2 slices, analysis, plot")
    row("mst slice --no-plot (wall) [s]", t_cli_np)

    syn = synthetic_gcode()
    t_sparse, gs = timed(lambda: G.parse_gcode(syn), n)
    t_sspan, _ = timed(lambda: M.free_spans(gs), n)
    smoves = sum(len(lay.segments) for lay in gs.layers)
    row("synthetic 100 layers: parse G-code [s]", t_sparse, note=f"{len(gs.layers)} layers, {smoves} moves")
    row("synthetic 100 layers: free spans [s]", t_sspan)

    print(f"# bench_slice ({n} repeats, {S.slicer_version(exe)}, {sys.platform}, python {sys.version.split()[0]})")
    print(f"| {'measure':<42} | {'median':>7} | {'min / max':>15} | note |")
    print(f"|{'-' * 44}|{'-' * 9}|{'-' * 17}|------|")
    for name, med, mm, note in rows:
        print(f"| {name:<42} | {med:>7} | {mm:>15} | {note} |")


if __name__ == "__main__":
    main()
