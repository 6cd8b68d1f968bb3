"""Running PrusaSlicer's command line: find it, check a profile, slice a model, read a mesh.

Errors the user can fix are :class:`~mst_cli.errors.InputError` (one line, exit 2): the
slicer is not installed (with how to install it), the profile is not a PrusaSlicer config
(with the reason). A slicer that fails on a valid input raises :class:`SlicerError`.
"""

from __future__ import annotations

import functools
import os
import re
import shutil
import subprocess
import tempfile
import time
import zipfile
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from mst_cli.cad.deterministic import PRUSA_CUSTOM_GCODE_MEMBER, PRUSA_PAUSE_PRINT_TYPE
from mst_cli.errors import InputError
from mst_cli.io.files import read_input_text

EXECUTABLES = ("prusa-slicer", "PrusaSlicer", "prusa-slicer-console")
ENV_EXECUTABLE = "MST_PRUSA_SLICER"
INSTALL_HINT = (
    "install it with 'sudo apt-get install prusa-slicer' (Debian/Ubuntu), or get "
    "PrusaSlicer from https://www.prusa3d.com/prusaslicer/ and put it on PATH "
    f"or in ${ENV_EXECUTABLE}"
)
DEFAULT_TIMEOUT_S = 300.0
PROFILE_NAME = "tpu85a-0.4mm.ini"
MAX_PROFILE_BYTES = 1_000_000  # a full PrusaSlicer config is about 20 KB


GCODE_END = "; prusaslicer_config = end"  # the last line of every G-code PrusaSlicer writes


class SlicerError(RuntimeError):
    """PrusaSlicer ran but did not produce what it was asked for: no file, an empty or
    truncated one, or one that is not text (the message says which; exit 1, a machine fault)."""


def _no_output(r: subprocess.CompletedProcess, what: str) -> str:
    """Why PrusaSlicer wrote no ``what``: its last error line, or that it claimed success."""
    if r.returncode == 0:
        return f"exited 0 but wrote no {what}"
    lines = _clean(r.stderr + "\n" + r.stdout)
    errors = [s for s in lines if "rror" in s or "annot" in s or "nvalid" in s] or lines
    return errors[-1] if errors else f"exit code {r.returncode}, no {what} written"


def bundled_profile() -> Path:
    """The TPU 85A profile shipped as package data (``mst_cli/cad/data``): found the same way in
    an editable and a regular install (pip installs packages as files, so it is a real path
    PrusaSlicer can load)."""
    return Path(str(resources.files("mst_cli.cad").joinpath("data", PROFILE_NAME)))


def find_prusa_slicer() -> str:
    """Path of the PrusaSlicer executable; InputError (exit 2) naming how to install it."""
    env = os.environ.get(ENV_EXECUTABLE)
    if env:
        found = shutil.which(env)
        if found:
            return found
        raise InputError(ENV_EXECUTABLE, env, "is not an executable PrusaSlicer; " + INSTALL_HINT)
    for name in EXECUTABLES:
        found = shutil.which(name)
        if found:
            return found
    raise InputError("prusa-slicer", "not found on PATH", INSTALL_HINT)


def _clean(stderr: str) -> list[str]:
    """PrusaSlicer's output without its boost trace and progress lines."""
    keep = []
    for line in stderr.splitlines():
        s = line.strip()
        if not s or "[trace]" in s or "[debug]" in s or "[info]" in s or re.match(r"^\d+ => ", s):
            continue
        keep.append(s)
    return keep


def _run(args: list[str], timeout_s: float) -> subprocess.CompletedProcess:
    try:
        return subprocess.run(
            args, capture_output=True, text=True, timeout=timeout_s, env={**os.environ, "LC_ALL": "C"}
        )
    except subprocess.TimeoutExpired:
        raise SlicerError(f"prusa-slicer did not finish within {timeout_s:g} s") from None
    except OSError as exc:
        raise InputError("prusa-slicer", args[0], f"cannot be run ({exc.strerror}); " + INSTALL_HINT) from None


