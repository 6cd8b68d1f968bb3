"""How far a wall's root turns into the TPU plate under it, over the design box (issue 44,
docs/design.md 4.7): the whole-part rung on same-layer designs, swept over the wall's angle and
thickness and the plate's thickness. Writes a CSV, changes nothing.

    PYTHONPATH=. .venv/bin/python studies/root_turn_sweep.py [--out root_turn.csv]
    PYTHONPATH=. .venv/bin/python studies/root_turn_sweep.py --fit studies/data/root_turn_*.csv

studies/data/root_turn_low.csv is the low corner the designs reach (``--h 1.5 --theta 8 12 26 45
65 75 --t 0.4 0.55 --plates 0.8 1.6`` and ``--h 1.22 --theta 8 12 18 26 35 45 58 65 75 --t 0.4
--plates 0.8 1.6 2.4``, the undrawable cells skipped). ``--fit`` also fits a squeeze logarithmic
in the plate, s ln(1 + w plate/t)/(E'D) (studies/data/plate_joint_log_squeeze.patch puts it in the
model; docs/design.md 4.7, "The low corner").

Each design is the forward config with three identical layers (theta, t, h) and plates ``plate``
mm thick; in regime 1 (every layer open) the plates' turn at the wall heads vanishes by the
cell's mirror symmetry, so the plates' extra drop on the rung (plates in TPU less every member
rigid, :func:`studies.plate_walls.rung_rows`) is the roots' local turn alone
(:func:`studies.plate_walls.mechanisms`). Per design the CSV has that drop and the c of the root's
spring M / theta = c E'D t^2 that reproduces it. Two rung solves a design, about 10 s each.
"""

from __future__ import annotations

import argparse
import csv
import itertools
import tempfile
from pathlib import Path

import numpy as np
import yaml

import mst_cli as mst
from mst_cli.errors import InputError
from mst_cli.model import load_path as lp
from mst_cli.model import plate_joint as pj
from mst_cli.model.mechanics import layer_laws
from studies.plate_walls import FORWARD, fit_c, rung_rows

THETA_DEG = (15.0, 33.0, 50.0)
T_MM = (0.4, 0.7, 1.0, 1.4)
PLATE_MM = (0.8, 1.6, 2.4)
H_MM = (2.4, 3.6)


def design(folder: Path, theta: float, t: float, h: float, plate: float) -> Path:
    """The forward config with three layers (theta, t, h) and plates ``plate`` mm thick."""
    base = yaml.safe_load(FORWARD.read_text())
    layer = {"theta_deg": theta, "t_mm": t, "h_mm": h}
    name = f"same-{theta:g}-{t:g}-{h:g}-{plate:g}"
    doc = {**base, "name": name, "layers": [layer] * 3, "housing": {"plate_mm": plate}}
    path = folder / f"{doc['name']}.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("root_turn.csv"))
    ap.add_argument("--h", type=float, nargs="*", default=H_MM, help="the layers' heights, mm")
    ap.add_argument("--t", type=float, nargs="*", default=T_MM, help="the walls' thicknesses, mm")
    ap.add_argument("--theta", type=float, nargs="*", default=THETA_DEG, help="the walls' angles, degrees")
    ap.add_argument("--plates", type=float, nargs="*", default=PLATE_MM, help="the plates' thicknesses, mm")
    ap.add_argument("--fit", type=Path, nargs="*", help="no rung: fit model.plate_joint's constants on these CSVs")
    args = ap.parse_args()
    if args.fit:
        fit(args.fit)
        return
    with tempfile.TemporaryDirectory() as tmp, args.out.open("w", newline="") as f:
        out = csv.writer(f)
        out.writerow(["theta_deg", "t_mm", "h_mm", "plate_mm", "rung_um_per_N", "c"])
        for h, theta, t, plate in itertools.product(args.h, args.theta, args.t, args.plates):
            try:
                row = rung_rows(design(Path(tmp), theta, t, h, plate), regimes=1)[0]
            except InputError as e:  # a cell that cannot be drawn
                print(f"  skipped theta {theta} t {t} h {h} plate {plate}: {e}", flush=True)
                continue
            out.writerow([theta, t, h, plate, f"{1e3 * row['rung']:.4f}", f"{fit_c([row]):.4f}"])
            f.flush()


