"""Regenerate every bundled example data file from the current model (deterministic: fixed seeds).

The files are synthetic measurements of a known print of the default part, so they change when
the forward model does (a layer law, a member's compliance, the insert): re-run this after such
a change and commit what it writes. tests/test_examples.py fails, naming this command, while a
bundled file differs from what it writes.

* ``docs/examples/loadtest.csv``: 60 load-test samples (seed 11) of the known printed sensor of
  studies/printed_sensor.py (the forward design with walls +0.05 mm, modulus x0.85, the board
  0.3 mm further, remanence x0.95; 2 uT noise, the chip's LSB); docs/examples/calibrate_and_read.py
  calibrates it and recovers those values.

Run:  python tools/make_examples.py [--check]
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "studies"))

from printed_sensor import loadtest_csv  # noqa: E402  (studies/ is not a package)

# every bundled example data file, and the function that writes its text
EXAMPLES: dict[Path, Callable[[], str]] = {ROOT / "docs" / "examples" / "loadtest.csv": loadtest_csv}


def stale() -> list[Path]:
    """The bundled files that differ from what the current model writes."""
    return [path for path, make in EXAMPLES.items() if not path.exists() or path.read_text() != make()]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="write nothing; exit 1 naming the files that are stale")
    args = ap.parse_args()
    if args.check:
        old = stale()
        for path in old:
            print(f"stale: {path.relative_to(ROOT)}")
        return 1 if old else 0
    for path, make in EXAMPLES.items():
        text = make()
        changed = not path.exists() or path.read_text() != text
        path.write_text(text)
        print(f"{'wrote' if changed else 'unchanged'}: {path.relative_to(ROOT)} ({len(text.splitlines()) - 1} rows)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
