"""Live and file rates of `mst read`, side by side: a pseudo-terminal fed at a board's rate and
flat out, against the same readings from a file. Prints a markdown table; asserts nothing.

    python benchmarks/bench_live.py [--readings 4000] [--two-chip-readings 1000] [--rate 2000] [--repeats 3]
                                    [--one-chip | --two-chip]

On the bundled sensor (configs/mohammadi2021-forward.yaml, spring; its offset and shear tables
found or built as `mst read` does, kept in the cache for the next run: the first run builds them,
minutes, not timed), one chip with --estimate none, offset and shear, and (unless --one-chip) two
chips at (0, 0) and (10, 6) mm with none and shear (all five; their tables take about a minute):

* file: `ForceReader.read` of the readings parsed from a CSV (the pipeline `api.read` runs), and
  the estimate alone (the estimator's `estimate_all` on the same readings): their ratio is the
  share of the file's time the estimate takes;
* live at --rate: the lines written to a pseudo-terminal at that rate (batches of 20 lines, on the
  clock, by a process of its own, as a board writes) and read by the live session
  (`mst_cli.readout.live.read_stream`, as `--serial` does): the rate it showed samples at (from
  the first line written to the last shown), the lag of a sample behind its line's writing
  (median, and at the end), and how fast the lag grows from the middle of the stream to its end
  (ms per s of stream: about 0 keeps up, rate / live rate - 1 is a backlog, quoted when larger:
  one batch can hold the whole stream); "keeps up" when it grows by less than 50 ms a second past
  the session's start and a sample is shown within 1 s of its writing at the end;
* live flat out: every line written as fast as the port takes it; readings a second.

Every figure is the median of --repeats runs, the rows measured round robin in one run, so a
shared machine's load hits every row alike.
"""

from __future__ import annotations

import argparse
import os
import pty
import shutil
import subprocess
import sys
import tempfile
import time
import tty
from pathlib import Path

os.environ.setdefault("MST_WORKERS", "1")

import numpy as np

from mst_cli.calibration.loadtest import parse_readings
from mst_cli.estimation.table_reader import offset_table_reader, shear_table_reader, two_chip_reader
from mst_cli.model.general_load import field_T, loaded_stack
from mst_cli.readout.live import LiveOptions, read_stream
from mst_cli.readout.reading import ForceReader
from mst_cli.sensor.document import load_design_document

ROOT = Path(__file__).resolve().parents[1]
DESIGN = ROOT / "configs" / "mohammadi2021-forward.yaml"
TWO_CHIPS = "  noise_uT_rms: 2.0\n  positions_mm: [[0, 0], [10, 6]]\n"
FEED_BATCH = 20  # lines the feed writes at once (PtyFeed's)
BACKLOG_S_PER_S = 0.05  # a lag growing faster than this (s a s of stream) is a backlog ...
MAX_LAG_S = 1.0  # ... and so is one longer than this at the end (one batch held the stream)


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


def file_rates(reader: ForceReader, header: str, lines: list[str], offsets) -> tuple[float, float]:
    """(readings/s of the file's pipeline, of the estimate alone; nan without one)."""
    t0 = time.perf_counter()
    rd = parse_readings(header + "\n" + "\n".join(lines) + "\n", "r.csv", need_force=False)
    got = reader.read(rd, offsets)
    rate = len(lines) / (time.perf_counter() - t0)
    if offsets is None:
        return rate, float("nan")
    B = rd.B_T if getattr(offsets, "chips", 1) == 1 else rd.B_chips_T
    t0 = time.perf_counter()
    offsets.estimate_all(B, got.force_centred_N)
    return rate, len(lines) / (time.perf_counter() - t0)


FEEDER = """
import os, sys, time
fd, rate, batch = int(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3])
lines = open(sys.argv[4], "rb").read().splitlines(keepends=True)
sys.stdin.readline()  # the port is open: start
t0 = time.perf_counter()
written = []
for i in range(0, len(lines), batch):
    if rate > 0:
        time.sleep(max(0.0, t0 + i / rate - time.perf_counter()))
    os.write(fd, b"".join(lines[i : i + batch]))
    written.append(time.perf_counter())
print(" ".join(repr(t) for t in written), flush=True)
"""


class ProcessFeed:
    """A board on a pseudo-terminal: a process of its own (not a thread of the reader's, which
    the estimate would hold back) writes ``lines`` ``rate`` lines a second (None: flat out) in
    batches of FEED_BATCH from :meth:`start`, and says when it wrote each batch."""

    def __init__(self, lines: list[str], rate: float | None, folder: Path):
        self.master, self.slave = pty.openpty()
        tty.setraw(self.slave)
        self.port = os.ttyname(self.slave)
        text = folder / "lines.txt"
        text.write_bytes(b"".join((line + "\r\n").encode() for line in lines))
        args = [sys.executable, "-c", FEEDER, str(self.master), str(rate or 0.0), str(FEED_BATCH), str(text)]
        self.proc = subprocess.Popen(args, stdin=subprocess.PIPE, stdout=subprocess.PIPE, pass_fds=(self.master,))

    def start(self) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(b"go\n")
        self.proc.stdin.flush()

    def written(self) -> np.ndarray:
        """When each line was written (perf_counter s; a batch's lines at once)."""
        out, _ = self.proc.communicate(timeout=60)
        return np.repeat([float(t) for t in out.split()], FEED_BATCH)

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        os.close(self.master)
        os.close(self.slave)


