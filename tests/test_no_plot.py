"""Pictures on demand (issue 14): --no-plot on every command that draws, --json implies it, the
non-plot path never imports matplotlib, and an old picture never survives beside newer results."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from mst_cli.cli.app import main

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"
SPEC = ROOT / "configs" / "fingertip.yaml"
SIM_FILES = {"report.json", "response.csv"}


def run(args):
    return CliRunner().invoke(main, [str(a) for a in args])


def modules_after(args) -> set[str]:
    """Top-level packages a command imported: run in-process in a fresh interpreter (this test
    session may have imported matplotlib already)."""
    code = (
        "import sys\nfrom mst_cli.cli.app import main\n"
        f"sys.argv = ['mst'] + {[str(a) for a in args]!r}\n"
        "try:\n    main()\nexcept SystemExit as exc:\n    assert not exc.code, exc.code\n"
        "print(','.join(sorted({m.split('.')[0] for m in sys.modules})), file=sys.stderr)\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0, r.stderr
    return set(r.stderr.strip().splitlines()[-1].split(","))


@pytest.mark.parametrize("flags", [["--no-plot"], ["--json"], ["--json", "--no-plot"]])
def test_simulate_without_the_picture_writes_no_png_and_imports_no_matplotlib(tmp_path, flags):
    out = tmp_path / "o"
    mods = modules_after(["simulate", FORWARD, "--out", out, *flags])
    assert "matplotlib" not in mods
    assert {p.name for p in out.iterdir()} == SIM_FILES
    assert "mst_cli" in mods  # the probe did see the command's imports


def test_the_picture_imports_matplotlib_so_the_probe_can_see_it(tmp_path):
    assert "matplotlib" in modules_after(["simulate", FORWARD, "--out", tmp_path / "o"])


def test_design_without_the_picture_imports_no_matplotlib(tmp_path):
    out = tmp_path / "d"
    mods = modules_after(["design", SPEC, "--out", out, "--no-plot", "--quiet"])
    assert "matplotlib" not in mods
    assert {p.name for p in out.iterdir()} == SIM_FILES | {"design.yaml"}


def test_a_stale_picture_is_removed_and_a_failed_run_keeps_the_old_set(tmp_path):
    out = tmp_path / "o"
    assert run(["simulate", FORWARD, "--out", out]).exit_code == 0
    assert (out / "response.png").is_file()
    # a run that fails on its input leaves the earlier complete set whole, picture included
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: bad\nlayers: []\n")
    assert run(["simulate", bad, "--out", out, "--no-plot"]).exit_code == 2
    assert {p.name for p in out.iterdir()} == SIM_FILES | {"response.png"}
    # a run without the picture: the old one goes, it must not pass for this run's
    before = (out / "report.json").stat().st_mtime_ns
    r = run(["simulate", FORWARD, "--out", out, "--no-plot"])
    assert r.exit_code == 0, r.output
    assert {p.name for p in out.iterdir()} == SIM_FILES
    assert (out / "report.json").stat().st_mtime_ns >= before
    assert "response.png" not in r.stdout and "response.csv" in r.stdout


def test_json_output_is_the_report_written(tmp_path):
    out = tmp_path / "j"
    r = run(["simulate", FORWARD, "--out", out, "--json"])
    assert r.exit_code == 0
    assert json.loads(r.stdout) == json.loads((out / "report.json").read_text())
    assert not (out / "response.png").exists()


def test_design_json_and_no_plot_write_no_picture(tmp_path):
    out = tmp_path / "d"
    assert run(["design", SPEC, "--out", out, "--quiet"]).exit_code == 0
    assert (out / "response.png").is_file()
    r = run(["design", SPEC, "--out", out, "--json"])
    assert r.exit_code == 0, r.output
    assert {p.name for p in out.iterdir()} == SIM_FILES | {"design.yaml"}
    assert json.loads(r.stdout) == json.loads((out / "report.json").read_text())


def _load_test_csv(path: Path) -> None:
    """A noise-free load test of the design itself (force_N, Bx_uT, By_uT, Bz_uT)."""
    from mst_cli.model.response import simulate
    from mst_cli.sensor.document import load_design_document

    doc, geometry = load_design_document(FORWARD)
    resp = simulate(geometry, doc.material, noise_uT_rms=doc.noise_uT_rms)
    F = np.linspace(0.0, resp.max_force_N, 60)
    B = np.stack([np.interp(F, resp.force_N, resp.B_T[:, i]) for i in range(3)], -1) * 1e6
    path.write_text(
        "force_N,Bx_uT,By_uT,Bz_uT\n" + "".join(f"{f:.5f},{x:.4f},{y:.4f},{z:.4f}\n" for f, (x, y, z) in zip(F, B))
    )


def test_calibrate_no_plot(tmp_path):
    lt = tmp_path / "lt.csv"
    _load_test_csv(lt)
    out = tmp_path / "c"
    assert run(["calibrate", FORWARD, lt, "--out", out, "--params", "modulus_factor"]).exit_code == 0
    assert (out / "calibration.png").is_file()
    mods = modules_after(["calibrate", FORWARD, lt, "--out", out, "--params", "modulus_factor", "--no-plot"])
    assert "matplotlib" not in mods
    assert not (out / "calibration.png").exists()
    assert {"calibrated.yaml", "calibration.json", "lookup.csv"} <= {p.name for p in out.iterdir()}


def test_bench_no_plot_drops_the_picture(tmp_path, monkeypatch):
    from mst_cli.bench import ladder_bench

    monkeypatch.setattr(ladder_bench, "run_bench", lambda **kw: {"models": {}})
    monkeypatch.setattr(ladder_bench, "bench_markdown", lambda result: "# bench\n")
    out = tmp_path / "b"
    out.mkdir()
    (out / "bench.png").write_bytes(b"old")
    r = run(["bench", "--out", out, "--no-plot"])
    assert r.exit_code == 0, r.output
    assert {p.name for p in out.iterdir()} == {"bench.md", "bench.json"}


@pytest.mark.parametrize(
    "command, picture, implied",
    [
        ("simulate", "response.png", True),
        ("design", "response.png", True),
        ("calibrate", "calibration.png", False),
        ("bench", "bench.png", False),
        ("slice", "print.png", True),
    ],
)
def test_every_drawing_command_offers_the_same_no_plot(command, picture, implied):
    r = run([command, "--help"])
    assert r.exit_code == 0
    text = " ".join(r.stdout.split())
    assert "--no-plot" in text and f"Draw no {picture}" in text and "import no matplotlib" in text
    assert ("--json implies it" in text) == implied


def test_a_design_without_a_front_removes_an_older_front(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    for name in ("pareto.csv", "pareto.png"):
        (out / name).write_text("from an older run")
    r = run(["design", str(ROOT / "configs" / "mohammadi2021.yaml"), "--out", str(out), "--no-plot", "-q"])
    assert r.exit_code == 0, r.output
    assert not (out / "pareto.csv").exists() and not (out / "pareto.png").exists()
    assert (out / "design.yaml").is_file()
