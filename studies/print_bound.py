"""Issue 21 item 4: the lowest worst print deviation at <= 20 mm for the paper's targets, with any
scaling of the webs' stiffness, and the physical terms it is made of.

Prints markdown tables, changes nothing. From the repository root:

    MST_WORKERS=1 .venv/bin/python studies/print_bound.py [--quick] [--height 20] [--spec FILE]

About 4-6 minutes on one core (359 s on a loaded machine) (``--quick``: m 1, 6, 12, s_min 0 and
0.05, 1 % bisection: 80 s).
Every "lowest" is the best the shipped local solver (seed 0) finds: an upper bound on the true
minimum, and the lowest-height column is not always monotone in the scale bound for that reason.

"Worst print deviation" is report.json's ``print_error_sensitivity.worst_change_rel``: the largest
|relative change| of any S_i or R_i when every wall is printer.wall_tolerance_mm (0.05 mm)
thicker or thinner (:func:`mst_cli.design.verify.verify_design`, forward model L0).

1. **One scale for every web** (a web of depth 20/m mm, or a modulus E/m: k and R of every layer
   scale by 1/m). As issue 21 emulated it: the full-depth part designed for S_i/m and R_i m.
   Per m, the lowest worst deviation that :func:`mst_cli.design.document.design_document` meets
   with design.max_height_mm and design.max_print_deviation_rel (bisection on the limit; every
   number from its forward-model verification), the best point of the ``--pareto 12`` front at
   or below the height, and the lowest height at which 25 % is met.
2. **A free scale per layer** (each layer its own web depth or modulus): a
   :class:`~mst_cli.design.problem.DesignProblem` whose laws are scaled per layer by
   s_i = R*_i / R_i(full depth), clipped to [s_min, 1] when a printable web depth bounds it; same
   solver, bisection, and outputs checked against :func:`forward` (the forward model's numbers).
3. **Decomposition** of the worst output of each best design: the same forward model with the
   wall thickness moved in one place only -- the wall section (A = b t, I = b t^3 / 12), the wall
   length L = (h - t) / (2 sin theta), the lock stroke h - 2t - a, the L2-fitted joint and lock
   factors (functions of t/L and the stroke ratio), the web's finite-depth factor, the locked
   pads' contact stiffness -- and the magnet gap (gap0 depends on the layer heights only,
   :func:`mst_cli.model.assembly.unloaded_gap_mm`: measured as the change of gap0 itself).

Measured on configs/mohammadi2021.yaml (STEMMA board, housing 11.35 mm of the height) with 0.12's
L0: today's full-depth webs reach 45.7 % at 20.00 mm; one scale for every web bottoms out near
33 % (32.8 % at m = 6, 34.1 % at m = 12; at m = 16 no design of <= 20 mm meets the targets, at
m = 24 none at all: the stiff layers reach theta = 75 deg). The worst output is always a
sensitivity with thinner walls, and it is the walls' stiffness (section + length + L2 fits, 24-32
points) that moves it; the stroke adds 1.6-8.5 points, the magnet gap nothing. A free scale per
layer reaches 20.7-23.8 % with webs 0.2-0.5 mm deep, 26.8 % with webs >= 1 mm, 31.1 % >= 2 mm.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace
from functools import partial

import numpy as np

from mst_cli import api
from mst_cli.design.document import design_document
from mst_cli.design.problem import DesignProblem
from mst_cli.design.solver import solve
from mst_cli.model.cell import lock_stroke_mm, wall_centreline_length_mm
from mst_cli.model.mechanics import correction
from mst_cli.model.mechanics.depth import web_modulus_MPa
from mst_cli.model.mechanics.spring import contact_stiffness_N_per_mm, layer_stiffness_N_per_mm
from mst_cli.model.response import field_magnitude_T, regime_kernel, simulate
from mst_cli.sensor.as_printed import as_printed
from mst_cli.sensor.sections import OBJECTIVE_TERMS

TERMS = ("section", "length", "stroke", "fits", "web", "contact")
HEIGHT_ONLY = np.array([1.0 if term == "height" else 0.0 for term in OBJECTIVE_TERMS])


# --------------------------------------------------------------------------- forward model, term by term
def term_laws(cells: dict, E: float, nu: float, t: dict) -> tuple:
    """(k, d_lock, R, k_locked) of L0 (:func:`mst_cli.model.mechanics.spring.spring_arrays` on the
    web modulus of :func:`mst_cli.model.mechanics.layer_laws`), each use of the wall thickness
    reading its own entry of ``t`` (TERMS): equal entries give the shipped law to the bit."""
    th, h, a, b = cells["theta"], cells["h"], cells["a"], cells["b"]
    E_web = web_modulus_MPa(th, t["web"], h, b, E, nu)
    # L = (h' - t_section) / (2 sin theta) with h' = h - t_length + t_section: the length term's t
    k = layer_stiffness_N_per_mm(th, t["section"], h - t["length"] + t["section"], b, E_web, nu)
    d_geo = lock_stroke_mm(t["stroke"], h, a)
    L_fit = wall_centreline_length_mm(th, t["fits"], h)
    x = t["fits"] / L_fit
    sigma = correction.stroke_ratio(lock_stroke_mm(t["fits"], h, a), L_fit, th)
    k = k * correction.stiffness_factor(x, th)
    force_factor, stroke_factor = correction.lock_factors(x, th, sigma)
    d_lock = d_geo * stroke_factor
    R = np.minimum(k * d_geo * force_factor, k * d_lock)
    k_locked = k + contact_stiffness_N_per_mm(th, t["contact"], cells["W"], b, E_web, nu)
    return k, d_lock, R, k_locked


def forward(doc, scale=1.0, shifted=TERMS, dt_mm: float = 0.0) -> np.ndarray:
    """(S_1..S_n, R_1..R_n) of the design ``doc`` as printed, every layer's web stiffness times
    ``scale`` (one number or one per layer), the walls ``dt_mm`` thicker in the TERMS ``shifted``."""
    printed = as_printed(doc)
    g, mat = printed.geometry(), printed.material
    c0 = g.layers[0]
    cells = {
        "theta": np.array([c.theta_rad for c in g.layers]),
        "h": np.array([c.h_mm for c in g.layers]),
        "a": c0.contact_allowance_mm,
        "b": c0.b_mm,
        "W": c0.width_mm,
    }
    t0 = np.array([c.t_mm for c in g.layers])
    t = {term: t0 + (dt_mm if term in shifted else 0.0) for term in TERMS}
    k, d_lock, R, k_locked = term_laws(cells, mat.youngs_modulus_MPa, mat.poisson_ratio, t)
    s = np.broadcast_to(np.asarray(scale, dtype=float), k.shape)
    field = partial(field_magnitude_T, geometry=g, model="axial")
    _, S, _, _ = regime_kernel(k * s, d_lock, k_locked * s, g.gap0_mm, field, R * s)
    return np.concatenate([S, R * s])


def check_forward(doc) -> float:
    """Largest |relative difference| of :func:`forward` against the forward model
    (:func:`mst_cli.model.response.simulate` on the part as printed), nominal and walls +- 0.05 mm."""
    worst = 0.0
    for dt in (0.0, 0.05, -0.05):
        printed = as_printed(doc, dt)
        resp = simulate(printed.geometry(), printed.material, field_model="axial")
        ref = np.array([r.sensitivity_secant_per_N for r in resp.regimes] + list(resp.lock_forces_N))
        worst = max(worst, float(np.max(np.abs(forward(doc, dt_mm=dt) / ref - 1.0))))
    return worst


def decompose(doc, scale=1.0, dt_mm: float = 0.05) -> dict:
    """The worst output at walls +- ``dt_mm`` and its relative change (%) with every term, each
    term alone, every term but the stroke (a stroke the wall tolerance does not reach), and the
    magnet gap's own change (mm)."""
    nominal = forward(doc, scale)
    n = len(nominal) // 2
    both = {sign: forward(doc, scale, TERMS, sign * dt_mm) / nominal - 1.0 for sign in (1.0, -1.0)}
    sign, j = max(((s, int(np.argmax(np.abs(v)))) for s, v in both.items()), key=lambda p: abs(both[p[0]][p[1]]))
    name = f"{'S' if j < n else 'R'}_{j % n + 1} at t {'+' if sign > 0 else '-'} {dt_mm:g}"
    parts = {term: 100 * (forward(doc, scale, (term,), sign * dt_mm)[j] / nominal[j] - 1.0) for term in TERMS}
    rest = tuple(term for term in TERMS if term != "stroke")
    no_stroke = 100 * (forward(doc, scale, rest, sign * dt_mm)[j] / nominal[j] - 1.0)
    gap = as_printed(doc, sign * dt_mm).geometry().gap0_mm - as_printed(doc).geometry().gap0_mm
    return {"output": name, "all": 100 * both[sign][j], "parts": parts, "no_stroke": no_stroke, "gap0_mm": gap}


