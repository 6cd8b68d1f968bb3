"""Hostile input and faults (issues 13 and 22): no traceback, no hang, no silent acceptance,
nothing half-written. One section per class of the issues; each holds at least one test that
failed on the tree before the fix. Sections 8 and 17 are the property suites: hostile documents
generated from the schema's own rules, run through ``mst simulate`` in-process; load tests and
readings from their column rules, export.json from the Manifest type (through ``mst check`` and
``mst slice``), slicer results, and designs at their bounds through what export writes.

Tests that send signals set the dispositions they rely on in the child (a background or nohup
shell starts children with SIGINT/SIGHUP ignored); the suite passes from a terminal, a pipe or
a background shell."""

import contextlib
import errno
import json
import math
import os
import re
import signal
import subprocess
import sys
import tempfile
import textwrap
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml
from click.testing import CliRunner
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st
from slicer_support import need_slicer

from mst_cli.cli.app import main
from mst_cli.io.outputs import STAGING_PREFIX, Staging, staged
from mst_cli.sensor.document import load_document
from mst_cli.sensor.sections import LAYER_RULES, SECTIONS, TOP_KEYS
from mst_cli.version import package_version

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"
SPEC = ROOT / "configs" / "fingertip.yaml"
PYTHON = sys.executable
LAYER = {"theta_deg": 25, "t_mm": 0.6, "h_mm": 2.0}
OUTPUTS = {"report.json", "response.csv", "response.png"}


def run(args, **kwargs):
    return CliRunner().invoke(main, [str(a) for a in args], **kwargs)


def timed(args, **kwargs):
    t0 = time.perf_counter()
    r = run(args, **kwargs)
    return r, time.perf_counter() - t0


def one_line(r) -> str:
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, lines
    return lines[0]


def refused(r, field=None) -> str:
    """Exit 2, one line on stderr naming ``field``, no traceback; returns the line."""
    assert r.exit_code == 2, (r.exit_code, r.output, r.stderr)
    assert r.exception is None or isinstance(r.exception, SystemExit), r.exception
    line = one_line(r)
    if field is not None:
        assert line.startswith(f"mst: invalid input: {field}"), line
    return line


def staging_left(folder: Path) -> list[Path]:
    return [p for p in Path(folder).rglob(f"{STAGING_PREFIX}*")]


def no_constant(name):
    raise AssertionError(f"{name} in JSON output")


def load_json_strict(path: Path):
    return json.loads(Path(path).read_text(), parse_constant=no_constant)


def write(tmp_path, text, name="in.yaml") -> Path:
    f = tmp_path / name
    f.write_text(text)
    return f


def doc_text(**sections) -> str:
    d = {"name": "x", "layers": [dict(LAYER)]}
    d.update(sections)
    return yaml.safe_dump(d)


@pytest.fixture(scope="module", autouse=True)
def warm_imports():
    """Import the schema's dependencies once, so the timings below measure the refusal only."""
    load_document(FORWARD)