def live(reader: ForceReader, lines: list[str], rate: float | None, offsets) -> tuple[float, float, float, float]:
    """(samples shown a second, the median lag s, the lag at the end s, the lag's growth s/s) of
    ``lines`` fed at ``rate`` (None: flat out); the lag of a sample is from its line's writing to
    its showing, its growth that from the first quarter's median to the end over the stream."""
    shown: list[float] = []
    with tempfile.TemporaryDirectory() as tmp:
        feed = ProcessFeed(lines, rate, Path(tmp))
        try:
            opts = LiveOptions(count=len(lines), timeout_s=30.0)
            show = lambda _: shown.append(time.perf_counter())  # noqa: E731
            read_stream(reader, feed.port, opts, None, show, offsets, lambda _: feed.start())
            written = feed.written()[: len(shown)]
        finally:
            feed.close()
    n, q = len(shown), len(shown) // 4
    lag = np.array(shown) - written
    end = float(np.mean(lag[-max(1, n // 20) :]))
    middle = float(np.median(lag[2 * q : 2 * q + max(1, n // 20)]))  # past the start's transient
    growth = (end - middle) / max(written[-1] - written[2 * q], 1e-9)
    return n / (shown[-1] - written[0]), float(np.median(lag)), end, growth


class Row:
    """One path's readings, reader and estimator, and its measurements over the repeats."""

    def __init__(self, name: str, reader: ForceReader, header: str, lines: list[str], offsets):
        self.name, self.reader, self.header, self.lines, self.offsets = name, reader, header, lines, offsets
        self.runs: list[tuple[float, ...]] = []

    def measure(self, rate: float) -> None:
        f, est = file_rates(self.reader, self.header, self.lines, self.offsets)
        got, median_lag, end_lag, growth = live(self.reader, self.lines, rate, self.offsets)
        flat = live(self.reader, self.lines, None, self.offsets)[0]
        self.runs.append((f, est, got, median_lag, end_lag, growth, flat))

    def line(self, rate: float) -> str:
        f, est, got, median_lag, end_lag, growth, flat = np.median(np.array(self.runs), axis=0)
        share = f"{est:,.0f} ({100 * f / est:.0f} %)" if np.isfinite(est) else "-"
        keeps = growth < BACKLOG_S_PER_S and end_lag < MAX_LAG_S
        verdict = "keeps up" if keeps else f"backlog: lag +{1e3 * max(growth, rate / got - 1.0):,.0f} ms/s"
        return (
            f"| {self.name} | {len(self.lines)} | {f:,.0f} | {share} | {got:,.0f} | {got / f:.2f} | "
            f"{1e3 * median_lag:,.0f} / {1e3 * end_lag:,.0f} | {verdict} | {flat:,.0f} | {flat / rate:.2f} |"
        )


def one_chip_rows(tmp: Path, n: int, rng) -> list[Row]:
    model = tmp / "one" / "model.yaml"
    model.parent.mkdir()
    shutil.copy(DESIGN, model)
    doc, _ = load_design_document(model)
    reader = ForceReader.open(doc, model, "spring")
    imap = reader.inverse_map
    offset, _ = offset_table_reader(doc, imap, 1.0, model, "spring", 1.0, False)  # the cache's, else built
    shear, _ = shear_table_reader(doc, imap, 1.0, model, "spring", False)
    lines = one_chip_lines(reader, n, rng)
    header = "Bx_uT,By_uT,Bz_uT"
    return [
        Row("one chip, no estimate", reader, header, lines, None),
        Row("one chip, `--estimate offset`", reader, header, lines, offset),
        Row("one chip, `--estimate shear`", reader, header, lines, shear),
    ]


def two_chip_rows(tmp: Path, n: int, rng) -> list[Row]:
    model = tmp / "two" / "model.yaml"
    model.parent.mkdir()
    model.write_text(DESIGN.read_text().replace("  noise_uT_rms: 2.0\n", TWO_CHIPS))
    doc, _ = load_design_document(model)
    reader = ForceReader.open(doc, model, "spring")
    lines = two_chip_lines(reader, n, rng)
    header = "Bx_uT,By_uT,Bz_uT,Bx2_uT,By2_uT,Bz2_uT"
    est = two_chip_reader(doc, reader.inverse_map, 1.0, "spring", False)
    return [
        Row("two chips, no estimate", reader, header, lines, None),
        Row("two chips, `--estimate shear` (all five)", reader, header, lines, est),
    ]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--readings", type=int, default=4000)
    ap.add_argument("--rate", type=float, default=2000.0, help="lines a second fed to the pseudo-terminal")
    ap.add_argument("--repeats", type=int, default=3, help="runs of every row (the median is printed)")
    ap.add_argument("--one-chip", action="store_true", help="one chip only (no two-chip tables to build)")
    ap.add_argument("--two-chip", action="store_true", help="two chips only (no one-chip tables to find)")
    ap.add_argument("--two-chip-readings", type=int, default=1000, help="readings of the two-chip rows")
    ap.add_argument("--seed", type=int, default=3)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    with tempfile.TemporaryDirectory() as tmp:
        rows = [] if args.two_chip else one_chip_rows(Path(tmp), args.readings, rng)
        if not args.one_chip:
            rows += two_chip_rows(Path(tmp), args.two_chip_readings, rng)
        for k in range(args.repeats):
            for row in rows:
                print(f"run {k + 1}/{args.repeats}: {row.name}", file=sys.stderr, flush=True)
                row.measure(args.rate)
    print(
        f"| path | readings | file: readings/s | the estimate alone: readings/s (its share of the file's time) | "
        f"live at {args.rate:,.0f}/s: readings/s | live / file | lag median / at the end (ms) | "
        f"backlog | live flat out: readings/s | flat out / {args.rate:,.0f} |\n" + "|---" * 10 + "|"
    )
    for row in rows:
        print(row.line(args.rate))
    print(f"\nmedians of {args.repeats} runs; load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