# --------------------------------------------------------------------------- one scale for every web
def scaled_spec(base, m: float, **design):
    """The spec with every web's stiffness 1/m of the full-depth part: targets S_i / m, R_i m."""
    layers = [
        replace(la, target_sensitivity_per_N=la.target_sensitivity_per_N / m, target_range_N=la.target_range_N * m)
        for la in base.layers
    ]
    return replace(base.with_layers(layers), design={**base.design, **design})


def bisect(met, lo: float = 0.05, hi: float = 0.60, step: float = 0.005):
    """The lowest limit (to ``step``) at which ``met(limit)`` returns a design (None: none at hi)."""
    best = met(hi)
    if best is None:
        return None
    while hi - lo > step:
        mid = 0.5 * (lo + hi)
        found = met(mid)
        if found is None:
            lo = mid
        else:
            hi, best = mid, found
    return best


def common_scale(base, m: float, height: float, step: float) -> dict:
    """Row of table 1: the lowest worst deviation at <= ``height`` for one scale m, its design."""

    def met(limit):
        r = design_document(
            scaled_spec(base, m, max_height_mm=height, max_print_deviation_rel=limit), name_height=False
        )
        return r if r.status == "met" else None

    best = bisect(met, step=step)
    _, front = api.pareto(scaled_spec(base, m, max_height_mm=None), 12)
    inside = [p for p in front if p.height_mm <= height + 1e-9]
    pareto = min(inside, key=lambda p: p.print_worst_change) if inside else None
    low = design_document(
        scaled_spec(
            base, m, max_height_mm=None, max_print_deviation_rel=0.25, objective=dict(zip(OBJECTIVE_TERMS, HEIGHT_ONLY))
        ),
        name_height=False,
    )
    return {
        "label": f"m = {m:g}",
        "worst": None if best is None else 100 * best.print_error["worst_change_rel"],
        "height": None if best is None else best.geometry.total_height_mm,
        "cells": None if best is None else best.document,
        "scale": 1.0,
        "pareto": None if pareto is None else (100 * pareto.print_worst_change, pareto.height_mm),
        "h25": low.geometry.total_height_mm if low.status == "met" else None,
    }