@functools.lru_cache(maxsize=4)
def known_options(exe: str) -> frozenset[str]:
    """The option names this PrusaSlicer writes in a full config (its ``--save`` of defaults)."""
    with tempfile.TemporaryDirectory(prefix="mst-prusa-") as tmp:
        out = Path(tmp) / "defaults.ini"
        r = _run([exe, "--save", str(out)], 60)
        if not out.is_file():
            raise SlicerError(f"prusa-slicer --save (its default config) failed: {_no_output(r, 'config')}")
        try:
            keys = frozenset(parse_ini(out.read_text(encoding="utf-8"), str(out)).keys())
        except (InputError, UnicodeDecodeError):
            keys = frozenset()
        if not keys:
            raise SlicerError("prusa-slicer --save wrote a default config that is empty or not one")
        return keys


def parse_ini(text: str, where: str = "profile") -> dict[str, str]:
    """``key = value`` lines of a PrusaSlicer config; '#' and ';' start comment lines.
    InputError naming the first line that is not a setting."""
    values: dict[str, str] = {}
    for n, line in enumerate(text.splitlines(), start=1):
        s = line.strip()
        if not s or s[0] in "#;":
            continue
        if s.startswith("[") and s.endswith("]"):
            raise InputError(
                "--profile",
                where,
                f"line {n} '{s}' is a section header: this is a config bundle, not one "
                "PrusaSlicer config (export one with File > Export > Export Config)",
            )
        if "=" not in s:
            raise InputError("--profile", where, f"line {n} is not 'key = value': {s[:60]!r}")
        key, value = s.split("=", 1)
        key = key.strip()
        if key in values:
            raise InputError("--profile", where, f"line {n}: '{key}' is set twice")
        values[key] = value.strip()
    return values


def check_profile(path: Path, exe: str) -> dict[str, str]:
    """The settings of a PrusaSlicer FFF config, or InputError (exit 2) with the reason."""
    path = Path(path)
    if not path.exists():
        raise InputError("--profile", str(path), "no such file (a PrusaSlicer .ini config)")
    text = read_input_text(path, MAX_PROFILE_BYTES, field="--profile", what="PrusaSlicer .ini config")
    values = parse_ini(text, str(path))
    if not values:
        raise InputError("--profile", str(path), "holds no settings: not a PrusaSlicer config")
    known = known_options(exe)
    unknown = sorted(k for k in values if k not in known)
    if unknown:
        raise InputError(
            "--profile",
            str(path),
            f"'{unknown[0]}' is not a PrusaSlicer option"
            + (f" ({len(unknown)} unknown keys)" if len(unknown) > 1 else "")
            + ": not a PrusaSlicer config for this version",
        )
    if values.get("printer_technology", "FFF") != "FFF":
        raise InputError(
            "--profile", str(path), f"printer_technology = {values['printer_technology']}: an FFF config is needed"
        )
    return values


def bed_centre(values: dict[str, str]) -> tuple[float, float]:
    """Centre of the bounding box of ``bed_shape`` (default PrusaSlicer bed 200 x 200)."""
    pts = []
    for p in values.get("bed_shape", "0x0,200x0,200x200,0x200").split(","):
        try:
            x, y = p.split("x")
            pts.append((float(x), float(y)))
        except ValueError:
            continue
    if not pts:
        return 100.0, 100.0
    a = np.array(pts)
    return float((a[:, 0].min() + a[:, 0].max()) / 2), float((a[:, 1].min() + a[:, 1].max()) / 2)


@dataclass
class SliceRun:
    gcode_path: Path
    seconds: float
    messages: list[str]


def slice_model(
    exe: str,
    model: Path,
    profile: Path,
    out_gcode: Path,
    centre_xy: tuple[float, float],
    extra_args: tuple[str, ...] = (),
    timeout_s: float = DEFAULT_TIMEOUT_S,
) -> SliceRun:
    """``prusa-slicer --export-gcode --load PROFILE --center X,Y [extra] MODEL --output OUT``.

    ``--center`` puts the centre of the model's bounding box (x, y) at ``centre_xy`` and the
    model is dropped onto the bed (its lowest point at z = 0), so G-code = model + shift.
    """
    out_gcode = Path(out_gcode)
    if out_gcode.exists():
        out_gcode.unlink()
    args = [
        exe,
        "--export-gcode",
        "--load",
        str(profile),
        "--center",
        f"{centre_xy[0]:g},{centre_xy[1]:g}",
        *extra_args,
        str(model),
        "--output",
        str(out_gcode),
    ]
    t0 = time.perf_counter()
    r = _run(args, timeout_s)
    seconds = time.perf_counter() - t0
    lines = _clean(r.stderr + "\n" + r.stdout)
    if r.returncode != 0 or not out_gcode.is_file():
        message = _no_output(r, "G-code")
        if "reading config file" in message or "config" in message.lower() and "load" in message.lower():
            raise InputError("--profile", str(profile), f"PrusaSlicer rejects it: {message}")
        raise SlicerError(f"prusa-slicer failed on {model.name}: {message}")
    return SliceRun(out_gcode, seconds, lines)


