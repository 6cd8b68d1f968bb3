"""What ``mst read`` and ``mst calibrate`` give a section-mode design (``model.load_path: section``)
against the closed form reading the same fields (docs/design.md 4.7, "The read side"). Prints a
table, changes nothing.

    PYTHONPATH=. .venv/bin/python studies/section_reading.py

The forward design with ``model: {load_path: section}``: its simulated presses (centred, at
(3, 2) mm, centred with a tangential force of 0.2 Fz along x) written as a rig's readings file,
and a load test of the same part with its TPU 15 % softer. Each is read (calibrated) by the
section-mode file and by the same file in the closed form (``load_path: part``). A round trip
through mst's own section model: it shows the inverse and what the closed form would make of the
same fields, not that the model is right. About 2 min on two cores with a warm cache.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import yaml

from mst_cli import api

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"
SOFTER = 0.85


def forward_copy(folder: Path, load_path: str, modulus_factor: float = 1.0) -> Path:
    """The forward design with ``model.load_path`` set, its TPU's modulus scaled (the tests'
    copies too, tests/test_section_reading.py)."""
    raw = yaml.safe_load(FORWARD.read_text())
    raw["model"] = {**(raw.get("model") or {}), "load_path": load_path}
    raw["material"]["youngs_modulus_MPa"] *= modulus_factor
    path = folder / f"forward-{load_path}-{modulus_factor:g}.yaml"
    path.write_text(yaml.safe_dump(raw, sort_keys=False))
    return path


def fields_csv(path: Path, force_N: np.ndarray, B_T: np.ndarray) -> Path:
    """A readings file of the forces and the fields (T) at them, as a rig writes it."""
    rows = "".join(f"{f:.6f},{1e6 * b[0]:.4f},{1e6 * b[1]:.4f},{1e6 * b[2]:.4f}\n" for f, b in zip(force_N, B_T))
    path.write_text("force_N,Bx_uT,By_uT,Bz_uT\n" + rows)
    return path


def span(values: np.ndarray) -> str:
    v = 100 * values[np.isfinite(values)]
    return f"{v.min():+.1f} .. {v.max():+.1f} %" if v.size else "nothing read"


def main() -> None:
    quiet = lambda _line: None  # noqa: E731 -- a design file read as a model warns that it is one
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        models = {"section": forward_copy(d, "section"), "closed form": forward_copy(d, "part")}
        rows = []
        resp = api.simulate(models["section"])
        pick = np.linspace(5, np.flatnonzero(resp.in_range)[-1] - 5, 12).astype(int)
        csv = fields_csv(d / "centred.csv", resp.force_N[pick], resp.B_T[pick])
        for name, model in models.items():
            got = api.read(model, csv, warn=quiet).force_N
            rows.append(("centred, force", name, span(got / resp.force_N[pick] - 1)))
        for label, kw, est in (
            ("at (3, 2) mm", {"offset_mm": (3.0, 2.0)}, "offset"),
            ("0.2 Fz along x", {"offset_mm": (0.0, 0.0), "shear_ratio": (0.2, 0.0)}, "shear"),
        ):
            r = api.simulate_offcentre(models["section"], **kw)
            last = r.axial.regimes[-1].force_to_N
            pick = np.flatnonzero((r.force_N > 0.1 * last) & (r.force_N < 0.9 * last))[::10]
            csv = fields_csv(d / f"{est}.csv", r.force_N[pick], r.B_T[pick])
            for name, model in models.items():
                got = api.read(model, csv, estimate=est, polish=True, warn=quiet).offset
                ok = got.flag == "ok"
                F = r.force_N[pick][ok]
                rows.append((f"{label}, force", name, span(got.force_N[ok] / F - 1)))
                if est == "offset":
                    off = np.hypot(got.x_mm[ok] - 3.0, got.y_mm[ok] - 2.0)
                    rows.append((f"{label}, place", name, f"at most {off.max():.3f} mm off"))
                else:
                    rows.append((f"{label}, Fx", name, span(got.shear_x_N[ok] / (0.2 * F) - 1)))
        printed = api.simulate(forward_copy(d, "section", SOFTER))
        pick = np.flatnonzero(printed.in_range)[::4]
        test = fields_csv(d / "load_test.csv", printed.force_N[pick], printed.B_T[pick])
        for name, model in models.items():
            f = api.calibrate(model, test, params="modulus_factor").fit.values["modulus_factor"]
            rows.append((f"TPU x {SOFTER}: modulus factor", name, f"{f:.4f}"))
    print("| what | read by | read / true - 1 (or the value) |\n|---|---|---|")
    for row in rows:
        print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