# --------------------------------------------------------------------------- a free scale per layer
class FreeScale(DesignProblem):
    """The design problem with every layer's web stiffness scaled by s_i = R*_i / R_i (its lock
    force at full depth), clipped to [``s_min``, ``s_max``]: a web of depth 20 s_i mm, or a modulus
    s_i E, of its own. Unclipped, every R_i meets its target and the solver matches the S_i
    with the geometry; the robustness constraints see the scale of the nominal walls."""

    def __init__(self, doc, s_min: float = 0.0, s_max: float = np.inf):
        super().__init__(doc)
        self.s_bounds = (s_min, s_max)

    def scales(self, R_full: np.ndarray) -> np.ndarray:
        return np.clip(self.R_target / R_full, *self.s_bounds)

    def _scaled(self, laws: tuple, R_full: np.ndarray) -> tuple:
        if np.shape(R_full)[-1:] != (self.n,):
            return laws  # the start's table of single cells (mst_cli.design.seed): full depth
        s = self.scales(R_full)
        k, d_lock, R, k_locked = laws
        return k * s, d_lock, R * s, k_locked * s

    def layer_laws(self, theta_deg, t_mm, h_mm) -> tuple:
        laws = super().layer_laws(theta_deg, t_mm, h_mm)
        return self._scaled(laws, laws[2])

    def shifted_layer_laws(self, theta_deg, t_mm, h_mm, dt_mm) -> tuple:
        laws = super().shifted_layer_laws(theta_deg, t_mm, h_mm, dt_mm)
        return self._scaled(laws, laws[2][0])  # the nominal walls' scale for all three

    def print_shift_log(self, theta_deg, t_mm, h_mm, dt_mm=None, nominal=None) -> np.ndarray:
        """ln(out(t +- dt) / out(t)) with the nominal walls' scale (the base class would rescale
        the shifted walls to their targets, hiding the R_i changes)."""
        theta_deg, t_mm, h_mm = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (theta_deg, t_mm, h_mm)))
        dt = self.wall_tolerance_mm if dt_mm is None else dt_mm
        R, S, *_ = self._responses_of(
            self.shifted_layer_laws(theta_deg, t_mm, h_mm, dt), np.broadcast_to(h_mm, (3,) + h_mm.shape)
        )
        out = np.log(np.maximum(np.concatenate([S, R], axis=-1), 1e-300))
        return out[1:] - out[:1]