# =========================================================================== 1. unbounded work
def alias_bomb() -> str:
    lines = ['a0: &a0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    for i in range(1, 10):
        lines.append(f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]")
    return "\n".join(lines) + "\nname: bomb\nlayers: [*a9]\n"


def test_alias_bomb_is_refused_in_well_under_a_second(tmp_path):
    r, dt = timed(["simulate", write(tmp_path, alias_bomb()), "--out", tmp_path / "o"])
    line = refused(r, "(file)")
    assert "aliases expanded" in line and dt < 1.0, (line, dt)
    assert not (tmp_path / "o").exists()


def test_recursive_alias_and_merge_keys_are_refused(tmp_path):
    r = run(["simulate", write(tmp_path, "name: x\nx: &a [1, *a]\nlayers: []\n"), "--out", tmp_path / "o"])
    assert "recursive" in refused(r, "(file)")
    r = run(
        [
            "simulate",
            write(
                tmp_path, "name: x\nmagnet:\n  <<: {diameter_mm: 6}\nlayers: [{theta_deg: 25, t_mm: 0.6, h_mm: 2}]\n"
            ),
            "--out",
            tmp_path / "o",
        ]
    )
    assert "merge keys" in refused(r, "magnet.<<")


def test_aliases_within_the_cap_still_load(tmp_path):
    # yaml.safe_dump writes anchors for a repeated Python object: such files keep working
    text = yaml.safe_dump({"name": "al", "layers": [LAYER] * 2})
    assert "&id001" in text
    assert run(["simulate", write(tmp_path, text), "--out", tmp_path / "o"]).exit_code == 0


def test_a_50_MB_list_is_refused_before_parsing(tmp_path):
    big = tmp_path / "big.yaml"
    big.write_text("name: big\nlayers:\n" + "  - 1\n" * (50_000_000 // 6))
    r, dt = timed(["simulate", big, "--out", tmp_path / "o"])
    assert "larger than 1000000 bytes" in refused(r, "(file)") and dt < 1.0, dt


def test_a_list_just_under_the_size_cap_stops_at_the_node_cap(tmp_path):
    text = "name: x\nx: [" + ",".join(["0"] * 480_000) + "]\nlayers: []\n"
    assert len(text) < 1_000_000
    r, dt = timed(["simulate", write(tmp_path, text), "--out", tmp_path / "o"])
    assert "more than 5000 values" in refused(r, "(file)") and dt < 1.0, dt


def test_deep_nesting_is_refused(tmp_path):
    text = "name: x\nx: " + "[" * 50_000 + "]" * 50_000 + "\nlayers: []\n"
    r, dt = timed(["simulate", write(tmp_path, text), "--out", tmp_path / "o"])
    assert "nested too deeply" in refused(r, "(file)") and dt < 1.0, dt


def test_absurd_chip_offset_is_refused_by_its_bounds(tmp_path):
    f = write(
        tmp_path,
        "name: x\nmagnetometer: {chip_offset_mm: [1.0e+300, 0]}\nlayers: [{theta_deg: 25, t_mm: 0.6, h_mm: 2}]\n",
    )
    r, dt = timed(["simulate", f, "--out", tmp_path / "o"])
    line = refused(r, "magnetometer.chip_offset_mm[0]")
    assert "<= 100 mm" in line and dt < 1.0, (line, dt)


@pytest.mark.parametrize("digits", [50, 1000, 5000])
def test_integers_with_thousands_of_digits_are_refused_with_a_short_line(tmp_path, digits):
    f = write(
        tmp_path,
        "name: x\nmagnetometer: {noise_uT_rms: " + "7" * digits + "}\nlayers: [{theta_deg: 25, t_mm: 0.6, h_mm: 2}]\n",
    )
    r, dt = timed(["simulate", f, "--out", tmp_path / "o"])
    line = refused(r, "magnetometer.noise_uT_rms")
    assert len(line) < 300 and dt < 1.0, (line, dt)


def numeric_rules():
    """(path, rule) of every numeric key outside the design section (another owner's)."""
    for section, rules in SECTIONS.items():
        if section == "design":
            continue
        for key, rule in rules.items():
            if rule.kind in ("float", "int", "pair"):
                yield f"{section}.{key}", rule
    for key, rule in LAYER_RULES.items():
        yield f"layers[].{key}", rule


@pytest.mark.parametrize("path,rule", list(numeric_rules()), ids=lambda v: v if isinstance(v, str) else "")
def test_every_numeric_key_has_a_lower_and_an_upper_bound(path, rule):
    assert rule.lo is not None and rule.hi is not None, path
    assert math.isfinite(rule.lo) and math.isfinite(rule.hi) and rule.lo < rule.hi
    assert abs(rule.lo) < 1e6 and abs(rule.hi) <= 1e6


def test_the_documented_ranges_match_the_schema():
    text = (ROOT / "docs" / "file-format.md").read_text()
    for path, rule in numeric_rules():
        key = path.replace("layers[].", "layers[i].")
        row = re.search(rf"^\| `{re.escape(key)}` \| ([^|]+) \|", text, re.M)
        assert row, f"docs/file-format.md has no range row for {key}"
        cell = row.group(1)
        assert f"{rule.lo:g}" in cell and f"{rule.hi:g}" in cell, (key, cell, rule)


# =========================================================================== 2. silent acceptance
@pytest.mark.parametrize(
    "text,field,line",
    [
        ("name: a\nname: b\nlayers: [{theta_deg: 25, t_mm: 0.6, h_mm: 2}]\n", "name", 2),
        (
            "name: a\nmagnet:\n  diameter_mm: 6\n  diameter_mm: 8\nlayers: [{theta_deg: 25, t_mm: 0.6, h_mm: 2}]\n",
            "magnet.diameter_mm",
            4,
        ),
        ("name: a\nlayers:\n  - theta_deg: 25\n    t_mm: 0.6\n    h_mm: 2\n    t_mm: 0.8\n", "layers[0].t_mm", 6),
        (
            "name: a\nlayers: [{theta_deg: 25, t_mm: 0.6, h_mm: 2}]\nlayers: [{theta_deg: 25, t_mm: 1, h_mm: 3}]\n",
            "layers",
            3,
        ),
    ],
    ids=["top", "section", "layer", "layers"],
)
def test_duplicate_keys_are_refused_naming_the_key_path_and_line(tmp_path, text, field, line):
    r = run(["simulate", write(tmp_path, text), "--out", tmp_path / "o"])
    msg = refused(r, field)
    assert f"line {line}: duplicate key" in msg, msg
    assert not (tmp_path / "o").exists()


SATURATED_ONE_LAYER = """\
name: sat
family: {width_mm: 40, depth_mm: 34}
magnet: {diameter_mm: 20, thickness_mm: 10, grade: N52}
layers:
  - {theta_deg: 25, t_mm: 0.6, h_mm: 2.0}
"""


def test_one_layer_saturated_design_writes_null_with_a_reason_not_nan(tmp_path):
    out = tmp_path / "o"
    r = run(["simulate", write(tmp_path, SATURATED_ONE_LAYER), "--out", out, "--json"])
    assert r.exit_code == 0, r.output + r.stderr
    rep = load_json_strict(out / "report.json")
    assert json.loads(r.stdout, parse_constant=no_constant) == rep
    reg = rep["regimes"][0]
    assert reg["force_resolution_N"] is None and "saturates" in reg["force_resolution_N_reason"]
    assert rep["magnetometer"]["field_resolution_uT"] is None
    assert "nan" not in r.stdout.lower()


def test_one_layer_design_and_spec_reports_are_finite(tmp_path):
    r = run(["simulate", write(tmp_path, doc_text(name="one")), "--out", tmp_path / "s"])
    assert r.exit_code == 0, r.stderr
    load_json_strict(tmp_path / "s" / "report.json")
    spec = doc_text(name="onespec", layers=[{"target_sensitivity_per_N": 0.03, "target_range_N": 10}])
    r = run(["design", write(tmp_path, spec, "spec.yaml"), "--out", tmp_path / "d", "-q"])
    assert r.exit_code in (0, 1), r.stderr
    load_json_strict(tmp_path / "d" / "report.json")


def test_json_writer_refuses_nan_instead_of_writing_it(tmp_path):
    with pytest.raises(ValueError), staged(tmp_path / "o") as st:
        st.write_json("x.json", {"a": float("nan")})
    assert not (tmp_path / "o").exists()


# =========================================================================== 3. float edges
@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize(
    "section,key",
    [
        ("magnet", "diameter_mm"),
        ("magnet", "thickness_mm"),
        ("magnet", "remanence_T"),
        ("family", "width_mm"),
        ("family", "depth_mm"),
        ("material", "youngs_modulus_MPa"),
        ("housing", "cover_mm"),
        ("printer", "layer_height_mm"),
        ("printer", "nozzle_mm"),
    ],
)
@pytest.mark.parametrize("value", [1e-308, 5e-324, 1e308])
def test_float_edges_in_sections_are_refused(tmp_path, section, key, value):
    r = run(["simulate", write(tmp_path, doc_text(**{section: {key: value}})), "--out", tmp_path / "o"])
    refused(r, f"{section}.{key}")
    assert not (tmp_path / "o").exists()


@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize(
    "key,value", [("theta_deg", 1e-308), ("t_mm", 1e-308), ("h_mm", 1e-308), ("h_mm", 1e308), ("weight", 1e-308)]
)
def test_float_edges_in_layers_are_refused(tmp_path, key, value):
    layer = dict(LAYER, **{key: value})
    r = run(["simulate", write(tmp_path, doc_text(layers=[layer])), "--out", tmp_path / "o"])
    refused(r, f"layers[0].{key}")


@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize("key", ["target_sensitivity_per_N", "target_range_N"])
def test_tiny_targets_are_refused_before_design(tmp_path, key):
    layer = {"target_sensitivity_per_N": 0.03, "target_range_N": 10.0, key: 1e-308}
    r = run(["design", write(tmp_path, doc_text(layers=[layer])), "--out", tmp_path / "o"])
    refused(r, f"layers[0].{key}")


@pytest.mark.filterwarnings("error")
def test_extreme_accuracy_request_is_refused(tmp_path):
    r = run(["simulate", write(tmp_path, doc_text(model={"accuracy_rel": 1e-308})), "--out", tmp_path / "o"])
    refused(r, "model.accuracy_rel")


# =========================================================================== 4. file-system faults
def test_out_below_a_regular_file(tmp_path):
    blocker = tmp_path / "afile"
    blocker.write_text("keep")
    r = run(["simulate", FORWARD, "--out", blocker / "sub"])
    assert r.exit_code == 2 and (r.exception is None or isinstance(r.exception, SystemExit))
    line = one_line(r)
    assert line == f"mst: invalid path: {blocker}: Not a directory (ENOTDIR)", line
    assert blocker.read_text() == "keep"


@pytest.mark.parametrize("cmd", [["export", FORWARD, "--stl"], ["design", SPEC]], ids=["export", "design"])
def test_a_bad_output_path_is_refused_before_the_work(tmp_path, cmd):
    blocker = tmp_path / "afile"
    blocker.write_text("keep")
    r, dt = timed(cmd + ["--out", blocker / "sub"])
    assert r.exit_code == 2 and dt < 1.5, (r.stderr, dt)
    assert one_line(r) == f"mst: invalid path: {blocker}: Not a directory (ENOTDIR)"


def test_read_only_output_folder_names_the_path_and_reason(tmp_path, monkeypatch):
    # root ignores permission bits: simulate the read-only file system where the folder is made
    import mst_cli.io.outputs as outputs

    def read_only(*a, **k):
        raise OSError(errno.EROFS, os.strerror(errno.EROFS), str(k.get("dir", a[-1] if a else "")))

    monkeypatch.setattr(outputs.tempfile, "mkdtemp", read_only)
    out = tmp_path / "ro" / "x"
    r = run(["simulate", FORWARD, "--out", out])
    assert r.exit_code == 2
    assert one_line(r) == f"mst: invalid path: {out}: Read-only file system (EROFS)"
    assert not (tmp_path / "ro").exists()


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_read_only_folder_for_real(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        r = run(["simulate", FORWARD, "--out", ro / "x"])
        assert r.exit_code == 2 and "Permission denied (EACCES)" in one_line(r)
    finally:
        ro.chmod(0o755)


def test_name_too_long_for_the_default_output_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    f = write(tmp_path, doc_text(name="n" * 300))
    r = run(["simulate", f])
    assert r.exit_code == 2
    line = one_line(r)
    assert line.startswith("mst: invalid path: mst-out/nnnn") and line.endswith("File name too long (ENAMETOOLONG)"), (
        line
    )
    assert not (tmp_path / "mst-out").exists()


def test_nul_in_the_name_and_in_out(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    f = write(tmp_path, 'name: "a\\0b"\nlayers: [{theta_deg: 25, t_mm: 0.6, h_mm: 2}]\n')
    assert "NUL" in refused(run(["simulate", f]), "name")
    r = run(["simulate", FORWARD, "--out", "o\0x"])
    assert r.exit_code == 2 and "holds a NUL byte (EINVAL)" in one_line(r)
    assert list(tmp_path.iterdir()) == [f]


def test_full_disk_exits_1_and_keeps_the_earlier_complete_output(tmp_path, monkeypatch):
    out = tmp_path / "o"
    assert run(["simulate", FORWARD, "--out", out]).exit_code == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    real_write_text = Path.write_text

    def full_disk(self, *a, **k):
        if STAGING_PREFIX in str(self):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))  # a write(): no file name
        return real_write_text(self, *a, **k)

    monkeypatch.setattr(Path, "write_text", full_disk)
    r = run(["simulate", FORWARD, "--out", out])
    assert r.exit_code == 1
    assert one_line(r) == f"mst: system error: {out / 'report.json'}: No space left on device (ENOSPC)"
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert not staging_left(tmp_path)


# =========================================================================== 5. interrupted runs
STAGE_AND_SLEEP = textwrap.dedent("""
    import sys, time
    from pathlib import Path
    from mst_cli.io.outputs import staged
    with staged(Path(sys.argv[1])) as st:
        st.write_text("report.json", "{}")
        print("staged", flush=True)
        time.sleep(60)
""")

SIMULATE_SLOW_PLOT = textwrap.dedent("""
    import sys, time
    import mst_cli.simulation.report as report
    plot = report.plot_response
    def slow(*a, **k):
        plot(*a, **k)
        print("staged", flush=True)
        time.sleep(60)
    report.plot_response = slow
    from mst_cli.cli.app import main
    main(["simulate", sys.argv[2], "--out", sys.argv[1]], prog_name="mst")
""")


HANDLED = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


def default_dispositions():
    """In the child before exec: SIGINT/SIGTERM/SIGHUP at their defaults. A background or nohup
    shell starts its children with SIGINT/SIGHUP ignored (issue 22), and an ignored disposition
    survives exec; the tests below are about the default ones, so they set them."""
    for sig in HANDLED:
        signal.signal(sig, signal.SIG_DFL)


def ignoring(*sigs):
    """A preexec_fn: the defaults, then ``sigs`` ignored (as nohup or 'cmd &' start a child)."""

    def setup():
        default_dispositions()
        for sig in sigs:
            signal.signal(sig, signal.SIG_IGN)

    return setup


def interrupt(script, out: Path, sig, *extra):
    p = subprocess.Popen(
        [PYTHON, "-c", script, str(out), *map(str, extra)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=out.parent,
        preexec_fn=default_dispositions,
    )
    try:
        assert p.stdout.readline().strip().endswith("staged")
        assert staging_left(out)  # the staging folder exists now
        p.send_signal(sig)
        _, err = p.communicate(timeout=30)
    finally:
        if p.poll() is None:
            p.kill()
    return p.returncode, err


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT, signal.SIGHUP], ids=lambda s: s.name)
def test_signals_remove_the_staging_folder(tmp_path, sig):
    out = tmp_path / "new"
    code, err = interrupt(STAGE_AND_SLEEP, out, sig)
    assert code in (128 + sig, -sig, 1), (code, err)
    assert not out.exists(), list(out.iterdir())  # nothing at all: the folder was new


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=lambda s: s.name)
def test_interrupted_simulate_keeps_the_earlier_complete_output(tmp_path, sig):
    out = tmp_path / "o"
    assert run(["simulate", FORWARD, "--out", out]).exit_code == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    code, err = interrupt(SIMULATE_SLOW_PLOT, out, sig, FORWARD)
    assert code == 128 + sig, (code, err)
    assert err.strip().splitlines()[-1] == f"mst: interrupted ({sig.name}): nothing half-written was left"
    assert len(err.strip().splitlines()) == 1, err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def _sigint_once_mapped(p: subprocess.Popen, library: str, delay_s: float) -> bool:
    """SIGINT to ``p`` ``delay_s`` after its process maps ``library`` (an extension module being
    imported); False when it ended or 60 s passed first."""
    start = time.monotonic()
    while time.monotonic() - start < 60 and p.poll() is None:
        try:
            mapped = library in Path(f"/proc/{p.pid}/maps").read_text()
        except OSError:
            return False
        if mapped:
            time.sleep(delay_s)
            p.send_signal(signal.SIGINT)
            return True
        time.sleep(0.002)
    return False


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc/self/maps").exists(), reason="watches /proc/PID/maps (Linux)")
@pytest.mark.parametrize("delay_s", [0.0, 0.3])
def test_ctrl_c_during_the_cad_kernels_import_is_the_one_interrupt_line(tmp_path, delay_s):
    # OCP (build123d's kernel) turns a KeyboardInterrupt inside its initialisation into
    # "ImportError: initialization failed": the signal lands while its library is being loaded
    out = tmp_path / "print"
    p = subprocess.Popen(
        [
            PYTHON,
            "-c",
            "import sys; from mst_cli.cli.app import main; main(sys.argv[1:], prog_name='mst')",
            "export",
            str(FORWARD),
            "--step",
            "--out",
            str(out),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=default_dispositions,
    )
    try:
        sent = _sigint_once_mapped(p, "OCP", delay_s)
        _, err = p.communicate(timeout=120)
    finally:
        if p.poll() is None:
            p.kill()
    assert sent, "the export ended before it loaded OCP"
    assert p.returncode == 130, err
    # progress lines may come first (stderr); then the one line, and no traceback
    assert err.strip().splitlines()[-1] == "mst: interrupted (SIGINT): nothing half-written was left", err
    assert "Traceback" not in err and "ImportError" not in err, err
    assert not out.exists()


STAGE_AND_WAIT = textwrap.dedent("""
    import sys
    from pathlib import Path
    from mst_cli.io.outputs import staged
    with staged(Path(sys.argv[1])) as st:
        st.write_text("report.json", "{}")
        print("staged", flush=True)
        sys.stdin.readline()                     # the test's go-ahead, after its signals
        st.write_text("response.csv", "F\\n")
    print("committed", flush=True)
""")


@pytest.mark.parametrize(
    "sigs",
    [(signal.SIGHUP,), (signal.SIGINT, signal.SIGHUP), (signal.SIGTERM,)],
    ids=lambda s: "+".join(x.name for x in s),
)
def test_a_signal_ignored_at_start_stays_ignored_and_the_run_completes(tmp_path, sigs):
    # the decision of issue 22: mst keeps a disposition it inherits as ignored (nohup, 'cmd &'
    # in a script): such a run is not stopped by that signal and writes its whole output
    out = tmp_path / "o"
    p = subprocess.Popen(
        [PYTHON, "-c", STAGE_AND_WAIT, str(out)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=ignoring(*sigs),
    )
    try:
        assert p.stdout.readline().strip() == "staged"
        for sig in sigs:
            p.send_signal(sig)
        stdout, err = p.communicate("go\n", timeout=30)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 0 and stdout.strip() == "committed", (p.returncode, err)
    assert {q.name for q in out.iterdir()} == {"report.json", "response.csv"}


def dead_pid() -> int:
    p = subprocess.Popen([PYTHON, "-c", "pass"])
    p.wait()
    return p.pid


def test_stale_staging_of_a_killed_run_is_removed_by_the_next_run(tmp_path):
    out = tmp_path / "o"
    out.mkdir()
    killed = out / f"{STAGING_PREFIX}{dead_pid()}-abc"  # the pid is gone: stale
    killed.mkdir()
    (killed / "report.json").write_text("{half")
    old = out / f"{STAGING_PREFIX}oldstyle"  # no pid, an hour old: stale
    old.mkdir()
    os.utime(old, (time.time() - 3600, time.time() - 3600))
    sleeper = subprocess.Popen([PYTHON, "-c", "import time; time.sleep(60)"])
    try:
        live = out / f"{STAGING_PREFIX}{sleeper.pid}-xyz"  # a live run's: left alone
        live.mkdir()
        fresh = out / f"{STAGING_PREFIX}fresh"  # no pid, new: ignored
        fresh.mkdir()
        r = run(["simulate", FORWARD, "--out", out])
        assert r.exit_code == 0, r.stderr
        assert not killed.exists() and not old.exists()
        assert live.exists() and fresh.exists()
        assert OUTPUTS <= {p.name for p in out.iterdir()}
    finally:
        sleeper.kill()
        sleeper.wait()


def test_sigkilled_run_leaves_staging_that_the_next_run_removes(tmp_path):
    out = tmp_path / "o"
    p = subprocess.Popen([PYTHON, "-c", STAGE_AND_SLEEP, str(out)], stdout=subprocess.PIPE, text=True)
    try:
        assert p.stdout.readline().strip() == "staged"
        p.kill()
        p.wait()
    finally:
        if p.poll() is None:
            p.kill()
    assert staging_left(out)
    assert run(["simulate", FORWARD, "--out", out]).exit_code == 0
    assert not staging_left(out) and {p.name for p in out.iterdir()} == OUTPUTS


def test_staging_folder_records_the_pid():
    with tempfile.TemporaryDirectory() as d:
        st = Staging(Path(d))
        try:
            assert st.tmp.name.startswith(f"{STAGING_PREFIX}{os.getpid()}-")
        finally:
            st.abort()


# =========================================================================== 6. mst check
@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    out = tmp_path_factory.mktemp("export") / "out"
    r = run(["export", FORWARD, "--stl", "--out", out])
    assert r.exit_code == 0, r.output + r.stderr
    return out


def copy_export(exported: Path, dest: Path) -> Path:
    dest.mkdir()
    for p in exported.iterdir():
        (dest / p.name).write_bytes(p.read_bytes())
    return dest


STL_DTYPE = np.dtype([("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])


def poison_stl(folder: Path, value: float) -> None:
    data = (folder / "sensor.stl").read_bytes()
    tris = np.frombuffer(data[84:], dtype=STL_DTYPE).copy()
    tris["v"][5, 1, 2] = value
    (folder / "sensor.stl").write_bytes(data[:84] + tris.tobytes())


@pytest.mark.parametrize("value", [float("nan"), float("inf"), 1e37], ids=["nan", "inf", "1e37"])
def test_check_refuses_an_stl_with_non_finite_or_huge_coordinates(exported, tmp_path, value):
    folder = copy_export(exported, tmp_path / "c")
    poison_stl(folder, value)
    r, dt = timed(["check", folder])
    line = refused(r, "PATH")
    assert "must be finite and within +-1000 mm" in line and dt < 5.0, (line, dt)


def mutate(manifest: dict, path: str, value):
    node = manifest
    keys = re.findall(r"[^.\[\]]+", path)
    for k in keys[:-1]:
        node = node[int(k)] if k.isdigit() else node[k]
    last = keys[-1]
    if value is KeyError:
        del node[last]
    elif last.isdigit():
        node[int(last)] = value
    else:
        node[last] = value


@pytest.mark.parametrize(
    "path,value",
    [
        ("layers", "three"),
        ("layers", []),
        ("layers.0.t_mm", "0.6"),
        ("layers.0", [1, 2]),
        ("print.rotation", [[1, 0], [0, 1]]),
        ("print.rotation.1.2", None),
        ("print.pause.after_layer", 66.5),
        ("body", []),
        ("body.bbox_max_mm", [1e37, 0, 0]),
        ("body.volume_mm3", True),
        ("board_slot.cable_windows", {}),
        ("board_slot.cable_windows.0.floor_y_mm", {"a": 1}),
        ("magnet_pocket.radius_mm", KeyError),
        ("printer.nozzle_mm", 0),
        ("gap0_mm", 10**400),
        ("stl_tolerance_mm", [0.01]),
    ],
)
def test_check_refuses_a_manifest_of_wrong_type_or_nesting_before_measuring(
    exported, tmp_path, monkeypatch, path, value
):
    import mst_cli.cad.checks as checks

    folder = copy_export(exported, tmp_path / "c")
    manifest = json.loads((folder / "export.json").read_text())
    mutate(manifest, path, value)
    (folder / "export.json").write_text(json.dumps(manifest))
    measured = []
    monkeypatch.setattr(checks, "run_checks", lambda *a, **k: measured.append(1) or [])
    r = run(["check", folder])
    first = re.findall(r"[^.\[\]]+", path)[0]
    line = refused(r, f"export.json.{first}")
    assert len(line) < 400 and not measured, line


def test_check_refuses_nan_in_the_manifest(exported, tmp_path):
    folder = copy_export(exported, tmp_path / "c")
    text = (folder / "export.json").read_text()
    (folder / "export.json").write_text(re.sub(r'"gap0_mm": [^,]+,', '"gap0_mm": NaN,', text))
    assert "NaN is not a JSON number" in refused(run(["check", folder]), "export.json")


def test_a_bug_inside_a_check_is_not_reported_as_a_malformed_manifest(exported, monkeypatch):
    import mst_cli.cad.checks as checks

    def broken(*a, **k):
        raise KeyError("a bug")

    monkeypatch.setattr(checks, "CHECKS", tuple(broken if c is checks.check_board_slot else c for c in checks.CHECKS))
    r = run(["check", exported])
    assert isinstance(r.exception, KeyError), (r.exit_code, r.stderr)


def test_check_json_holds_no_nan(exported):
    r = run(["check", exported, "--json"])
    assert r.exit_code == 0, r.stderr
    json.loads(r.stdout, parse_constant=no_constant)


# =========================================================================== 7. usage errors
@pytest.mark.parametrize(
    "args",
    [
        ["simulate", "--bogus"],
        ["simulate", FORWARD, "--field-model", "xx"],
        ["simulate", ROOT / "configs"],
        ["simulate"],
        ["nope"],
        ["design", SPEC, "--seed", "-1"],
        ["bench", "--seed", "-5"],
        ["export", FORWARD, "--stl-tolerance", "abc"],
        ["check"],
        ["bench", "--samples", "0"],
        ["--bogus"],
    ],
    ids=lambda a: " ".join(map(str, a)),
)
def test_usage_errors_are_one_line_and_exit_2(args):
    r = run(args)
    assert r.exit_code == 2 and (r.exception is None or isinstance(r.exception, SystemExit))
    line = one_line(r)
    assert line.startswith("mst: usage error: ") and "--help" in line, line
    assert r.stdout == ""


def test_help_and_version_still_work():
    r = run(["--help"])
    assert r.exit_code == 0 and r.stdout.startswith("Usage: ") and "simulate" in r.stdout
    r = run(["simulate", "--help"])
    assert r.exit_code == 0 and "DESIGN_FILE" in r.stdout
    r = run(["--version"])
    assert r.exit_code == 0 and package_version() in r.stdout


def test_usage_error_from_the_installed_command():
    mst = Path(PYTHON).parent / "mst"
    if not mst.exists():
        pytest.skip("console script not installed")
    p = subprocess.run([str(mst), "simulate", "--bogus"], capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and p.stdout == ""
    assert p.stderr.count("\n") == 1 and p.stderr.startswith("mst: usage error: No such option")


# =========================================================================== 8. property suite
class Raw(str):
    """A YAML literal written as is (unquoted): .nan, 1.0e+400, a 3000-digit integer."""


RAW_LITERALS = [
    ".nan",
    ".NaN",
    ".inf",
    "-.inf",
    "1.0e+400",
    "-1.0e+400",
    "1.0e-400",
    "0x7fffffffffffffffffffffff",
    "1" * 5000,
    "-" + "9" * 3000,
    "1_000_000_000_000_000",
    "190:20:30",
    "0o777777777777777777777777",
]
EXTREME_FLOATS = [1e-308, -1e-308, 5e-324, 1e308, -1e308, 1e300, -1e300, 0.0, -0.0, 1e-30, 1e30, 1e15]


def rule_values(rule):
    """Values on and just past the rule's own bounds and choices."""
    vals = []
    for b in (rule.lo, rule.hi):
        if b is not None:
            vals += [b, math.nextafter(b, -math.inf), math.nextafter(b, math.inf), -b, 10 * b + 1]
    vals += list(rule.choices) + (["not-a-choice"] if rule.choices else [])
    if rule.kind == "pair" and rule.lo is not None:
        vals += [[rule.lo, rule.hi], [rule.hi, rule.lo], [rule.lo], [rule.hi, rule.hi, 0]]
    return vals


scalars = st.one_of(
    st.sampled_from(EXTREME_FLOATS),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(10**40), max_value=10**40),
    st.sampled_from(["nan", "NaN", "inf", "-inf", "1e400", "", "0x10", "six"]),
    st.sampled_from(RAW_LITERALS).map(Raw),
    st.none(),
    st.booleans(),
    st.text(max_size=8),
)
values = st.one_of(scalars, st.lists(scalars, max_size=3), st.dictionaries(st.text(max_size=4), scalars, max_size=2))
junk_keys = st.text(alphabet="abcxyz_<&*!\n\0. ", min_size=1, max_size=6)


def in_bounds(rule):
    """Valid but extreme values of the rule: its closed ends, just inside them, the middle."""
    if rule.choices:
        return list(rule.choices)
    if rule.lo is None or rule.hi is None:
        return []
    lo, hi = rule.lo, rule.hi
    vals = [math.nextafter(lo, math.inf), math.nextafter(hi, -math.inf), 0.5 * (lo + hi)]
    vals += [lo] if not rule.lo_open else []
    vals += [hi] if not rule.hi_open else []
    vals += [math.sqrt(lo * hi)] if lo > 0 else []
    if rule.kind == "pair":
        return [[a, b] for a in vals for b in vals[:2]]
    if rule.kind == "int":
        return sorted({int(math.ceil(v)) for v in vals if lo <= math.ceil(v) <= hi})
    return vals


def value_for(rule):
    """Half the time a valid extreme (so the run goes on to the arithmetic), else hostile."""
    valid, own = in_bounds(rule), rule_values(rule)
    hostile = st.one_of(st.sampled_from(own), values) if own else values
    return st.one_of(st.sampled_from(valid), hostile) if valid else hostile


@st.composite
def hostile_documents(draw):
    doc = {
        "name": "h",
        "model": {"mechanics": "spring"},
        "layers": [dict(LAYER), {"theta_deg": 33, "t_mm": 1.0, "h_mm": 2.8}],
    }
    for _ in range(draw(st.integers(1, 4))):
        op = draw(st.sampled_from(["section"] * 3 + ["layer"] * 2 + ["top", "drop", "resize", "name"]))
        if op == "section":
            section = draw(st.sampled_from(sorted(SECTIONS)))
            rules = SECTIONS[section]
            key = draw(st.one_of(st.sampled_from(sorted(rules)), junk_keys))
            body = doc.setdefault(section, {})
            if not isinstance(body, dict):
                body = doc[section] = {}
            body[key] = draw(value_for(rules[key]) if key in rules else values)
        elif op == "layer" and isinstance(doc.get("layers"), list) and doc["layers"]:
            i = draw(st.integers(0, len(doc["layers"]) - 1))
            key = draw(st.one_of(st.sampled_from(sorted(LAYER_RULES)), junk_keys))
            if isinstance(doc["layers"][i], dict):
                doc["layers"][i][key] = draw(value_for(LAYER_RULES[key]) if key in LAYER_RULES else values)
        elif op == "top":
            doc[draw(st.one_of(st.sampled_from(TOP_KEYS), junk_keys))] = draw(values)
        elif op == "drop":
            doc.pop(draw(st.sampled_from(TOP_KEYS)), None)
        elif op == "resize" and isinstance(doc.get("layers"), list):
            n = draw(st.integers(0, 8))
            doc["layers"] = [
                dict(doc["layers"][i % len(doc["layers"])]) if doc["layers"] else dict(LAYER) for i in range(n)
            ]
        elif op == "name":
            doc["name"] = draw(
                st.sampled_from(
                    ["n" * 300, "a\0b", "../up", ".hidden", "", "a/b", "ok\nnext", "x" * 100, "µ-sensor", "tab\there"]
                )
            )
    raws = {}

    def placeholder(v):
        if isinstance(v, Raw):
            token = f"RAW{len(raws)}TOKEN"
            raws[token] = str(v)
            return token
        if isinstance(v, dict):
            return {k: placeholder(x) for k, x in v.items()}
        if isinstance(v, list):
            return [placeholder(x) for x in v]
        return v

    text = yaml.safe_dump(placeholder(doc), sort_keys=False, allow_unicode=True)
    for token, literal in raws.items():
        text = text.replace(token, literal)
    if draw(st.booleans()) and draw(st.booleans()):
        text += draw(st.sampled_from(["name: again\n", "layers: []\n", "model: {}\n"]))  # duplicate key
    return text


def check_invariants(folder: Path, r, dt: float, caught) -> None:
    assert r.exit_code in (0, 1, 2), (r.exit_code, r.stderr, r.exception)
    assert r.exception is None or isinstance(r.exception, SystemExit), repr(r.exception)
    if r.exit_code == 2:
        assert len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)], [str(w.message) for w in caught]
    assert "Traceback" not in r.stderr
    assert not staging_left(folder)
    written = [p for p in folder.rglob("*") if p.is_file() and p.name != "in.yaml"]
    by_folder = {}
    for p in written:
        by_folder.setdefault(p.parent, set()).add(p.name)
    for names in by_folder.values():  # all of a run's files, or none
        assert names == OUTPUTS, names
    if written:
        assert r.exit_code == 0
    for p in written:
        if p.suffix == ".json":
            load_json_strict(p)
    assert dt < 5.0, dt


@settings(
    max_examples=400,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(text=hostile_documents(), default_out=st.booleans())
def test_property_hostile_documents_keep_the_contract(text, default_out):
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        f = folder / "in.yaml"
        f.write_text(text)
        args = ["simulate", f] + ([] if default_out else ["--out", folder / "out"])
        cwd = os.getcwd()
        os.chdir(folder)
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                r, dt = timed(args)
        finally:
            os.chdir(cwd)
        event(f"exit {r.exit_code}")
        check_invariants(folder, r, dt, caught)


MANIFEST_PATHS = [
    "layers",
    "layers.0",
    "layers.0.t_mm",
    "layers.1.z_bottom_mm",
    "print",
    "print.rotation",
    "print.rotation.0",
    "print.rotation.0.0",
    "print.pause",
    "print.pause.after_layer",
    "print.layer_height_mm",
    "body",
    "body.bbox_min_mm",
    "body.bbox_max_mm.2",
    "body.volume_mm3",
    "body.bodies",
    "magnet_pocket",
    "magnet_pocket.section_z_mm",
    "board_slot.cable_windows",
    "board_slot.chip_xy_mm",
    "board_slot.board",
    "printer.nozzle_mm",
    "printer.min_gap_mm",
    "gap0_mm",
    "stl_tolerance_mm",
]


@settings(
    max_examples=150,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(
    path=st.sampled_from(MANIFEST_PATHS),
    value=st.one_of(
        st.floats(-2000, 2000),
        st.integers(-100, 100),
        values,
        st.just(KeyError),
        st.sampled_from([1e37, -1e37, 10**30, 1e-300, 0, -1]),
        st.sampled_from(MANIFEST_PATHS),
    ),
)
def test_property_hostile_manifests_keep_the_contract(exported, path, value):
    with tempfile.TemporaryDirectory() as d:
        folder = copy_export(exported, Path(d) / "c")
        manifest = json.loads((folder / "export.json").read_text())
        mutate(manifest, path, value)
        (folder / "export.json").write_text(json.dumps(manifest))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            r, dt = timed(["check", folder, "--json"])
        event(f"exit {r.exit_code}: {r.stderr.strip()[:60]}")
        assert r.exit_code in (0, 1, 2), (r.exit_code, r.stderr, r.exception)
        assert r.exception is None or isinstance(r.exception, SystemExit), repr(r.exception)
        if r.exit_code == 2:
            assert len(r.stderr.strip().splitlines()) == 1, r.stderr
        else:
            json.loads(r.stdout, parse_constant=no_constant)
        assert not [w for w in caught if issubclass(w.category, RuntimeWarning)], [str(w.message) for w in caught]
        assert dt < 20.0, dt


# =========================================================================== issue 22: round two
# Each section below is one class of issue 22; each test failed (a hang, a traceback, a wrong
# exit code or message) on the tree before its fix.
MST = "import sys; from mst_cli.cli.app import main; main(sys.argv[1:], prog_name='mst')"


def mst_process(args, timeout=120, **kwargs) -> subprocess.CompletedProcess:
    """``mst ARGS`` in its own process, bounded: a command that blocks fails the test."""
    return subprocess.run(
        [PYTHON, "-c", MST, *map(str, args)], capture_output=True, text=True, timeout=timeout, **kwargs
    )


def refused_line(p: subprocess.CompletedProcess, code: int = 2) -> str:
    assert p.returncode == code, (p.returncode, p.stdout, p.stderr)
    assert "Traceback" not in p.stderr, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1, lines
    return lines[0]


# ----------------------------------------------------------------- 9. special files (FIFO, devices)
@pytest.fixture(scope="module")
def loadtest_files(tmp_path_factory):
    """A small valid load test and readings file of the forward design (its own model + noise)."""
    from mst_cli.model.response import simulate
    from mst_cli.sensor.document import load_document

    doc = load_document(FORWARD)
    resp = simulate(doc.geometry(), doc.material, noise_uT_rms=doc.noise_uT_rms)
    rng = np.random.default_rng(5)
    F = np.sort(rng.uniform(0, resp.max_force_N, 40))
    B = np.stack([np.interp(F, resp.force_N, resp.B_T[:, i]) for i in range(3)], -1) * 1e6
    B = B + rng.normal(0, 2.0, B.shape)
    d = tmp_path_factory.mktemp("lt")
    (d / "lt.csv").write_text(
        "force_N,Bx_uT,By_uT,Bz_uT\n" + "".join(f"{f:.4f},{x:.3f},{y:.3f},{z:.3f}\n" for f, (x, y, z) in zip(F, B))
    )
    (d / "readings.csv").write_text("Bx_uT,By_uT,Bz_uT\n" + "".join(f"{x:.3f},{y:.3f},{z:.3f}\n" for x, y, z in B))
    return {"dir": d, "lt": d / "lt.csv", "readings": d / "readings.csv", "resp": resp, "F": F, "B_uT": B}


def fifo(tmp_path, name) -> Path:
    path = tmp_path / name
    os.mkfifo(path)
    return path


@pytest.mark.parametrize(
    "case",
    [
        "calibrate-loadtest",
        "read-readings",
        "calibrate-design",
        "read-model",
        "simulate",
        "check-manifest",
        "slice-profile",
    ],
)
def test_a_fifo_is_refused_naming_the_path_without_blocking(tmp_path, loadtest_files, exported, case):
    out = tmp_path / "o"
    if case == "calibrate-loadtest":
        args, name = ["calibrate", FORWARD, fifo(tmp_path, "lt.csv")], "lt.csv"
    elif case == "read-readings":
        args, name = ["read", FORWARD, fifo(tmp_path, "r.csv")], "r.csv"
    elif case == "calibrate-design":
        args, name = ["calibrate", fifo(tmp_path, "d.yaml"), loadtest_files["lt"]], "d.yaml"
    elif case == "read-model":
        args, name = ["read", fifo(tmp_path, "m.yaml"), loadtest_files["readings"]], "m.yaml"
    elif case == "simulate":
        args, name = ["simulate", fifo(tmp_path, "d.yaml")], "d.yaml"
    elif case == "check-manifest":
        folder = copy_export(exported, tmp_path / "c")
        (folder / "export.json").unlink()
        os.mkfifo(folder / "export.json")
        args, name, out = ["check", folder], "export.json", None
    else:
        need_slicer()  # mst slice looks for PrusaSlicer before it reads the profile
        args, name, out = ["slice", exported, "--profile", fifo(tmp_path, "p.ini")], "p.ini", None
    p = mst_process(args + (["--out", out] if out else []), timeout=60)
    line = refused_line(p)
    assert "a FIFO (named pipe)" in line and name in line, line
    assert out is None or not out.exists()


def test_a_fifo_beside_the_model_in_place_of_calibration_json_does_not_block(tmp_path, loadtest_files):
    model = tmp_path / "model.yaml"
    model.write_text(FORWARD.read_text())
    fifo(tmp_path, "calibration.json")
    p = mst_process(["read", model, loadtest_files["readings"], "--out", tmp_path / "o"], timeout=60)
    assert p.returncode == 0, p.stderr
    assert "has no calibration.json beside it" in p.stderr
    assert (tmp_path / "o" / "forces.csv").is_file()


@pytest.mark.parametrize("cmd", ["calibrate", "read"])
def test_a_device_as_the_csv_is_refused_by_kind(tmp_path, cmd):
    args = [cmd, FORWARD, "/dev/zero", "--out", tmp_path / "o"]
    line = refused(run(args), "(file)")
    assert "a character device" in line and "/dev/zero" in line, line


# ----------------------------------------------------------------- 10. mst slice trusts export.json
BUNDLED_PROFILE = ROOT / "mst_cli" / "cad" / "data" / "tpu85a-0.4mm.ini"
FAKE_EXE = "/fake/prusa-slicer"


def box_gcode(
    layers: int = 25,
    pause_after: int | tuple[int, ...] | None = None,
    layer_h: float = 0.2,
    size: float = 10.0,
    centre=(125.0, 105.0),
    end: bool = True,
    **config,
) -> str:
    """PrusaSlicer-like G-code of a square tube ``size`` wide, ``layers`` high, with the footer and
    the closing config block PrusaSlicer writes (``end=False``: without the last line)."""
    x0, y0 = centre[0] - size / 2, centre[1] - size / 2
    corners = [(x0, y0), (x0 + size, y0), (x0 + size, y0 + size), (x0, y0 + size), (x0, y0)]
    out = ["M83", "G90", "G92 E0"]
    pauses = () if pause_after is None else (pause_after,) if isinstance(pause_after, int) else pause_after
    for k in range(1, layers + 1):
        z = round(k * layer_h, 4)
        out += [";LAYER_CHANGE", f";Z:{z:g}", f";HEIGHT:{layer_h:g}", f"G1 Z{z:g} F600"]
        if k - 1 in pauses:
            out += [";PAUSE_PRINT", "M117 magnet", "M601"]
        out += [";TYPE:External perimeter", ";WIDTH:0.45", f"G1 X{corners[0][0]:.3f} Y{corners[0][1]:.3f}"]
        out += [f"G1 X{x:.3f} Y{y:.3f} E0.40000" for x, y in corners[1:]]
    out += [
        "; filament used [mm] = 100.0",
        "; filament used [cm3] = 0.24",
        "; total filament used [g] = 0.29",
        "; estimated printing time (normal mode) = 10m 5s",
        "; prusaslicer_config = begin",
        "; pause_print_gcode = M601",
        f"; layer_height = {layer_h:g}",
    ]
    out += [f"; {k} = {v}" for k, v in config.items()]
    out += ["; prusaslicer_config = end"] if end else []
    return "\n".join(out) + "\n"


class FakeSlicer:
    """PrusaSlicer's command line as mst drives it, in-process (``cad.slicer._run``): --save
    writes the bundled profile, --help names a version, --export-gcode writes ``gcode`` (bytes,
    or None: nothing) and exits with ``code``. ``calls`` counts the slices."""

    def __init__(self, gcode: bytes | None, code: int = 0):
        self.gcode, self.code, self.calls = gcode, code, 0

    def __call__(self, args, timeout_s):
        if "--save" in args:
            Path(args[args.index("--save") + 1]).write_text(BUNDLED_PROFILE.read_text())
            return subprocess.CompletedProcess(args, 0, "", "")
        if "--help" in args:
            return subprocess.CompletedProcess(args, 0, "PrusaSlicer-2.7.0+fake\n", "")
        self.calls += 1
        if self.gcode is not None:
            Path(args[args.index("--output") + 1]).write_bytes(self.gcode)
        return subprocess.CompletedProcess(args, self.code, "", "Slicing done\n")


@pytest.fixture
def fake_slicer(monkeypatch):
    """Install a FakeSlicer (G-code of the forward design's pause by default); returns it."""
    import mst_cli.cad.slicer as S

    def install(gcode=None, code=0):
        fake = FakeSlicer(gcode, code)
        monkeypatch.setattr(S, "find_prusa_slicer", lambda: FAKE_EXE)
        monkeypatch.setattr(S, "_run", fake)
        S.known_options.cache_clear()
        return fake

    yield install
    S.known_options.cache_clear()


def slice_export(exported: Path, dest: Path, manifest=None) -> Path:
    """A copy of the export (STL + export.json, or ``manifest`` as export.json) to slice."""
    folder = copy_export(exported, dest)
    if manifest is not None:
        (folder / "export.json").write_text(manifest if isinstance(manifest, str) else json.dumps(manifest))
    return folder


def exported_manifest(exported: Path) -> dict:
    return json.loads((exported / "export.json").read_text())


def good_gcode(exported: Path) -> bytes:
    """G-code with every pause export.json asks for (the magnet's, the insert's)."""
    after = tuple(p["after_layer"] for p in exported_manifest(exported)["print"]["pauses"])
    return box_gcode(layers=max(after) + 10, pause_after=after).encode()


def test_fake_slicer_g_code_of_the_reference_export_passes(exported, tmp_path, fake_slicer):
    fake = fake_slicer(good_gcode(exported))
    folder = slice_export(exported, tmp_path / "s")
    r = run(["slice", folder, "--no-plot", "--json"])
    assert r.exit_code == 0, r.stderr
    assert fake.calls == 2 and json.loads(r.stdout)["pause"]["ok"]


@pytest.mark.parametrize(
    "path,value,field",
    [
        (None, [1, 2], "export.json"),
        ("print.pause.z_mm", "1e400", "export.json.print.pause.z_mm"),
        ("print.pause.after_layer", "abc", "export.json.print.pause.after_layer"),
        ("print.pause.after_layer", 1e30, "export.json.print.pause.after_layer"),
        ("print.layer_height_mm", "NaN", "export.json"),
        ("print.cavity_lines.0", {"layer": 1}, "export.json.print.cavity_lines[0].x_mm"),
        ("print", "x", "export.json.print"),
        ("name", 7, "export.json.name"),
    ],
    ids=["list", "pause-1e400", "layer-abc", "layer-1e30", "nan-layer-height", "cavity-line", "print", "name"],
)
def test_slice_validates_export_json_before_slicing(exported, tmp_path, fake_slicer, path, value, field):
    fake = fake_slicer(good_gcode(exported))
    manifest = exported_manifest(exported)
    if path is None:
        text = json.dumps(value)
    else:
        literal = value if value in ("1e400", "NaN") else None
        mutate(manifest, path, "@@" if literal else value)
        text = json.dumps(manifest).replace('"@@"', literal) if literal else json.dumps(manifest)
    folder = slice_export(exported, tmp_path / "s", text)
    r = run(["slice", folder, "--no-plot"])
    line = refused(r, field)
    assert fake.calls == 0, "sliced before the manifest was checked"
    assert not (folder / "sensor.gcode").exists() and not staging_left(folder), line


# ----------------------------------------------------------------- 11. a slicer that lies
FAKE_SLICER_SCRIPT = """#!{python}
import sys
print("Slicing done")          # and exit 0, writing nothing
"""


def test_a_slicer_that_exits_0_and_writes_nothing_is_a_one_line_machine_fault(exported, tmp_path, monkeypatch):
    fake = tmp_path / "prusa-slicer"
    fake.write_text(FAKE_SLICER_SCRIPT.format(python=PYTHON))
    fake.chmod(0o755)
    monkeypatch.setenv("MST_PRUSA_SLICER", str(fake))
    folder = slice_export(exported, tmp_path / "s")
    before = sorted(p.name for p in folder.iterdir())
    r = run(["slice", folder, "--no-plot"])
    assert r.exit_code == 1 and (r.exception is None or isinstance(r.exception, SystemExit)), r.exception
    line = one_line(r)
    assert line.startswith("mst slice: prusa-slicer --save") and "exited 0 but wrote no config" in line, line
    assert sorted(p.name for p in folder.iterdir()) == before


@pytest.mark.parametrize(
    "gcode,reason",
    [
        (None, "exited 0 but wrote no G-code"),
        (b"", "an empty G-code file"),
        (b"\xff\xfe\x00garbage", "not UTF-8"),
        ("truncated", "it is truncated"),
        ("no-end", "it is truncated"),
        (box_gcode(layers=0).encode(), "without one extrusion of the part"),
    ],
    ids=["nothing", "empty", "binary", "truncated", "no-end", "no-part"],
)
def test_slicer_output_that_is_missing_empty_or_truncated_is_exit_1(exported, tmp_path, fake_slicer, gcode, reason):
    good = good_gcode(exported)
    gcode = {"truncated": good[: len(good) // 2], "no-end": box_gcode(end=False).encode()}.get(gcode, gcode)
    fake_slicer(gcode)
    folder = slice_export(exported, tmp_path / "s")
    before = sorted(p.name for p in folder.iterdir())
    r = run(["slice", folder, "--no-plot"])
    assert r.exit_code == 1 and (r.exception is None or isinstance(r.exception, SystemExit)), r.exception
    lines = [s for s in r.stderr.strip().splitlines() if not s.startswith("[")]  # not the progress lines
    assert len(lines) == 1 and reason in lines[0] and lines[0].endswith("nothing was written"), lines
    assert sorted(p.name for p in folder.iterdir()) == before


# ----------------------------------------------------------------- 12. a full disk during export
def file_size_limit(nbytes: int):
    """A preexec_fn: writes past ``nbytes`` fail with EFBIG (Python ignores SIGXFSZ), as a full
    file system would fail them, in every writer of the process, OCCT's included."""
    import resource

    def setup():
        default_dispositions()
        resource.setrlimit(resource.RLIMIT_FSIZE, (nbytes, nbytes))

    return setup


@pytest.mark.slow
@pytest.mark.parametrize("fmt,name", [("--step", "sensor.step"), ("--stl", "sensor.stl"), ("--3mf", "sensor.3mf")])
def test_export_onto_a_full_disk_is_one_line_exit_1_for_every_writer(tmp_path, fmt, name):
    out = tmp_path / "o"
    # 2 kB: below every body file (the manifold3d 3MF of the forward design is 4.6 kB)
    p = mst_process(["export", FORWARD, fmt, "--out", out], timeout=300, preexec_fn=file_size_limit(2_000))
    line = [s for s in p.stderr.strip().splitlines() if not s.startswith("[")]
    assert p.returncode == 1 and "Traceback" not in p.stderr, p.stderr
    assert line == [f"mst: system error: {out / name}: File too large (EFBIG)"], line
    assert not out.exists()


def test_step_writer_failure_on_a_full_disk_names_the_file(tmp_path, monkeypatch):
    import mst_cli.cad.deterministic as det

    real = Path.write_bytes

    def full(self, data):
        if self.suffix == ".step":
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(self, data)

    monkeypatch.setattr(Path, "write_bytes", full)
    monkeypatch.setattr(det, "_renumber_nauo", lambda data: data)
    out = tmp_path / "o"

    class Assembly:
        pass

    monkeypatch.setattr("build123d.export_step", lambda assembly, target, **k: target.write(b"ISO-10303-21;"))
    with pytest.raises(OSError) as exc, staged(out) as st:
        st.write_bytes("sensor.step", det.step_bytes(Assembly()))
    assert exc.value.errno == errno.ENOSPC and exc.value.filename == str(out / "sensor.step")
    assert not out.exists()


# ----------------------------------------------------------------- 13. bounds two commands share
def test_the_finest_stl_tolerance_export_writes_is_one_check_accepts(tmp_path):
    from mst_cli.cad.manifest import STL_TOLERANCE_MM

    lo, hi = STL_TOLERANCE_MM
    out = tmp_path / "fine"
    assert run(["export", FORWARD, "--stl", "--out", out, "--stl-tolerance", lo]).exit_code == 0
    r = run(["check", out, "--json"])
    assert r.exit_code in (0, 1) and "stl_tolerance" not in r.stderr, r.stderr
    assert json.loads(r.stdout)["checks"]
    assert "must be a number from" in refused(run(["export", FORWARD, "--stl-tolerance", lo / 2]), "--stl-tolerance")
    assert "must be a number from" in refused(run(["export", FORWARD, "--stl-tolerance", hi * 2]), "--stl-tolerance")


def test_check_nozzle_has_the_design_files_range(exported):
    from mst_cli.sensor.sections import SECTIONS

    rule = SECTIONS["printer"]["nozzle_mm"]
    for value in (rule.lo, rule.hi):
        assert run(["check", exported, "--nozzle", value]).exit_code in (0, 1)
    for value in (rule.lo / 2, rule.hi * 2):
        assert f"from {rule.lo:g} to {rule.hi:g} mm" in refused(run(["check", exported, "--nozzle", value]), "--nozzle")


def test_every_seed_option_has_the_spec_files_range():
    from mst_cli.cli.app import load_command
    from mst_cli.sensor.sections import SECTIONS

    rule = SECTIONS["design"]["seed"]
    for name in ("design", "bench"):
        (opt,) = [p for p in load_command(name).params if p.name == "seed"]
        assert (opt.type.min, opt.type.max) == (rule.lo, rule.hi), name


# ----------------------------------------------------------------- 14. saturation and noise
def test_read_flags_a_50_mT_reading_saturated(tmp_path):
    f = write(tmp_path, "Bx_uT,By_uT,Bz_uT\n0,0,50000\n0,0,-50000.0\n30000,0,40000\n0,0,49999\n", "r.csv")
    r = run(["read", FORWARD, f, "--out", tmp_path / "o"])
    assert r.exit_code == 0, r.stderr
    rows = (tmp_path / "o" / "forces.csv").read_text().splitlines()[1:]
    flags = [row.split(",")[5] for row in rows]
    assert flags[:2] == ["saturated", "saturated"] and flags[2:] == ["above_range", "above_range"], flags


def test_a_noise_only_load_test_is_named_as_no_relation(tmp_path, loadtest_files):
    rng = np.random.default_rng(1)
    F = loadtest_files["F"]
    B = np.array([0.0, 0.0, -3000.0]) + rng.normal(0, 2.0, (len(F), 3))
    f = write(
        tmp_path,
        "force_N,Bx_uT,By_uT,Bz_uT\n" + "".join(f"{a:.4f},{x:.3f},{y:.3f},{z:.3f}\n" for a, (x, y, z) in zip(F, B)),
        "noise.csv",
    )
    r = run(["calibrate", FORWARD, f, "--out", tmp_path / "o", "--no-plot"])
    assert r.exit_code == 1, r.output
    line = one_line(r)
    assert "does not follow the force at all" in line and "falls" not in line, line
    assert not (tmp_path / "o").exists()


# ----------------------------------------------------------------- 15. a profile's post-processing
def post_process_profile(tmp_path, value: str) -> Path:
    profile = tmp_path / "pp.ini"
    profile.write_text(BUNDLED_PROFILE.read_text().replace("post_process = \n", f"post_process = {value}\n"))
    return profile


def test_a_profiles_post_process_script_runs_only_with_consent_and_is_named_in_one_line(
    exported, tmp_path, fake_slicer
):
    fake = fake_slicer(good_gcode(exported))
    profile = post_process_profile(tmp_path, "/usr/local/bin/strip-moves --fast")
    folder = slice_export(exported, tmp_path / "s")
    before = {p.name for p in folder.iterdir()}
    r = run(["slice", folder, "--no-plot", "--json", "--profile", profile])  # issue 40: no consent, no run
    line = refused(r, "--profile")
    assert "'/usr/local/bin/strip-moves --fast'" in line and "--allow-post-process" in line, line
    assert fake.calls == 0 and {p.name for p in folder.iterdir()} == before
    r = run(["slice", folder, "--no-plot", "--json", "--profile", profile, "--allow-post-process"])
    assert r.exit_code == 0, r.stderr
    notes = [s for s in r.stderr.splitlines() if s.startswith("mst slice: note")]
    assert notes == [
        "mst slice: note: the profile's post_process runs '/usr/local/bin/strip-moves --fast' on "
        "each G-code (your script; what is measured is its output)"
    ], notes
    report = json.loads(r.stdout)
    assert report["post_process"] == report["post_process_run"] == ["/usr/local/bin/strip-moves --fast"]
    r = run(["slice", folder, "--no-plot"])  # the bundled profile runs nothing
    assert r.exit_code == 0 and "mst slice: note" not in r.stderr
    assert json.loads((folder / "slice.json").read_text())["post_process_run"] == []


def test_api_slice_refuses_post_process_scripts_by_default(exported, tmp_path, fake_slicer):
    from mst_cli import api
    from mst_cli.errors import InputError

    fake = fake_slicer(good_gcode(exported))
    profile = post_process_profile(tmp_path, "a.sh\\nb.sh --x")
    folder = slice_export(exported, tmp_path / "s")
    with pytest.raises(InputError, match="'a.sh', 'b.sh --x'"):
        api.slice(folder, profile=profile)
    assert fake.calls == 0 and not (folder / "slice.json").exists()
    result = api.slice(folder, profile=profile, allow_post_process=True)
    assert result.report["post_process_run"] == ["a.sh", "b.sh --x"]


# ----------------------------------------------------------------- 16. a long load test
def test_a_load_tests_field_magnitude_is_computed_once():
    from mst_cli.calibration.loadtest import parse_readings

    rd = parse_readings("Bx_uT,By_uT,Bz_uT\n" + "1,2,3\n" * 5, "r.csv", need_force=False)
    assert rd.B_abs_T is rd.B_abs_T  # a per-row rd.B_abs_T[i] is O(1) now


@pytest.mark.slow
def test_a_40000_sample_load_test_calibrates_with_a_progress_line(tmp_path, loadtest_files):
    resp = loadtest_files["resp"]
    rng = np.random.default_rng(2)
    F = np.sort(rng.uniform(0, resp.max_force_N, 40_000))
    B = np.stack([np.interp(F, resp.force_N, resp.B_T[:, i]) for i in range(3)], -1) * 1e6
    B += rng.normal(0, 2.0, B.shape)
    f = tmp_path / "big.csv"
    f.write_text(
        "force_N,Bx_uT,By_uT,Bz_uT\n" + "".join(f"{a:.4f},{x:.3f},{y:.3f},{z:.3f}\n" for a, (x, y, z) in zip(F, B))
    )
    assert f.stat().st_size > 1_000_000
    r, _ = timed(["calibrate", FORWARD, f, "--out", tmp_path / "o", "--no-plot"])
    assert r.exit_code == 0, r.output
    # its time is a speed goal: benchmarks/bench_calibrate.py (a timed assert failed on a loaded machine)
    assert "fitting 40000 samples" in r.stderr, r.stderr


# =========================================================================== 17. property suite, round two
PROPERTY = dict(
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.function_scoped_fixture],
)


def contract(
    r,
    dt: float,
    caught,
    folder: Path,
    outputs: set[str],
    required: set[str],
    limit_s: float,
    chatter: tuple[str, ...] = (),
    judged: str | None = None,
) -> None:
    """The CLI contract on one run: exit 0/1/2, never an exception; a refusal is one line
    (besides ``chatter``: progress and warnings); no RuntimeWarning; nothing staged left; the
    folder holds all of a run's ``required`` files (exit 0, or exit 1 with the ``judged`` line:
    a result that fails a limit is still written) or none of ``outputs``; JSON strict."""
    assert r.exit_code in (0, 1, 2), (r.exit_code, r.stderr, r.exception)
    assert r.exception is None or isinstance(r.exception, SystemExit), repr(r.exception)
    assert "Traceback" not in r.stderr
    said = [s for s in r.stderr.strip().splitlines() if s and not s.startswith(chatter)]
    if r.exit_code == 2:
        assert len(said) == 1 and said[0].startswith("mst: "), said
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)], [str(w.message) for w in caught]
    assert not staging_left(folder)
    written = {p.name for p in folder.rglob("*") if p.is_file() and p.name in outputs}
    complete = r.exit_code == 0 or (r.exit_code == 1 and judged is not None and judged in r.stderr)
    assert required <= written if complete else written == set(), (r.exit_code, written, r.stderr)
    for p in folder.rglob("*.json"):
        if p.name in outputs:
            load_json_strict(p)
    assert dt < limit_s, dt


def invoke(args):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r, dt = timed(args)
    return r, dt, caught


# ----------------------------------------------------------------- load tests and readings
HOSTILE_CELLS = [
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e400",
    "-1e400",
    "1e-400",
    "",
    " ",
    "abc",
    "0x10",
    "1_0",
    "+5",
    "--1",
    "1,5",
    '"3"',
    "5e",
    "١٢",
    "\0",
    "50000",
    "-50000",
    "32768",
    "-32768",
    "1e15",
    "3.5",
]
WRONG_UNIT_COLUMNS = ["force_kN", "load_g", "Bz_mT", "bx_gauss", "F", "time_s", "note"]


EXTRA_COLUMNS = ["T_C", "cycle", "branch", "time_s", "x_mm", "gain_sel", ""]


def any_cell():
    """A cell of any content (no line break: a line is a row) and any length, up to and past the bound
    on a cell (mst_cli.io.csv_table.MAX_CELL_CHARS) and past the csv module's own field limit."""
    from mst_cli.io.csv_table import MAX_CELL_CHARS

    text = st.text(
        st.characters(blacklist_categories=("Cs",), blacklist_characters="\n\r\x0b\x0c\x1c\x1d\x1e\x85\u2028\u2029"),
        max_size=12,
    )
    long = st.builds(
        lambda ch, n: ch * n,
        st.sampled_from(["x", "9", '"', ",", " "]),
        st.sampled_from([MAX_CELL_CHARS, MAX_CELL_CHARS + 1, 131_073, 200_000]),
    )
    return st.one_of(text, long)


@st.composite
def reading_files(draw, need_force: bool, resp, setting):
    """A load test (``need_force``) or readings CSV drawn from the column rules of
    mst_cli.calibration.loadtest: its column names (uT or raw codes, force, chip setting), the
    chip's ranges for the numbers, then hostile cells, rows, headers and separators."""
    from mst_cli.calibration import loadtest as lt
    from mst_cli.model import chip as mlx

    raw = draw(st.booleans()) and setting is not None
    cols = list(lt.CODE_COLUMNS if raw else lt.UT_COLUMNS)
    if need_force or draw(st.booleans()):
        cols.insert(0, lt.FORCE_COLUMN)
    with_setting = draw(st.booleans())
    if with_setting:
        cols += list(lt.SETTING_COLUMNS)
    cols += draw(st.lists(st.sampled_from(WRONG_UNIT_COLUMNS + EXTRA_COLUMNS), max_size=2, unique=True))
    if draw(st.integers(0, 5)) == 0:
        cols = draw(st.permutations(cols))
    n = draw(st.sampled_from([0, 1, 5, 13, 40]))
    F = np.sort(np.asarray(draw(st.lists(st.floats(0, 1.05 * resp.max_force_N), min_size=n, max_size=n)), float))
    B = np.stack([np.interp(F, resp.force_N, resp.B_T[:, i]) for i in range(3)], -1) * 1e6 if n else np.zeros((0, 3))
    B = B + np.random.default_rng(draw(st.integers(0, 9))).normal(0, 2.0, B.shape)
    limit = mlx.CODE_RANGE_LSB[setting.res] if setting is not None else 0
    rows = []
    for f, b in zip(F, B):
        cells = {
            lt.FORCE_COLUMN: f"{f:.4f}",
            "gain_sel": str(setting.gain_sel) if setting else "0",
            "res": str(setting.res) if setting else "0",
        }
        if raw:
            lsb = (setting.xy_uT_per_lsb, setting.xy_uT_per_lsb, setting.z_uT_per_lsb)
            codes = np.clip(np.round(b / np.array(lsb)), -limit, limit).astype(int)
            cells.update({c: str(v) for c, v in zip(lt.CODE_COLUMNS, codes)})
        else:
            cells.update({c: f"{v:.3f}" for c, v in zip(lt.UT_COLUMNS, b)})
        rows.append([cells.get(c, "x") for c in cols])
    known = {lt.FORCE_COLUMN, *lt.SETTING_COLUMNS, *lt.UT_COLUMNS, *lt.CODE_COLUMNS}
    for c in cols:  # an extra column holds values of one type, drawn once per column
        if c not in known:
            # a rig's columns (issue 38) too: branch labels, a chip too hot or too cold, times that run back
            kinds = ["number", "integer", "text", "bool", "empty", "label", "hot", "cold", "descending", "ascending"]
            kind = draw(st.sampled_from(kinds))
            values = {"number": "23.5", "integer": "7", "text": "warm", "bool": "true", "empty": ""}
            values.update({"label": draw(st.sampled_from(["loading", "unloading", "hold", "Hold"])), "hot": "125.5"})
            values.update({"cold": "-40.5"})
            j = cols.index(c)
            for i, row in enumerate(rows):
                ordered = {"descending": str(len(rows) - i), "ascending": str(0.5 * i)}
                row[j] = ordered.get(kind, values.get(kind, ""))
    edges = [str(v) for v in (limit - 1, limit, -limit, 25000, 50000, -50000, 49999.999, 1e9)]
    for _ in range(draw(st.integers(0, 3))):
        if rows:
            i, j = draw(st.integers(0, len(rows) - 1)), draw(st.integers(0, len(cols) - 1))
            rows[i][j] = draw(st.one_of(st.sampled_from(HOSTILE_CELLS + edges), any_cell()))
    if rows and draw(st.integers(0, 6)) == 0:
        rows[draw(st.integers(0, len(rows) - 1))].pop()  # a short row
    delim = draw(st.sampled_from([",", ",", ";", "\t"]))
    lines = [delim.join(cols)] + [delim.join(r) for r in rows]
    if draw(st.integers(0, 6)) == 0:
        extra = draw(st.sampled_from(["# comment", "", "   ", delim.join(cols)]))
        lines.insert(draw(st.integers(0, len(lines))), extra)
    text = "\n".join(lines) + draw(st.sampled_from(["\n", "", "\r\n"]))
    return ("\ufeff" if draw(st.integers(0, 8)) == 0 else "") + text


@pytest.fixture(scope="module")
def forward_response(loadtest_files):
    return loadtest_files["resp"]


CAL_OUTPUTS = {"calibrated.yaml", "calibration.json", "residuals.csv", "lookup.csv", "force_table.h"}


@contextlib.contextmanager
def run_on_csv(command: str, text: str, *options):
    """``mst COMMAND FORWARD in.csv --out o OPTIONS`` in a fresh folder: (folder, result, seconds,
    warnings caught)."""
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        (folder / "in.csv").write_text(text)
        r, dt, caught = invoke([command, FORWARD, folder / "in.csv", "--out", folder / "o", *options])
        event(f"exit {r.exit_code}")
        yield folder, r, dt, caught


@settings(max_examples=40, **PROPERTY)
@given(data=st.data())
def test_property_load_tests_from_the_column_rules_keep_the_contract(forward_response, data):
    resp = forward_response
    text = data.draw(reading_files(True, resp, resp.chip_setting))
    with run_on_csv("calibrate", text, "--no-plot") as (folder, r, dt, caught):
        contract(r, dt, caught, folder, CAL_OUTPUTS, CAL_OUTPUTS - {"force_table.h"}, 20.0)
        assert_no_non_finite(folder / "o")
        if r.exit_code == 1:
            assert r.stderr.count("\n") == 1 and r.stderr.startswith("mst: calibration failed"), r.stderr


@settings(max_examples=60, **PROPERTY)
@given(data=st.data())
def test_property_readings_from_the_column_rules_keep_the_contract(forward_response, data):
    resp = forward_response
    text = data.draw(reading_files(False, resp, resp.chip_setting))
    with run_on_csv("read", text) as (folder, r, dt, caught):
        contract(r, dt, caught, folder, {"forces.csv"}, {"forces.csv"}, 10.0, chatter=("mst read: warning",))
        assert_no_non_finite(folder / "o")
        assert r.exit_code in (0, 2), r.stderr
        if r.exit_code == 0:
            flags = [row.rsplit(",", 2)[-2] for row in (folder / "o" / "forces.csv").read_text().splitlines()[1:]]
            from mst_cli.estimation.inverse_map import FLAGS

            assert set(flags) <= set(FLAGS), flags


# ----------------------------------------------------------------- manifests from the Manifest type
def manifest_paths(kind=None, prefix=""):
    """(dotted path, kind) of every field of export.json as :class:`Manifest` declares it."""
    from dataclasses import fields as dc_fields
    from dataclasses import is_dataclass

    from mst_cli.cad.manifest import ListOf, Manifest

    kind = Manifest if kind is None else kind
    for f in dc_fields(kind):
        sub, path = f.metadata["kind"], f"{prefix}{f.name}"
        yield path, sub
        if isinstance(sub, ListOf):  # (a ListOf is itself a dataclass instance)
            yield from manifest_paths(sub.kind, path + ".0.")
        elif isinstance(sub, type) and is_dataclass(sub):
            yield from manifest_paths(sub, path + ".")


def forward_design_dict() -> dict:
    """The reference design as export.json's ``design`` holds it."""
    from mst_cli.sensor.document import document_to_dict, load_document

    return document_to_dict(load_document(FORWARD))


def valid_for(kind):
    """Values the manifest's field ``kind`` accepts, drawn from its own bounds."""
    from dataclasses import fields as dc_fields
    from dataclasses import is_dataclass

    from mst_cli.cad import manifest as M

    if isinstance(kind, str):
        return {
            "num": st.floats(-M.MAX_COORD_MM, M.MAX_COORD_MM),
            "pos": st.floats(M.MIN_SIZE_MM, M.MAX_COORD_MM),
            "tol": st.floats(*M.STL_TOLERANCE_MM),
            "vol": st.floats(0, M.MAX_VOLUME),
            "int": st.integers(-(10**9), 10**9),
            "str": st.text(max_size=12),
            "design": st.just(forward_design_dict()),
        }[kind]
    if isinstance(kind, tuple):
        return st.lists(valid_for(kind[0]), min_size=kind[1], max_size=kind[1])
    if isinstance(kind, M.ListOf):
        return st.lists(valid_for(kind.kind), min_size=kind.min_len, max_size=3)
    assert isinstance(kind, type) and is_dataclass(kind)
    return st.fixed_dictionaries({f.name: valid_for(f.metadata["kind"]) for f in dc_fields(kind)})


MANIFEST_FIELDS = list(manifest_paths())
SLICE_READS = (
    "name",
    "print",
    "print.layer_height_mm",
    "print.pause",
    "print.cavity_lines",
    "print.wall_lines",
    "design",
)


@st.composite
def generated_manifests(draw, base: dict):
    """export.json: the reference export's with 1-3 fields of the Manifest type redrawn, from
    the field's own kind (mostly valid: the run goes on to the arithmetic) or hostile."""
    manifest = json.loads(json.dumps(base))
    for _ in range(draw(st.integers(1, 3))):
        path, kind = draw(st.sampled_from(MANIFEST_FIELDS))
        value = draw(
            st.one_of(
                valid_for(kind),
                valid_for(kind),
                values,
                st.just(KeyError),
                st.sampled_from([1e37, -1e37, 10**30, 1e-300, 0, -1, 1e-4, 1e-3, 1000.0]),
            )
        )
        with contextlib.suppress(KeyError, IndexError, TypeError):  # the path is gone (an earlier
            mutate(manifest, path, value)  # draw replaced its parent)
    return manifest


@pytest.fixture(scope="module")
def slice_base(exported):
    return exported_manifest(exported)


@settings(max_examples=60, **PROPERTY)
@given(data=st.data())
def test_property_manifests_from_the_manifest_type_keep_the_contract_in_check_and_slice(
    exported, slice_base, fake_slicer, data
):
    from mst_cli.cad.manifest import Manifest, SliceManifest
    from mst_cli.errors import InputError

    manifest = data.draw(generated_manifests(slice_base))
    fake_slicer(good_gcode(exported))
    try:
        Manifest.from_dict(manifest)
        whole = True
    except InputError:
        whole = False
    if whole:
        SliceManifest.from_dict(manifest)  # what check accepts, slice accepts: one set of rules
    with tempfile.TemporaryDirectory() as d:
        folder = slice_export(exported, Path(d) / "c", manifest)
        r, dt, caught = invoke(["check", folder, "--json"])
        contract(r, dt, caught, folder, set(), set(), 20.0)
        checked = r.exit_code
        assert (checked == 2) != whole, (checked, r.stderr)
        r, dt, caught = invoke(["slice", folder, "--no-plot", "--json"])
        event(f"check {checked}, slice {r.exit_code}")
        contract(
            r,
            dt,
            caught,
            folder,
            {"sensor.gcode", "slice.json"},
            {"sensor.gcode", "slice.json"},
            20.0,
            chatter=("[",),
            judged="mst slice: failed: ",
        )
        if r.exit_code == 2:
            assert checked == 2, r.stderr  # slice refuses only what check refuses too
        if r.exit_code != 2:
            report = load_json_strict(folder / "slice.json")
            assert report["name"] == manifest.get("name")


# ----------------------------------------------------------------- slicer results
@st.composite
def slicer_results(draw, good: bytes):
    """What a slicer may leave: the good G-code, empty, truncated anywhere, bytes dropped or
    garbled, numbers made hostile, the closing block gone, or nothing with exit 0 or 1."""
    code = draw(st.sampled_from([0, 0, 0, 1]))
    op = draw(st.sampled_from(["good", "none", "empty", "truncate", "garble", "numbers", "drop-lines", "no-end"]))
    data = good
    if op == "none":
        return None, code
    if op == "empty":
        data = draw(st.sampled_from([b"", b"\n", b"   \n\n"]))
    elif op == "truncate":
        data = good[: draw(st.integers(0, len(good) - 1))]
    elif op == "garble":
        at = draw(st.integers(0, len(good)))
        data = good[:at] + draw(st.binary(min_size=1, max_size=12)) + good[at:]
    elif op == "numbers":
        text = good.decode()
        tokens = list(re.finditer(r"-?\d+\.?\d*", text))
        for _ in range(draw(st.integers(1, 4))):
            m = draw(st.sampled_from(tokens))
            text = (
                text[: m.start()]
                + draw(st.sampled_from(["nan", "inf", "1e400", "-0", "99999999", "1e-300", "", "0", "-5"]))
                + text[m.end() :]
            )
            tokens = list(re.finditer(r"-?\d+\.?\d*", text))
        data = text.encode()
    elif op == "drop-lines":
        lines = good.decode().splitlines(keepends=True)
        keep = draw(st.lists(st.booleans(), min_size=len(lines), max_size=len(lines)))
        data = "".join(line for line, k in zip(lines, keep) if k or "prusaslicer_config = end" in line).encode()
    elif op == "no-end":
        data = good.decode().replace("; prusaslicer_config = end\n", "").encode()
    return data, code


@settings(max_examples=80, **PROPERTY)
@given(data=st.data())
def test_property_slicer_results_keep_the_contract(exported, fake_slicer, data):
    gcode, code = data.draw(slicer_results(good_gcode(exported)))
    fake_slicer(gcode, code)
    with tempfile.TemporaryDirectory() as d:
        folder = slice_export(exported, Path(d) / "c")
        r, dt, caught = invoke(["slice", folder, "--no-plot", "--json"])
        event(f"exit {r.exit_code}")
        contract(
            r,
            dt,
            caught,
            folder,
            {"sensor.gcode", "slice.json"},
            {"sensor.gcode", "slice.json"},
            20.0,
            chatter=("[",),
            judged="mst slice: failed: ",
        )
        said = [s for s in r.stderr.strip().splitlines() if not s.startswith("[")]
        if r.exit_code == 1:
            assert len(said) == 1 and said[0].startswith("mst slice: "), said
        if r.exit_code == 0 or "mst slice: failed: " in r.stderr:
            assert gcode is not None and (folder / "sensor.gcode").read_bytes() == gcode


# ----------------------------------------------------------------- one owner per shared bound
@st.composite
def valid_design_documents(draw):
    """A design of 1-4 layers with printer, family, magnet and housing keys at valid extremes
    of their own schema rules (in_bounds above)."""
    doc = yaml.safe_load(FORWARD.read_text())
    for section in ("printer", "family", "housing", "magnet"):
        rules = SECTIONS[section]
        for key in draw(st.lists(st.sampled_from(sorted(rules)), max_size=2, unique=True)):
            choices = in_bounds(rules[key])
            if choices:
                doc.setdefault(section, {})[key] = draw(st.sampled_from(choices))
    n = draw(st.integers(1, 4))
    doc["layers"] = [doc["layers"][i % len(doc["layers"])] for i in range(n)]
    doc["name"] = draw(st.sampled_from(["p", "µ-sensor", "x" * 60]))
    return doc


@settings(max_examples=150, **PROPERTY)
@given(raw=valid_design_documents(), tolerance=st.one_of(st.floats(1e-4, 1.0), st.sampled_from([1e-4, 1.0])))
def test_property_what_export_writes_check_and_slice_accept(raw, tolerance):
    from hypothesis import assume

    from mst_cli.cad.assembly import check_fits
    from mst_cli.cad.manifest import STL_TOLERANCE_MM, Manifest, SliceManifest, export_manifest
    from mst_cli.errors import InputError
    from mst_cli.sensor.document import parse_document

    lo, hi = STL_TOLERANCE_MM
    assume(lo <= tolerance <= hi)  # what 'mst export --stl-tolerance' accepts
    try:
        doc = parse_document(raw)
        geometry = doc.geometry()
        assume(not geometry.violations(doc.printer))
        check_fits(geometry)  # what 'mst export' checks before it writes
    except InputError:
        assume(False)
    event(f"{len(geometry.layers)} layers")
    manifest = json.loads(json.dumps(export_manifest(doc.name, geometry, doc.printer, tolerance, ["sensor.stl"])))
    Manifest.from_dict(manifest)  # mst check reads it
    SliceManifest.from_dict(manifest)  # mst slice reads it


# =========================================================================== issue 40: round three
# Each section below is one class of issue 40; each test failed (a traceback, exit 0 with nan
# written, a script run without consent) on the tree before its fix.


# ----------------------------------------------------------------- 18. a huge cell
@pytest.mark.parametrize("cmd", ["calibrate", "read"])
@pytest.mark.parametrize("size", [200_000, 20_000])
def test_a_huge_cell_in_an_extra_column_is_one_line_naming_file_line_and_column(tmp_path, loadtest_files, cmd, size):
    src = loadtest_files["lt" if cmd == "calibrate" else "readings"]
    lines = src.read_text().splitlines()
    lines[0] += ",note"
    lines[1:] = [line + ",ok" for line in lines[1:]]
    lines[3] = lines[3][: -len(",ok")] + "," + "x" * size
    f = tmp_path / "big-cell.csv"
    f.write_text("\n".join(lines) + "\n")
    r = run([cmd, FORWARD, f, "--out", tmp_path / "o"] + (["--no-plot"] if cmd == "calibrate" else []))
    line = refused(r, f"{f} line 4 column 'note'")
    assert f"{size} characters" in line and "at most 10000 characters" in line, line
    assert not (tmp_path / "o").exists()


# ----------------------------------------------------------------- 19. extra columns copied into forces.csv
def with_column(src: Path, dest: Path, name: str, value: str, row: int = 3) -> Path:
    """``src`` with a column ``name``: 1.5 in every row (1 in a cycle column: a whole number),
    ``value`` in data row ``row`` (from 1)."""
    lines = src.read_text().splitlines()
    lines[0] += f",{name}"
    filler = "1" if name == "cycle" else "1.5"
    lines[1:] = [line + (f",{value}" if i == row else f",{filler}") for i, line in enumerate(lines[1:], start=1)]
    dest.write_text("\n".join(lines) + "\n")
    return dest


@pytest.mark.parametrize("name", ["T_C", "time_s", "cycle", "note"])
@pytest.mark.parametrize("value", ["nan", "inf", "-Infinity", "1e400"])
def test_read_refuses_a_non_finite_number_in_an_extra_column(tmp_path, loadtest_files, name, value):
    f = with_column(loadtest_files["readings"], tmp_path / "r.csv", name, value)
    line = refused(run(["read", FORWARD, f, "--out", tmp_path / "o"]), f"{f} line 4 {name}")
    assert "finite" in line, line
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("name", ["T_C", "time_s", "cycle"])
def test_an_extra_column_with_a_meaning_must_hold_numbers(tmp_path, loadtest_files, name):
    f = with_column(loadtest_files["readings"], tmp_path / "r.csv", name, "warm")
    line = refused(run(["read", FORWARD, f, "--out", tmp_path / "o"]), f"{f} line 4 {name}")
    assert "must be a number" in line, line


def test_extra_columns_are_copied_checked_and_quoted(tmp_path, loadtest_files):
    f = with_column(loadtest_files["readings"], tmp_path / "r.csv", "note", '"pressed, twice"')
    f = with_column(f, tmp_path / "r2.csv", "T_C", "23.5")
    r = run(["read", FORWARD, f, "--out", tmp_path / "o"])
    assert r.exit_code == 0, r.stderr
    text = (tmp_path / "o" / "forces.csv").read_text()
    assert "nan" not in text.lower() and "inf" not in text.lower()
    import csv

    rows = list(csv.DictReader(text.splitlines()))
    assert rows[2]["note"] == "pressed, twice" and rows[2]["T_C"] == "23.5" and rows[0]["T_C"] == "1.5"


def test_a_load_test_refuses_nan_in_an_extra_column_too(tmp_path, loadtest_files):
    f = with_column(loadtest_files["lt"], tmp_path / "lt.csv", "T_C", "nan")
    refused(run(["calibrate", FORWARD, f, "--out", tmp_path / "o", "--no-plot"]), f"{f} line 4 T_C")
    assert not (tmp_path / "o").exists()


# ----------------------------------------------------------------- 20. no nan or inf in any output
NON_FINITE_CELL = re.compile(r"(?:^|[,;\t])\s*[-+]?(?:nan|inf|infinity)\s*(?=$|[,;\t])", re.IGNORECASE | re.MULTILINE)


def assert_no_non_finite(folder: Path) -> None:
    """No CSV cell and no JSON number in ``folder`` is nan or inf."""
    for p in Path(folder).rglob("*"):
        if p.suffix == ".csv":
            bad = NON_FINITE_CELL.search(p.read_text())
            assert bad is None, (p.name, bad.group(0))
        elif p.suffix == ".json":
            load_json_strict(p)


def face_half_mm() -> tuple[float, float]:
    g = load_document(FORWARD).geometry()
    return g.width_mm / 2, g.depth_mm / 2


def test_the_faces_corner_writes_an_empty_flagged_axial_reading_not_nan(tmp_path):
    """A press on the face's corner tilts the magnet until |B| falls below no load on the layers'
    load path (68 of 325 samples); on the whole part the cover turns as a beam past its lock and
    no sample gets there, so the case is the layers' path."""
    design = tmp_path / "layers.yaml"
    design.write_text(FORWARD.read_text() + "model:\n  load_path: layers\n")
    out = tmp_path / "o"
    r = run(["simulate", design, "--load-offset-mm", "15,10", "--out", out, "--no-plot"])
    assert r.exit_code == 0, r.stderr
    assert_no_non_finite(out)
    import csv

    rows = list(csv.DictReader((out / "offcentre.csv").read_text().splitlines()))
    empty = [row for row in rows if row["force_read_axial_N"] == ""]
    assert empty and all(row["read_error_N"] == "" and row["axial_reading_flag"] != "ok" for row in empty)
    assert {row["axial_reading_flag"] for row in empty} == {"below_no_load"}
    assert all(row["axial_reading_flag"] == "ok" for row in rows if row["force_read_axial_N"] != "")
    assert f"{len(empty)} of {len(rows)} force samples have no axial reading" in r.stdout, r.stdout
    report = load_json_strict(out / "report.json")
    assert report["off_centre"]["axial_reading"]["below_no_load"] == len(empty)


def test_the_offset_map_writes_empty_flagged_cells_not_nan(tmp_path, monkeypatch):
    """The map's forces lie at 25, 50 and 75 % of every regime's band. On the layers' load path
    the last regime spans 35 to 53 N, and a press on the face's corner at 48.6 N tilts the magnet
    until |B| falls below no load; on the whole part (the default) the last regime is 33.6 to
    34.4 N and no cell of the map reaches that tilt, so the case is the layers' path."""
    import mst_cli.api._simulating as S  # where the verb calls the kernel

    half = face_half_mm()
    real = S.run_offset_map
    monkeypatch.setattr(S, "run_offset_map", lambda *a, **k: real(*a, **dict(k, region_mm=half, grid=(3, 3))))
    design = tmp_path / "layers.yaml"
    design.write_text(FORWARD.read_text() + "model:\n  load_path: layers\n")
    out = tmp_path / "o"
    r = run(["simulate", design, "--offset-map", "--out", out, "--no-plot"])
    assert r.exit_code == 0, r.stderr
    assert_no_non_finite(out)
    rows = (out / "offset_map.csv").read_text().splitlines()
    assert rows[0].endswith(",read_error_rel,axial_reading_flag")
    assert any(row.endswith(",,below_no_load") for row in rows[1:])


@pytest.mark.slow
@settings(max_examples=12, **PROPERTY)
@given(fx=st.sampled_from([-1.0, -0.5, 0.0, 0.5, 0.9, 1.0]), fy=st.floats(-1.0, 1.0))
def test_property_no_output_holds_nan_or_inf_for_any_offset_on_the_face(fx, fy):
    hw, hd = face_half_mm()
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "o"
        r = run(["simulate", FORWARD, "--load-offset-mm", f"{fx * hw!r},{fy * hd!r}", "--out", out, "--no-plot"])
        event(f"exit {r.exit_code}")
        assert r.exit_code == 0, r.stderr
        assert_no_non_finite(out)


# ----------------------------------------------------------------- profiles with any post_process value
LINE_BREAKS = "\n\r\x0b\x0c\x1c\x1d\x1e\x85\u2028\u2029"


@settings(max_examples=40, **PROPERTY)
@given(
    value=st.one_of(
        st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters=LINE_BREAKS), max_size=40),
        st.lists(st.sampled_from(["", " ", "a.sh", "/bin/rm -rf x", "'q'", "x;y"]), max_size=4).map("\\n".join),
    ),
    consent=st.booleans(),
)
def test_property_profiles_with_any_post_process_value_keep_the_contract(exported, fake_slicer, value, consent):
    from mst_cli.cad.slicer import parse_ini, post_process_scripts

    fake = fake_slicer(good_gcode(exported))
    with tempfile.TemporaryDirectory() as d:
        profile = post_process_profile(Path(d), value)
        scripts = post_process_scripts(parse_ini(profile.read_text()))
        folder = slice_export(exported, Path(d) / "c")
        r, dt, caught = invoke(
            ["slice", folder, "--no-plot", "--profile", profile] + (["--allow-post-process"] if consent else [])
        )
        event(f"exit {r.exit_code}, {len(scripts)} scripts, consent {consent}")
        outputs = {"sensor.gcode", "slice.json"}
        contract(r, dt, caught, folder, outputs, outputs, 20.0, chatter=("[", "mst slice: note"))
        if scripts and not consent:
            line = refused(r, "--profile")
            assert "--allow-post-process" in line and fake.calls == 0
        else:
            assert r.exit_code == 0, r.stderr
            assert json.loads((folder / "slice.json").read_text())["post_process_run"] == scripts
