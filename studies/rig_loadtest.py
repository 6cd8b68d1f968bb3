"""A synthetic rig load test with known truth (issue 38): what a real TPU sensor on a rig gives.

The sensor is the bundled design configs/mohammadi2021-forward.yaml with the default 0.3 mm of air
over the board (:func:`rig_design`), as printed with walls
+0.04 mm, modulus x0.9 and the chip 0.2 mm further (``apply_parameters``), simulated once on the
spring rung (3 ms; the continuum rung takes about 0.8 s and moves the lock forces by 2-4 %, so
``forward_curve("continuum")`` is there for a study, the tests use the spring rung). On top of
that curve the rig adds, each with a stated truth:

* cycles: loading from 0 to a turning force (a fraction of the full scale, the last lock force)
  and unloading to 0, ``points_per_branch`` rows each, one row a second;
* hysteresis: on unloading the rig reads less force than the loading branch at the same
  deflection (the same field): F = F_load - h(F_load, F_turn), with the known truth
  h = pct/100 F_turn (x - x^3) / G_MAX, x = F_load / F_turn (zero at no load and at the turn,
  largest, pct % of the turning force, at x = 1/sqrt(3));
* stress softening: cycle 1 is ``first_cycle_pct`` % stiffer (deflection at F / (1 + p));
* holds: at the turning force of the cycles in ``hold_cycles`` the rig holds the force for
  ``hold_rows`` seconds and the sensor creeps: its deflection is that of F_turn (1 + c
  log10((t - t_peak) / 1 s)), c = ``creep_pct_per_decade`` / 100;
* drift: the chip's z offset drifts by ``drift_uT_per_s``;
* temperature: cycle k at ``T_C[k]``: remanence x (1 + alpha (T - 20 degC)) with alpha the grade's
  (-0.12 %/K, mst_cli.model.components) and modulus x (1 + beta (T - 20 degC)) with the test
  coefficient beta = ``modulus_coeff_per_K`` (TPU softens as it warms; -0.8 %/K is a stated test
  value, not a datasheet's). The laws are linear in E, so a modulus x m deflects at F like the
  reference at F / m: the field at (F, T) is r(T) B_ref(F / m(T)), exactly for a part all of
  TPU; with the default part's PLA insert, which softens far less, beta is the part's effective
  coefficient (the law mst_cli.calibration.temperature fits and the readers apply);
* the chip: 2 uT RMS noise per component, each component rounded to the chip setting's LSB;
  the load cell: ``force_noise_N`` RMS.

Run:  .venv/bin/python studies/rig_loadtest.py [--seed 1]
"""

from __future__ import annotations

import argparse
import functools
import math
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from mst_cli.model import chip as mlx
from mst_cli.model.components import MAGNET_REMANENCE_COEFF_PCT_PER_K
from mst_cli.model.response import simulate
from mst_cli.sensor.as_printed import apply_parameters
from mst_cli.sensor.document import load_document

ROOT = Path(__file__).resolve().parents[1]
DESIGN = ROOT / "configs" / "mohammadi2021-forward.yaml"
RIG_AIR_MM = 0.3  # the default housing.chip_clearance_mm: the cover lands inside the range
# Layer 2's height in the rig's sensor: 2.6 mm, not the bundled 2.8. As the rig prints it (walls
# +0.04 mm, modulus x0.9: PRINT), the bundled stack's last two layers lock 0.75 N apart (27.11 and
# 27.86 N), a regime 3 % of full scale that a load test's rows hardly resolve and whose lock order a
# model change can swap; at 2.6 mm they lock 23.3 and 27.9 N apart, every regime a band of its own.
RIG_LAYER_2_H_MM = 2.6


@functools.lru_cache(maxsize=1)
def rig_design() -> Path:
    """The rig's sensor as a design file (in a temporary folder): the bundled forward design with
    the default 0.3 mm of air, on which issue 38's rig was defined, and layer 2 at
    RIG_LAYER_2_H_MM. Its cover lands on the board inside the range, and that corner of the load
    curve tells the gap offset from the remanence to ~0.05 mm (the fit's 1 sigma on the rig of
    tests/test_rig_flow.py; misses up to 0.095 mm over noise seeds 1-5, studies/rig_seeds.py).
    The bundled config keeps the cover off the board (0.65 mm); there a rig's gap offset spreads
    0.08 mm RMS over noise seeds (docs/design.md 4.6, Contacts)."""
    raw = yaml.safe_load(DESIGN.read_text())
    raw["housing"] = {**raw.get("housing", {}), "chip_clearance_mm": RIG_AIR_MM}
    raw["layers"][1] = {**raw["layers"][1], "h_mm": RIG_LAYER_2_H_MM}
    path = Path(tempfile.mkdtemp(prefix="mst-rig-")) / DESIGN.name
    path.write_text(yaml.safe_dump(raw, sort_keys=False))
    return path