def free_design(base, limit: float | None, height: float | None, s_bounds: tuple, weights=None) -> dict | None:
    """The FreeScale design under the limits, judged by :func:`forward` (None: it misses a target,
    a rule or the limit)."""
    design = {**base.design, "max_height_mm": height, "max_print_deviation_rel": limit}
    problem = FreeScale(replace(base, design=design), *s_bounds)
    sol = solve(problem, seed=0, max_evaluations=20000, weights=weights)
    theta, t, h = (np.round(a, 4) for a in problem.to_physical(sol.u))
    layers = [
        replace(la, theta_deg=float(a), t_mm=float(b), h_mm=float(c)) for la, a, b, c in zip(base.layers, theta, t, h)
    ]
    doc = base.with_layers(layers)
    scale = problem.scales(DesignProblem.layer_laws(problem, theta, t, h)[2])
    nominal = forward(doc, scale)
    worst = max(float(np.max(np.abs(forward(doc, scale, TERMS, s * 0.05) / nominal - 1.0))) for s in (1.0, -1.0))
    rules = problem.evaluate_physical(theta, t, h).constraints[: -8 * problem.n if limit is not None else None]
    on_target = np.all(np.abs(nominal / problem.targets - 1.0) <= problem.tolerance_rel)
    if not (on_target and np.all(rules <= 0.0) and (limit is None or worst <= limit)):
        return None
    return {"doc": doc, "scale": scale, "worst": 100 * worst, "height": doc.geometry().total_height_mm}


def free_scale(base, s_min: float, height: float, step: float) -> dict:
    """Row of table 2: the lowest worst deviation at <= ``height`` with a free scale per layer in
    [s_min, 1] (a web at most full depth and at least 20 s_min mm deep); s_min 0: any s > 0."""
    bounds = (s_min, 1.0) if s_min > 0 else (0.0, np.inf)
    best = bisect(lambda limit: free_design(base, limit, height, bounds), step=step)
    low = free_design(base, 0.25, None, bounds, weights=HEIGHT_ONLY)
    label = "free, any s > 0" if s_min <= 0 else f"free, s in [{s_min:g}, 1] (web >= {20 * s_min:g} mm)"
    return {
        "label": label,
        "worst": None if best is None else best["worst"],
        "height": None if best is None else best["height"],
        "cells": None if best is None else best["doc"],
        "scale": None if best is None else best["scale"],
        "pareto": None,
        "h25": None if low is None else low["height"],
    }


