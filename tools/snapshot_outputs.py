"""Run every command on the bundled configs and record a digest of each file it writes.

A refactoring that must leave behaviour unchanged is judged by comparing two snapshots, one
taken before and one after (issue 37):

    python tools/snapshot_outputs.py --out /tmp/before     # on the old tree
    python tools/snapshot_outputs.py --out /tmp/after      # on the new tree
    python tools/snapshot_outputs.py --compare /tmp/before /tmp/after

Each file's digest is its SHA-256 after masking what legitimately differs between two runs of
the same code: the package version string, wall-clock timings (JSON keys and text cells that
measure seconds of run time), dates, and the absolute output folder. Binary outputs (PNG, STEP,
3MF) carry timestamps or renderer noise; the PNG's size in pixels and the STEP's and 3MF's
geometry (their STL twin) are compared instead, which is what a user sees. Everything else,
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
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = ROOT / "configs"
LOADTEST = ROOT / "docs" / "examples" / "loadtest.csv"

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


def snapshot(out: Path) -> dict:
    work = out / "work"
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    # this tree's package, whatever the environment has installed
    mst = [sys.executable, "-c", "import sys; from mst_cli.cli.app import main; sys.argv[0] = 'mst'; main()"]
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    record: dict = {"root": str(ROOT), "commands": {}, "files": {}}
    for name, cmd in _commands(mst, work):
        done = subprocess.run(cmd, capture_output=True, text=True, cwd=work, env=env)
        stdout = done.stdout.replace(str(work), "<work>").replace(str(ROOT), "<root>")
        record["commands"][name] = {"rc": done.returncode}
        (out / f"{name}.stdout").write_text(stdout)
        (out / f"{name}.stderr").write_text(done.stderr)
        print(f"{name:<16} rc {done.returncode}", flush=True)
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
    args = parser.parse_args()
    if args.compare:
        return compare(*args.compare)
    if not args.out:
        parser.error("give --out DIR or --compare BEFORE AFTER")
    snapshot(args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
