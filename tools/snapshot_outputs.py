"""Run every command on the bundled configs and record a digest of each file it writes.

A refactoring that must leave behaviour unchanged is judged by comparing two snapshots, one
taken before and one after (issue 37):

    python tools/snapshot_outputs.py --out /tmp/before     # on the old tree
    python tools/snapshot_outputs.py --out /tmp/after      # on the new tree
    python tools/snapshot_outputs.py --compare /tmp/before /tmp/after

``--only read`` runs only the commands whose code is the calibration, estimation, readout and
firmware packages (issue 45's split), in a few minutes: ``mst calibrate`` on the docs' load test
with both tables (their npz files and headers), and ``mst read`` on the calibrated model plain,
with ``--tare 3``, warm (the load test's rows with ``T_C`` = 30), ``--estimate offset`` and
``--estimate shear`` on off-centre sheared presses (each also ``--polish``-ed by the exact solve),
on the design itself, and on a two-chip copy of it (``positions_mm`` [[0, 0], [10, 6]], as
tests/test_chip_columns.py builds it) plain and with ``--estimate shear``. The other bundled
configs are specs (read only after ``mst design``). The presses' readings are fixed numbers below,
so a change to the model cannot move the inputs; the commands share one fresh ``MST_CACHE_DIR``
(outside the compared folder), so the tables are built by the code under test.

Each file's digest is its SHA-256 after masking what legitimately differs between two runs of
the same code: the package version string, wall-clock timings (JSON keys and text cells that
measure seconds of run time), dates, and the absolute output folder. Binary outputs (PNG, STEP,
3MF) carry timestamps or renderer noise; the PNG's size in pixels and the STEP's and 3MF's
geometry (their STL twin) are compared instead, which is what a user sees; an npz (a zip, its
members stamped with the time written) by its arrays' names, dtypes, shapes and bytes, all but
the hash of the files it was built from (they name the tree's absolute paths). Everything else,
every number of every CSV, JSON, YAML, header and G-code line, must match byte for byte.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = ROOT / "configs"
LOADTEST = ROOT / "docs" / "examples" / "loadtest.csv"

# the forward design's field (uT) at eight presses (0.3-24 N, shear up to 15 % of the force,
# pressed up to 4 mm off centre) plus 2 uT of noise: its one chip, and chips 1 and 2 of its
# two-chip copy (written once by the model, kept as numbers)
ONE_CHIP = """Bx_uT,By_uT,Bz_uT
0.56,3.59,3415.23
1.58,0.42,3464.38
34.30,38.00,3615.36
-72.32,80.80,3861.68
-66.01,-143.83,4024.80
102.51,-18.85,4430.14
-62.25,-45.09,4702.35
140.70,-92.67,5060.74
"""
TWO_CHIPS = """Bx_uT,By_uT,Bz_uT,Bx2_uT,By2_uT,Bz2_uT
1.28,-2.96,3417.15,-1068.99,-641.87,756.33
6.70,1.56,3462.29,-1082.48,-652.78,763.12
-19.33,35.45,3615.45,-1119.80,-666.11,762.83
-14.52,67.13,3881.66,-1186.03,-701.29,775.02
-39.70,138.07,4014.39,-1225.23,-726.21,766.26
11.25,-69.06,4332.54,-1257.68,-745.64,768.16
10.32,-75.66,4755.01,-1332.82,-808.23,753.39
-127.03,-133.04,4974.65,-1333.14,-786.78,714.42
"""

# keys whose values are wall-clock measurements or run identity, not results
VOLATILE_KEY = re.compile(r"(elapsed|runtime|duration|seconds|time_per|timing|speedup|version|date|created)", re.I)
# PrusaSlicer 2.5 slices in threads: two runs of one tree on one input give G-code that differs in
# its paths (print time, filament, the sliced walls' widths); those keys are compared by presence
SLICER_KEY = re.compile(r"(sliced|S_change|R_change|difference_mm|gcode_line|filament|print_time|slice_time)")
TIMING_TEXT = re.compile(r"\d[\d,]*(\.\d+)?\s*(µs|us|ms|s|x)\b")
VOLATILE_TEXT = [
    (re.compile(r"\b\d+\.\d+\.\d+(\.dev\d+)?\b"), "<version>"),
    (re.compile(r"\d{4}-\d\d-\d\dT?[ \d:.+Z-]*"), "<date>"),
]


def _read_inputs(folder: Path) -> dict[str, Path]:
    """The readings files and the two-chip design the read commands take (outside ``work``)."""
    folder.mkdir(parents=True, exist_ok=True)
    fwd = (CONFIGS / "mohammadi2021-forward.yaml").read_text()
    lines = LOADTEST.read_text().splitlines()
    texts = {
        "two.yaml": fwd.replace("  noise_uT_rms: 2.0\n", "  noise_uT_rms: 2.0\n  positions_mm: [[0, 0], [10, 6]]\n"),
        "one_chip.csv": ONE_CHIP,
        "two_chips.csv": TWO_CHIPS,
        "warm.csv": "\n".join([lines[0] + ",T_C"] + [f"{line},30" for line in lines[1:]]) + "\n",
    }
    for name, text in texts.items():
        (folder / name).write_text(text)
    return {name: folder / name for name in texts}


def _read_commands(mst: list[str], work: Path, inputs: dict[str, Path]) -> list[tuple[str, list[str]]]:
    """mst calibrate with both tables, and mst read in every mode on its model (see --only read)."""
    fwd, cal = CONFIGS / "mohammadi2021-forward.yaml", work / "cal-tables"
    model, one, two = cal / "calibrated.yaml", inputs["one_chip.csv"], inputs["two.yaml"]
    reads = [
        ("read-plain", [model, LOADTEST]),
        ("read-tare", [model, LOADTEST, "--tare", "3"]),
        ("read-warm", [model, inputs["warm.csv"]]),
        ("read-offset-presses", [model, one, "--estimate", "offset"]),
        ("read-offset-polish", [model, one, "--estimate", "offset", "--polish"]),
        ("read-shear", [model, one, "--estimate", "shear"]),
        ("read-shear-polish", [model, one, "--estimate", "shear", "--polish"]),
        ("read-design", [fwd, LOADTEST]),
        ("read-two-chips", [two, inputs["two_chips.csv"]]),
        ("read-two-chips-shear", [two, inputs["two_chips.csv"], "--estimate", "shear"]),
    ]
    first = ("calibrate-tables", ["calibrate", fwd, LOADTEST, "--out", cal, "--offset-table", "--shear-table"])
    return [
        (name, [*mst, *map(str, args)])
        for name, args in [first] + [(n, ["read", *a, "--out", work / n]) for n, a in reads]
    ]


def _commands(mst: list[str], work: Path) -> list[tuple[str, list[str]]]:
    fwd = str(CONFIGS / "mohammadi2021-forward.yaml")
    return [
        ("simulate", [*mst, "simulate", fwd, "--out", str(work / "simulate")]),
        ("simulate-offset", [*mst, "simulate", fwd, "--out", str(work / "simulate-offset"), "--load-offset-mm", "3,1"]),
        ("design", [*mst, "design", str(CONFIGS / "mohammadi2021.yaml"), "--out", str(work / "design")]),
        (
            "design-compact",
            [*mst, "design", str(CONFIGS / "mohammadi2021-compact.yaml"), "--out", str(work / "design-compact")],
        ),
        ("export", [*mst, "export", fwd, "--stl", "--3mf", "--step", "--out", str(work / "print")]),
        ("check", [*mst, "check", str(work / "print"), "--json"]),
        ("slice", [*mst, "slice", str(work / "print"), "--out", str(work / "slice")]),
        ("calibrate", [*mst, "calibrate", fwd, str(LOADTEST), "--out", str(work / "cal")]),
        ("read", [*mst, "read", str(work / "cal" / "calibrated.yaml"), str(LOADTEST), "--out", str(work / "read")]),
        (
            "read-offset",
            [
                *mst,
                "read",
                str(work / "cal" / "calibrated.yaml"),
                str(LOADTEST),
                "--estimate-offset",
                "--out",
                str(work / "read-offset"),
            ],
        ),
        ("bench", [*mst, "bench", "--quick", "--samples", "4", "--out", str(work / "bench")]),
    ]


def _mask_json(value, volatile: re.Pattern = VOLATILE_KEY):
    if isinstance(value, dict):
        return {k: ("<masked>" if volatile.search(k) else _mask_json(v, volatile)) for k, v in value.items()}
    if isinstance(value, list):
        return [_mask_json(v, volatile) for v in value]
    if isinstance(value, str):
        return _mask_text(value)
    return value


def _mask_text(text: str) -> str:
    for pattern, repl in VOLATILE_TEXT:
        text = pattern.sub(repl, text)
    return text


def _digest(path: Path, work: Path, root: Path = ROOT) -> str:
    suffix = path.suffix.lower()
    if suffix == ".png":
        from PIL import Image  # deferred: only PNGs need it

        with Image.open(path) as im:
            return f"png {im.size[0]}x{im.size[1]}"
    if suffix in (".step", ".3mf"):
        return f"{suffix[1:]} present"
    if suffix == ".gcode":
        return "gcode present"  # see SLICER_KEY
    if suffix == ".npz":
        return _npz_digest(path)
    raw = path.read_bytes()
    if suffix in (".stl",) and not raw[:5].lower().startswith(b"solid"):
        return hashlib.sha256(raw[80:]).hexdigest()  # binary STL: the 80-byte header names the writer
    # the output folder and the tree the inputs came from (a report names its design file)
    text = raw.decode("utf-8", errors="replace").replace(str(work), "<work>").replace(str(root), "<root>")
    if suffix == ".json":
        with contextlib.suppress(json.JSONDecodeError):  # a JSON file is compared masked, else as text
            volatile = SLICER_KEY if path.name == "slice.json" else VOLATILE_KEY
            text = json.dumps(_mask_json(json.loads(text), volatile), sort_keys=True)
    text = _mask_text(text)
    if suffix == ".md":  # bench.md's timing columns
        text = TIMING_TEXT.sub("<t>", text)
    return hashlib.sha256(text.encode()).hexdigest()


def _npz_digest(path: Path) -> str:
    import numpy as np  # deferred: only the tables need it

    h = hashlib.sha256()
    with np.load(path, allow_pickle=False) as z:
        # source_hash hashes calibration.json's text, which names its inputs' absolute paths:
        # the same tables from two trees differ there alone (the files it hashes are compared)
        for key in sorted(k for k in z.files if k != "source_hash"):
            a = np.ascontiguousarray(z[key])
            h.update(f"{key}|{a.dtype.str}|{a.shape}|".encode() + a.tobytes())
    return h.hexdigest()


def snapshot(out: Path, only: str = "all") -> dict:
    work = out / "work"
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    # this tree's package, whatever the environment has installed
    mst = [sys.executable, "-c", "import sys; from mst_cli.cli.app import main; sys.argv[0] = 'mst'; main()"]
    shutil.rmtree(out / "cache", ignore_errors=True)
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg", "MST_CACHE_DIR": str(out / "cache")}
    record: dict = {"root": str(ROOT), "commands": {}, "files": {}}
    commands = _read_commands(mst, work, _read_inputs(out / "inputs"))
    if only == "all":
        commands = _commands(mst, work) + commands
    for name, cmd in commands:
        t0 = time.perf_counter()
        done = subprocess.run(cmd, capture_output=True, text=True, cwd=work, env=env)
        stdout = done.stdout.replace(str(work), "<work>").replace(str(ROOT), "<root>")
        record["commands"][name] = {"rc": done.returncode}
        (out / f"{name}.stdout").write_text(stdout)
        (out / f"{name}.stderr").write_text(done.stderr)
        print(f"{name:<20} rc {done.returncode}  {time.perf_counter() - t0:6.1f} s", flush=True)
    for path in sorted(p for p in work.rglob("*") if p.is_file()):
        record["files"][str(path.relative_to(work))] = _digest(path, work)
    (out / "snapshot.json").write_text(json.dumps(record, indent=1, sort_keys=True))
    return record


def _stdout_digest(name: str, stdout: str) -> str:
    """What a command printed, its timings (and the slicer's own figures) masked."""
    stdout = TIMING_TEXT.sub("<t>", _mask_text(stdout))
    if name == "slice":  # the slicer's own figures (see SLICER_KEY)
        stdout = re.sub(r"\d+(\.\d+)?", "<n>", stdout)
    return hashlib.sha256(stdout.encode()).hexdigest()


def _load(folder: Path) -> dict:
    """A snapshot's record, its digests taken again with this version's masks (the outputs stay
    in ``folder/work``), so two snapshots compare alike whatever version of this script took them."""
    record = json.loads((folder / "snapshot.json").read_text())
    root, work = Path(record.get("root", "/work/main")), folder / "work"
    if work.is_dir():
        files = sorted(p for p in work.rglob("*") if p.is_file())
        record["files"] = {str(p.relative_to(work)): _digest(p, work, root) for p in files}
    for name, entry in record["commands"].items():
        stdout = (folder / f"{name}.stdout").read_text().replace(str(root), "<root>")
        entry["stdout"] = _stdout_digest(name, stdout)
        entry.pop("stdout_sha256", None)
    return record


def compare(before: Path, after: Path) -> int:
    a, b = _load(before), _load(after)
    bad = 0
    for section in ("commands", "files"):
        for key in sorted(set(a[section]) | set(b[section])):
            if a[section].get(key) != b[section].get(key):
                bad += 1
                print(f"differs: {section} {key}: {a[section].get(key)} != {b[section].get(key)}")
    n = len(a["files"])
    print(f"{len(a['commands'])} commands, {n} files compared: {'identical' if not bad else f'{bad} differ'}")
    return 1 if bad else 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, help="folder for a new snapshot")
    parser.add_argument("--compare", nargs=2, type=Path, metavar=("BEFORE", "AFTER"))
    parser.add_argument(
        "--only", choices=("all", "read"), default="all", help="read: only mst calibrate and mst read (a few minutes)"
    )
    args = parser.parse_args()
    if args.compare:
        return compare(*args.compare)
    if not args.out:
        parser.error("give --out DIR or --compare BEFORE AFTER")
    snapshot(args.out, args.only)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