def features(paths: list[Path]) -> dict[str, np.ndarray]:
    """Per design of the CSVs: its wall, plate, the rung's plates and the closed form's beams
    (mm/N), and the layers' own compliance (L0, small load, mm/N)."""
    cols: dict[str, list] = {k: [] for k in ("theta", "t", "h", "plate", "depth", "E", "rung", "beams", "layers")}
    with tempfile.TemporaryDirectory() as tmp:
        for path in paths:
            for r in csv.DictReader(path.open()):
                v = {k: float(x) for k, x in r.items()}
                doc, _ = mst.designed(design(Path(tmp), v["theta_deg"], v["t_mm"], v["h_mm"], v["plate_mm"]))
                g, m = doc.geometry(), doc.material
                cell = g.layers[0]
                row = (cell.theta_rad, cell.t_mm, cell.h_mm, g.housing.plate_mm, g.depth_mm,
                       m.youngs_modulus_MPa / (1.0 - m.poisson_ratio**2), 1e-3 * v["rung_um_per_N"],
                       sum(lp.members(g, m).plates_mm_per_N),
                       sum(1.0 / law.k_N_per_mm for law in layer_laws(g.layers, m, "spring")))  # fmt: skip
                for key, value in zip(cols, row):
                    cols[key].append(value)
    return {k: np.array(v) for k, v in cols.items()}


def joints(f: dict[str, np.ndarray], *constants: float) -> np.ndarray:
    """model.plate_joint's joints of a same-layer stack of three (4 roots on its 2 plates), mm/N,
    with the constants (c, a, b, s); with five (c, a, b, s, w), the squeeze s ln(1 + w plate/t)/(E'D)
    in place of the model's s plate/(E'D t)."""
    if len(constants) == 5:
        c, a, b, s, w = constants
        turn = joints(f, c, a, b, 0.0)
        return turn + s * np.log1p(w * f["plate"] / f["t"]) / (f["E"] * f["depth"])  # 4 roots x 1/4
    return 4.0 * pj.root_joint_mm_per_N(f["theta"], f["t"], f["h"], f["plate"], f["depth"], f["E"], constants)


def fit(paths: list[Path]) -> None:
    """Fit (c, a, b, s) on the designs' layers and plates together (what the part's prediction
    sees: a 1 % error there is 1 % of the part), then print the fit's and model.plate_joint's errors."""
    # deferred: scipy only for the fit
    from scipy.optimize import least_squares

    f = features(paths)
    truth, total = f["rung"] - f["beams"], f["layers"] + f["rung"]
    found = least_squares(lambda x: (joints(f, *x) - truth) / total, [0.4, -0.8, 0.0, 0.8]).x
    log = least_squares(lambda x: (joints(f, *x) - truth) / total, [0.4, -0.8, 0.0, 0.8, 1.0]).x
    (c,) = least_squares(lambda x: (joints(f, x[0], 0.0, 0.0, 0.0) - truth) / total, [0.4]).x
    model = pj.FITTED
    print(f"{len(truth)} designs; c, a, b, s fitted: " + ", ".join(f"{x:.3f}" for x in found))
    print("  with the logarithmic squeeze, c, a, b, s, w: " + ", ".join(f"{x:.3f}" for x in log))
    forms = (("fitted", found), ("logarithmic squeeze, fitted", log), ("one spring alone (c only)", (c, 0.0, 0.0, 0.0)))
    for name, x in (*forms, ("model.plate_joint", model)):
        on_total = (joints(f, *x) - truth) / total
        on_plates = (joints(f, *x) + f["beams"]) / f["rung"] - 1.0
        print(f"  {name}: layers and plates worst {100 * np.max(np.abs(on_total)):.2f} %, rms "
              f"{100 * np.sqrt(np.mean(on_total**2)):.2f} %; the plates alone worst "
              f"{100 * np.max(np.abs(on_plates)):.0f} %, rms {100 * np.sqrt(np.mean(on_plates**2)):.0f} %")  # fmt: skip
    worst = np.argsort(-np.abs(joints(f, *model) - truth) / total)[:5]  # on the layers and plates
    print("  model.plate_joint's five furthest designs (theta, t, h, plate; the rung's plates / the model's, um/N):")
    mine = joints(f, *model) + f["beams"]
    for i in worst:
        cell = f"{np.degrees(f['theta'][i]):.0f} deg, {f['t'][i]:g}, {f['h'][i]:g}, {f['plate'][i]:g} mm"
        print(f"    {cell}: {1e3 * f['rung'][i]:.1f} / {1e3 * mine[i]:.1f}")


if __name__ == "__main__":
    main()