# --------------------------------------------------------------------------- tables
def _pct(value) -> str:
    return "--" if value is None else f"{value:.1f}"


def _cells(doc) -> str:
    if doc is None:
        return "--"
    return " / ".join(f"{la.theta_deg:.1f}deg {la.t_mm:.2f} {la.h_mm:.2f}" for la in doc.layers)


def print_rows(title: str, rows: list[dict], height: float) -> None:
    print(f"\n### {title}\n")
    print(
        f"| web scale | lowest worst [%] at <= {height:g} mm | its height [mm] | Pareto-12 best <= {height:g} mm "
        "[% at mm] | lowest height for 25 % [mm] | web depth 20 s_i [mm] | theta t h per layer | time [s] |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        pareto = "--" if r["pareto"] is None else f"{r['pareto'][0]:.1f} at {r['pareto'][1]:.2f}"
        depth = "--" if r["scale"] is None else " / ".join(f"{20 * s:.2f}" for s in np.atleast_1d(r["scale"]))
        if r["label"].startswith("m ="):
            depth = f"{20 / float(r['label'][4:]):.2f} (all)"
        height_s = "--" if r["height"] is None else f"{r['height']:.2f}"
        h25 = "--" if r["h25"] is None else f"{r['h25']:.2f}"
        print(
            f"| {r['label']} | {_pct(r['worst'])} | {height_s} | {pareto} | {h25} | {depth} | "
            f"{_cells(r['cells'])} | {r['time']:.0f} |"
        )


def print_decomposition(rows: list[dict]) -> None:
    print("\n### Decomposition of each best design's worst output (relative change, %; walls all +- 0.05 mm)\n")
    print(
        "| design | height [mm] | worst output | all terms | "
        + " | ".join(TERMS)
        + " | sum | all but stroke | gap0 change [mm] |"
    )
    print("|---|---|---|---|" + "---|" * (len(TERMS) + 3))
    for r in rows:
        if r["cells"] is None:
            continue
        d = decompose(r["cells"], r["scale"])
        parts = " | ".join(f"{d['parts'][term]:+.1f}" for term in TERMS)
        print(
            f"| {r['label']} | {r['height']:.2f} | {d['output']} | {d['all']:+.1f} | {parts} | "
            f"{sum(d['parts'].values()):+.1f} | {d['no_stroke']:+.1f} | {d['gap0_mm']:+.3f} |"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="m 1, 6, 12; s_min 0, 0.05; 1 %% bisection")
    ap.add_argument("--height", type=float, default=20.0, help="total height budget, mm [20]")
    ap.add_argument("--spec", default="configs/mohammadi2021.yaml")
    args = ap.parse_args()
    base = api.load(args.spec)
    step = 0.01 if args.quick else 0.005
    m_values = (1.0, 6.0, 12.0) if args.quick else (1.0, 3.0, 6.0, 12.0, 16.0, 24.0)
    s_values = (0.0, 0.05) if args.quick else (0.0, 0.01, 0.025, 0.05, 0.1, 0.25)
    start = time.perf_counter()
    common, free = [], []
    for m in m_values:
        t0 = time.perf_counter()
        common.append(common_scale(base, m, args.height, step) | {"time": time.perf_counter() - t0})
    for s_min in s_values:
        t0 = time.perf_counter()
        free.append(free_scale(base, s_min, args.height, step) | {"time": time.perf_counter() - t0})
    print_rows("One scale for every web (targets S_i/m, R_i m on the full-depth part)", common, args.height)
    print_rows("A free scale per layer, s_i = R*_i / R_i(full depth)", free, args.height)
    print_decomposition(common + free)
    checked = [r["cells"] for r in common if r["cells"] is not None]
    if checked:
        diff = max(check_forward(doc) for doc in checked)
        print(f"\nterm-split forward model against mst's simulate (walls 0, +-0.05 mm): largest difference {diff:.1e}")
    print(f"\ntotal {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
