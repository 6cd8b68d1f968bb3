"""Live and file rates of `mst read`, side by side: a pseudo-terminal fed at a board's rate and
flat out, against the same readings from a file. Prints a markdown table; asserts nothing.

    python benchmarks/bench_live.py [--readings 6000] [--rate 2000] [--two-chip]

On the bundled sensor (configs/mohammadi2021-forward.yaml, spring, the default tables built
beside a copy first, not timed), for one chip with --estimate none, offset and shear, and
(--two-chip: its tables take about a minute to build) two chips with shear (all five):

* file: `ForceReader.read` of the readings parsed from a CSV (the pipeline `api.read` runs);
* live at --rate: the lines written to a pseudo-terminal at that rate (batches of 20 lines, on the
  clock) and read by the live session (`mst_cli.readout.live.read_stream`, as `--serial` does):
  the rate it showed samples at, and the lag of a sample behind its line's writing (median, at
  the end): a lag that stays put is keeping up, one that grows is a backlog;
* live flat out: every line written as fast as the port takes it; readings a second.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MST_WORKERS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the pty feed, shared with the tests

import numpy as np
from serial_support import PtyFeed

from mst_cli.calibrate.inverse_table import SHEAR_TABLE_FILE, TABLE_FILE
from mst_cli.calibrate.loadtest import parse_readings
from mst_cli.calibrate.reading import ForceReader
from mst_cli.calibrate.table_reader import build_beside, offset_table_reader, shear_table_reader, two_chip_reader
from mst_cli.model.general_load import field_T, loaded_stack
from mst_cli.readout.live import LiveOptions, read_stream
from mst_cli.sensor.document import load_design_document

ROOT = Path(__file__).resolve().parents[1]
DESIGN = ROOT / "configs" / "mohammadi2021-forward.yaml"
TWO_CHIPS = "  noise_uT_rms: 2.0\n  positions_mm: [[0, 0], [10, 6]]\n"


def one_chip_lines(reader: ForceReader, n: int, rng) -> list[str]:
    """Centred presses over the range with 2 uT noise, as x,y,z lines."""
    imap = reader.inverse_map
    F = rng.uniform(0.05, 0.95, n) * float(imap.force_N[-1])
    Bz = np.interp(F, imap.force_N, imap.B_abs_T) * 1e6
    B = np.column_stack([np.zeros(n), np.zeros(n), Bz]) + rng.normal(0.0, 2.0, (n, 3))
    return [f"{x:.3f},{y:.3f},{z:.3f}" for x, y, z in B]


def two_chip_lines(reader: ForceReader, n: int, rng) -> list[str]:
    """Loads with shear at offsets (40 distinct, repeated) with 2 uT noise, as six-number lines."""
    doc = reader.document
    stack = loaded_stack(doc.geometry(), doc.material, "spring")
    top = float(reader.inverse_map.force_N[-1])
    loads = []
    for _ in range(40):
        F = rng.uniform(0.1, 0.9) * top
        loads.append(
            field_T(stack, F, tuple(rng.uniform(-0.2, 0.2, 2) * F), tuple(rng.uniform(-4, 4, 2)), doc.chips_mm)
        )
    B = np.array([loads[i].ravel() for i in rng.integers(0, len(loads), n)]) * 1e6 + rng.normal(0, 2.0, (n, 6))
    return [",".join(f"{b:.3f}" for b in row) for row in B]


def file_rate(reader: ForceReader, header: str, lines: list[str], offsets) -> float:
    t0 = time.perf_counter()
    rd = parse_readings(header + "\n" + "\n".join(lines) + "\n", "r.csv", need_force=False)
    reader.read(rd, offsets)
    return len(lines) / (time.perf_counter() - t0)


def live(reader: ForceReader, lines: list[str], rate: float | None, offsets) -> tuple[float, float, float]:
    """(samples shown a second, the median lag s, the lag at the end s) of ``lines`` fed at ``rate``."""
    feed = PtyFeed([(line + "\r\n").encode() for line in lines], rate, start=False)
    shown: list[float] = []
    started: list[float] = []

    def start(_: str) -> None:  # the port is open: the board starts printing
        started.append(time.perf_counter())
        feed.start()

    try:
        opts = LiveOptions(count=len(lines), timeout_s=10.0)
        read_stream(reader, feed.port, opts, None, lambda _: shown.append(time.perf_counter()), offsets, start)
    finally:
        feed.close()
    t0, n = started[0], len(shown)
    written = t0 + np.arange(n) / (rate or np.inf)
    lag = np.array(shown) - written
    return n / (shown[-1] - t0), float(np.median(lag)), float(np.mean(lag[-max(1, n // 20) :]))


def row(name: str, reader: ForceReader, header: str, lines: list[str], rate: float, offsets) -> None:
    f = file_rate(reader, header, lines, offsets)
    got, median_lag, end_lag = live(reader, lines, rate, offsets)
    flat, _, _ = live(reader, lines, None, offsets)
    lag = f"{1e3 * median_lag:.0f} / {1e3 * end_lag:.0f}"
    print(f"| {name} | {len(lines)} | {f:,.0f} | {got:,.0f} | {lag} | {flat:,.0f} |")
    sys.stdout.flush()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--readings", type=int, default=6000)
    ap.add_argument("--rate", type=float, default=2000.0, help="lines a second fed to the pseudo-terminal")
    ap.add_argument("--two-chip", action="store_true", help="also two chips, all five (builds their tables)")
    ap.add_argument("--seed", type=int, default=3)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    print(
        f"| path | readings | file: readings/s | live at {args.rate:,.0f}/s: readings/s | "
        "lag median / at the end (ms) | live flat out: readings/s |\n|---|---|---|---|---|---|"
    )
    with tempfile.TemporaryDirectory() as tmp:
        model = Path(tmp) / "model.yaml"
        shutil.copy(DESIGN, model)
        doc, _ = load_design_document(model)
        reader = ForceReader.open(doc, model, "spring")
        top = float(reader.inverse_map.force_N[-1])
        build_beside(model, doc, "spring", 1.0, top).save(model.parent / TABLE_FILE)
        build_beside(model, doc, "spring", 1.0, top, kind="shear").save(model.parent / SHEAR_TABLE_FILE)
        imap = reader.inverse_map
        lines = one_chip_lines(reader, args.readings, rng)
        header = "Bx_uT,By_uT,Bz_uT"
        row("one chip, no estimate", reader, header, lines, args.rate, None)
        offset, _ = offset_table_reader(doc, imap, 1.0, model, "spring", 1.0, False)
        row("one chip, --estimate offset", reader, header, lines, args.rate, offset)
        shear, _ = shear_table_reader(doc, imap, 1.0, model, "spring", False)
        row("one chip, --estimate shear", reader, header, lines, args.rate, shear)
        if args.two_chip:
            two = Path(tmp) / "two" / "model.yaml"
            two.parent.mkdir()
            two.write_text(DESIGN.read_text().replace("  noise_uT_rms: 2.0\n", TWO_CHIPS))
            doc2, _ = load_design_document(two)
            reader2 = ForceReader.open(doc2, two, "spring")
            lines2 = two_chip_lines(reader2, args.readings, rng)
            header2 = "Bx_uT,By_uT,Bz_uT,Bx2_uT,By2_uT,Bz2_uT"
            row("two chips, no estimate", reader2, header2, lines2, args.rate, None)
            est = two_chip_reader(doc2, reader2.inverse_map, 1.0, "spring", False)
            row("two chips, --estimate shear (all five)", reader2, header2, lines2, args.rate, est)


if __name__ == "__main__":
    main()