def read_gcode(path: Path) -> str:
    """The text of G-code PrusaSlicer wrote; SlicerError when it is empty, not text, or ends
    before its closing config block (truncated: a full disk, a killed slicer, a post-process
    script that cut it)."""
    data = Path(path).read_bytes()
    if not data.strip():
        raise SlicerError(f"prusa-slicer wrote an empty G-code file ({Path(path).name})")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise SlicerError(f"prusa-slicer wrote G-code that is not UTF-8 text (byte {exc.start})") from None
    if text.rstrip().rsplit("\n", 1)[-1].strip() != GCODE_END:
        raise SlicerError(f"prusa-slicer wrote G-code that ends before its closing '{GCODE_END}' line: it is truncated")
    return text


def post_process_scripts(values: dict[str, str]) -> list[str]:
    """The scripts a profile's ``post_process`` makes PrusaSlicer run on the G-code it writes
    (one per line; the .ini writes a line break as the two characters backslash, n)."""
    text = values.get("post_process", "").replace("\\n", "\n")
    return [s.strip() for s in text.splitlines() if s.strip()]


def slicer_version(exe: str) -> str:
    r = _run([exe, "--help"], 60)
    for line in (r.stdout + "\n" + r.stderr).splitlines():
        m = re.match(r"\s*(PrusaSlicer-\S+)", line)
        if m:
            return m.group(1)
    return "PrusaSlicer (version unknown)"


# --------------------------------------------------------------------------- meshes
def read_stl(path: Path) -> np.ndarray:
    """(m, 3, 3) triangle corners of a binary or ASCII STL, mm."""
    data = Path(path).read_bytes()
    if len(data) >= 84:
        n = int(np.frombuffer(data[80:84], dtype="<u4")[0])
        if 84 + 50 * n == len(data):
            rec = np.frombuffer(data[84:], dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]))
            return rec["v"].astype(float)
    nums = re.findall(rb"vertex\s+(\S+)\s+(\S+)\s+(\S+)", data)
    return np.array(nums, dtype=float).reshape(-1, 3, 3)


def read_3mf(path: Path) -> np.ndarray:
    """(m, 3, 3) triangle corners of the meshes of a 3MF package (build transforms ignored)."""
    tris = []
    with zipfile.ZipFile(path) as zf:
        for name in zf.namelist():
            if not name.endswith(".model"):
                continue
            text = zf.read(name).decode("utf-8")
            for mesh in re.findall(r"<mesh>(.*?)</mesh>", text, re.DOTALL):
                v = np.array(
                    re.findall(r'<vertex\s+x="([^"]+)"\s+y="([^"]+)"\s+z="([^"]+)"', mesh), dtype=float
                ).reshape(-1, 3)
                t = np.array(
                    re.findall(r'<triangle\s+v1="(\d+)"\s+v2="(\d+)"\s+v3="(\d+)"', mesh), dtype=np.int64
                ).reshape(-1, 3)
                tris.append(v[t])
    return np.concatenate(tris) if tris else np.zeros((0, 3, 3))


def has_prusa_pause(path: Path) -> bool:
    """True when a 3MF carries PrusaSlicer per-height custom G-code with a pause."""
    try:
        with zipfile.ZipFile(path) as zf:
            text = zf.read(PRUSA_CUSTOM_GCODE_MEMBER).decode("utf-8")
    except (KeyError, OSError, zipfile.BadZipFile):
        return False
    return f'type="{PRUSA_PAUSE_PRINT_TYPE}"' in text