PRINT = {"wall_offset_mm": 0.04, "modulus_factor": 0.9, "gap_offset_mm": 0.2}
NOISE_uT = 2.0
G_MAX = 2.0 / (3.0 * math.sqrt(3.0))  # max of x - x^3 on [0, 1], at x = 1/sqrt(3)
T_REF_C = 20.0


@dataclass(frozen=True)
class Curve:
    """The sensor's forward curve: field components (T) against force (N)."""

    force_N: np.ndarray
    B_T: np.ndarray  # (n, 3)
    lock_forces_N: tuple[float, ...]
    xy_uT_per_lsb: float
    z_uT_per_lsb: float
    grade: str
    mechanics: str

    @property
    def full_scale_N(self) -> float:
        return self.lock_forces_N[-1]

    def field_T(self, force_N) -> np.ndarray:
        F = np.asarray(force_N, dtype=float)
        return np.stack([np.interp(F, self.force_N, self.B_T[:, i]) for i in range(3)], -1)

    def field_abs_T(self, force_N) -> np.ndarray:
        return np.linalg.norm(self.field_T(force_N), axis=-1)


def forward_curve(mechanics: str = "spring", design: Path | None = None) -> Curve:
    """The printed sensor's curve (``design``, by default :func:`rig_design`, as printed with
    :data:`PRINT`)."""
    doc = load_document(design or rig_design())
    printed, _ = apply_parameters(doc, PRINT)
    resp = simulate(printed.geometry(), printed.material, mechanics=mechanics, noise_uT_rms=NOISE_uT)
    s = resp.chip_setting
    assert s is not None
    return Curve(
        resp.force_N, resp.B_T, tuple(resp.lock_forces_N), s.xy_uT_per_lsb, s.z_uT_per_lsb, doc.magnet.grade, mechanics
    )


@dataclass(frozen=True)
class Rig:
    cycles: int = 4
    turn_fraction: tuple[float, ...] = ()  # per cycle, of the full scale; default 1.0 for all
    points_per_branch: int = 40
    hysteresis_pct: float = 3.0
    first_cycle_pct: float = 0.0
    hold_cycles: tuple[int, ...] = ()
    hold_rows: int = 60
    creep_pct_per_decade: float = 0.0
    drift_uT_per_s: float = 0.0
    T_C: tuple[float, ...] = ()  # per cycle; default 20 degC for all
    modulus_coeff_per_K: float = -0.008
    noise_uT: float = NOISE_uT
    force_noise_N: float = 0.01
    dt_s: float = 1.0
    seed: int = 0


@dataclass
class Truth:
    rig: Rig
    curve: Curve
    remanence_coeff_pct_per_K: float
    turn_forces_N: list[float] = field(default_factory=list)
    peak_rows: list[int] = field(default_factory=list)
    valley_rows: list[int] = field(default_factory=list)
    holds: list[tuple[int, int]] = field(default_factory=list)
    force_load_N: np.ndarray | None = None  # per row: the loading-branch force of the row's deflection
    h_N: np.ndarray | None = None  # per row: the hysteresis truth (0 off the unloading rows)


def hysteresis_N(F_load, F_turn, pct: float) -> np.ndarray:
    """The truth h(F_load, F_turn) = pct/100 F_turn (x - x^3) / G_MAX, x = F_load / F_turn."""
    x = np.clip(np.asarray(F_load, dtype=float) / F_turn, 0.0, 1.0)
    return 0.01 * pct * F_turn * (x - x**3) / G_MAX


def _cycle_rows(rig: Rig, k: int, F_turn: float) -> list[tuple[float, float, str, float]]:
    """(rig force, deflection-equivalent force, branch, seconds since the peak or NaN) of cycle k."""
    n = rig.points_per_branch
    up = np.linspace(0.0, F_turn, n + 1)
    rows = [(float(f), float(f), "loading", math.nan) for f in (up if k == 1 else up[1:])]
    if k in rig.hold_cycles:
        c = 0.01 * rig.creep_pct_per_decade
        for j in range(1, rig.hold_rows + 1):
            dt = j * rig.dt_s
            rows.append((F_turn, F_turn * (1.0 + c * math.log10(dt / 1.0)), "hold", dt))
    F_load = np.linspace(F_turn, 0.0, n + 1)[1:]
    F = F_load - hysteresis_N(F_load, F_turn, rig.hysteresis_pct)
    rows += [(float(f), float(fl), "unloading", math.nan) for f, fl in zip(F, F_load)]
    return rows


def rig_loadtest(rig: Rig, curve: Curve | None = None) -> tuple[dict[str, np.ndarray], Truth]:
    """The rows (force_N, Bx_uT, By_uT, Bz_uT, time_s, cycle, branch, T_C) and the truth."""
    curve = curve or forward_curve()
    fractions = rig.turn_fraction or (1.0,) * rig.cycles
    temps = rig.T_C or (T_REF_C,) * rig.cycles
    truth = Truth(rig, curve, MAGNET_REMANENCE_COEFF_PCT_PER_K[curve.grade])
    F, Fe, branch, cycle, T = [], [], [], [], []
    for k in range(1, rig.cycles + 1):
        F_turn = fractions[k - 1] * curve.full_scale_N
        rows = _cycle_rows(rig, k, F_turn)
        truth.turn_forces_N.append(F_turn)
        first = len(F)
        peak = first + sum(r[2] == "loading" for r in rows) - 1  # the last loading row
        truth.peak_rows.append(peak)
        if k in rig.hold_cycles:
            truth.holds.append((peak + 1, peak + 1 + rig.hold_rows))
        for f, fe, b, _ in rows:
            F.append(f), Fe.append(fe), branch.append(b), cycle.append(k), T.append(temps[k - 1])
        if k < rig.cycles:
            truth.valley_rows.append(len(F) - 1)
    F_a, Fe_a, T_a, cyc = np.array(F), np.array(Fe), np.array(T), np.array(cycle)
    stiff = np.where(cyc == 1, 1.0 + 0.01 * rig.first_cycle_pct, 1.0)
    m = 1.0 + rig.modulus_coeff_per_K * (T_a - T_REF_C)
    r = 1.0 + 0.01 * truth.remanence_coeff_pct_per_K * (T_a - T_REF_C)
    B = r[:, None] * curve.field_T(Fe_a / (stiff * m))
    t = rig.dt_s * np.arange(len(F_a))
    B[:, 2] += 1e-6 * rig.drift_uT_per_s * t
    rng = np.random.default_rng(rig.seed)
    B = B + 1e-6 * rig.noise_uT * rng.standard_normal(B.shape)
    lsb = np.array([curve.xy_uT_per_lsb, curve.xy_uT_per_lsb, curve.z_uT_per_lsb])
    B_uT = np.stack([mlx.quantise_lsb(B[:, i], lsb[i]) * lsb[i] for i in range(3)], -1)
    truth.force_load_N = Fe_a
    truth.h_N = np.where(np.array(branch) == "unloading", Fe_a - F_a, 0.0)
    rows_out = {
        "force_N": F_a + rig.force_noise_N * rng.standard_normal(len(F_a)),
        "Bx_uT": B_uT[:, 0],
        "By_uT": B_uT[:, 1],
        "Bz_uT": B_uT[:, 2],
        "time_s": t,
        "cycle": cyc,
        "branch": np.array(branch, dtype=object),
        "T_C": T_a,
    }
    return rows_out, truth


def truth_hysteresis_pct(truth: Truth, lo_N: float, hi_N: float) -> tuple[float, float]:
    """(largest truth hysteresis in % of the band hi - lo, at the loading force) for loads
    F_load in [lo, hi], cycles to the largest turning force."""
    F_turn = max(truth.turn_forces_N)
    F = np.linspace(lo_N, hi_N, 2001)
    h = hysteresis_N(F, F_turn, truth.rig.hysteresis_pct)
    i = int(np.argmax(h))
    return float(100.0 * h[i] / (hi_N - lo_N)), float(F[i])


def hysteresis_peak_tolerance_N(truth: Truth, lo_N: float, hi_N: float, rows: int) -> float:
    """What the rig's noise allows a measured hysteresis peak in [lo, hi] from ``rows``
    unloading rows: 3 standard errors of a cubic least-squares fit at its band's end, 4 sigma /
    sqrt(rows), sigma a row's force noise (the chip's noise over the curve's slope at the band's
    middle, and the load cell's)."""
    c, F_mid = truth.curve, 0.5 * (lo_N + hi_N)
    slope_T_per_N = float(np.interp(F_mid, c.force_N, np.gradient(c.field_abs_T(c.force_N), c.force_N)))
    sigma_N = math.hypot(1e-6 * truth.rig.noise_uT / slope_T_per_N, truth.rig.force_noise_N)
    return 3.0 * 4.0 * sigma_N / math.sqrt(rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--mechanics", default="spring")
    args = ap.parse_args()
    curve = forward_curve(args.mechanics)
    rows, truth = rig_loadtest(Rig(seed=args.seed, first_cycle_pct=8.0, hold_cycles=(3,), creep_pct_per_decade=1.0))
    print(f"{len(rows['force_N'])} rows, locks at {', '.join(f'{f:.2f}' for f in curve.lock_forces_N)} N")
    edges = (0.0, *curve.lock_forces_N)
    for lo, hi in zip(edges[:-1], edges[1:]):
        pct, at = truth_hysteresis_pct(truth, lo, hi)
        print(f"regime {lo:5.1f}..{hi:5.1f} N: truth hysteresis {pct:.2f} % of the band at {at:.1f} N")


if __name__ == "__main__":
    main()
