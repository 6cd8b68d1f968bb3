"""Inverse design (library level): round trips, the reference spec, the preference, diagnoses.

Every check of an achieved number re-runs the forward model (mst_cli.model.response.simulate) on the
design as written to design.yaml and loaded back, and compares it with the spec's targets.
"""

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import fsolve

from mst_cli.design import design_document
from mst_cli.design.explain import limits
from mst_cli.design.problem import DesignProblem
from mst_cli.errors import InputError
from mst_cli.model.cell import HexCell, cell_margins_mm
from mst_cli.model.mechanics.correction import VERIFIED_BOX
from mst_cli.model.printer import Printer
from mst_cli.model.response import simulate
from mst_cli.sensor.document import load_document, parse_document
from mst_cli.sensor.sections import DEFAULT_DESIGN

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "configs" / "fingertip.yaml"  # met by the printable cell
PAPER = ROOT / "configs" / "mohammadi2021.yaml"  # the paper's own targets
PRINT_ERROR_T_MM = Printer().wall_tolerance_mm  # the default printer's wall tolerance


def layers_only(doc):
    """The spec designed for its layers between rigid plates (model.load_path: layers): the
    optimiser's own tests on the paper's targets, which the part with today's TPU cap, plates and
    cover cannot reach (docs/design.md 4.6; tests/test_part_prediction.py designs the whole part)."""
    return replace(doc, load_path="layers")


def spec_doc(targets, load_path="layers", **design):
    """A spec with the reference file's constants and the given (S, R) targets."""
    raw = yaml.safe_load(SPEC.read_text())
    raw["model"] = {**(raw.get("model") or {}), "load_path": load_path}
    raw["layers"] = [{"target_sensitivity_per_N": float(s), "target_range_N": float(r)} for s, r in targets]
    raw.setdefault("design", {}).update(design)
    return parse_document(raw)


def forward(result, tmp_path):
    """Write design.yaml, load it back as a user would, and simulate it: (S_i, R_i, doc, geometry)."""
    path = tmp_path / "design.yaml"
    path.write_text(yaml.safe_dump(result.design_yaml_dict(), sort_keys=False))
    doc = load_document(path)
    geometry = doc.geometry()
    resp = simulate(
        geometry, doc.material, mechanics=doc.mechanics, whole_part=doc.whole_part, section=doc.section_rung
    )
    S = [r.sensitivity_secant_per_N for r in resp.regimes]
    R = [0.0] * len(doc.layers)
    for r in resp.regimes:
        R[r.layer - 1] = r.force_to_N
    return np.array(S), np.array(R), doc, geometry, resp


def random_specs(n_layers, count, seed):
    """Targets of seeded random valid designs (every constraint held with slack)."""
    probe = DesignProblem(spec_doc([(1.0, i + 1.0) for i in range(n_layers)]))
    theta, t, h = probe.sample_feasible(np.random.default_rng(seed), count)
    specs = []
    for j in range(count):
        cells = [probe.family.cell(*x) for x in zip(theta[j], t[j], h[j])]
        resp = simulate(probe.doc.geometry(cells), probe.doc.material, whole_part=False)
        specs.append([(r.sensitivity_secant_per_N, r.force_to_N) for r in resp.regimes])
    return specs


# --------------------------------------------------------------------------- the reference spec
@pytest.mark.parametrize(
    "config, max_height_mm",
    [("mohammadi2021.yaml", None), pytest.param("mohammadi2021-compact.yaml", 16.0, marks=pytest.mark.slow)],
)
def test_paper_targets_are_met_and_the_compact_part_is_at_most_16_mm(config, max_height_mm, tmp_path):
    """The paper's S = 0.26/0.08/0.03 1/N and R = 0.9/4.8/16.2 N (docs/design.md's table), re-simulated
    from the written design.yaml; with a board without connector sockets in at most 16 mm, the part
    as the whole-part rung measures it (the compact config's model.load_path: section; its layers
    alone between rigid plates would need more height than 16 mm)."""
    doc = load_document(ROOT / "configs" / config)
    result = design_document(doc if doc.section_rung else layers_only(doc))
    assert result.status == "met", result.reasons
    S, R, designed, geometry, _ = forward(result, tmp_path)
    assert np.all(np.abs(S / [0.26, 0.08, 0.03] - 1) <= 0.02)
    assert np.all(np.abs(R / [0.9, 4.8, 16.2] - 1) <= 0.02)
    assert geometry.violations(designed.printer) == []
    if max_height_mm is not None:
        assert geometry.total_height_mm <= max_height_mm


def test_issue_round_trip_designs_back_a_simulated_stubby_design(tmp_path):
    """(theta, t, h) = (28, 0.8, 2.6), (36, 1.3, 3.6), (42, 1.8, 4.5) -- walls up to t/L 0.9 --
    simulated, and its S_i, R_i given back as targets: mst design meets them."""
    doc = layers_only(load_document(PAPER))
    cells = [doc.family.cell(*x) for x in ((28, 0.8, 2.6), (36, 1.3, 3.6), (42, 1.8, 4.5))]
    resp = simulate(doc.geometry(cells), doc.material, whole_part=False)
    S = [r.sensitivity_secant_per_N for r in resp.regimes]
    R = [r.force_to_N for r in resp.regimes]
    assert [r.layer for r in resp.regimes] == [1, 2, 3]
    assert max(c.t_mm / c.wall_length_mm for c in cells) > 0.85  # past the old 0.6 fence
    result = design_document(spec_doc(list(zip(S, R))))
    assert result.status == "met", result.reasons
    S2, R2, _, _, _ = forward(result, tmp_path)
    assert np.all(np.abs(S2 / S - 1) <= 0.02) and np.all(np.abs(R2 / R - 1) <= 0.02)


def test_fingertip_spec_meets_all_six_targets_within_2_percent_with_printable_cells(tmp_path):
    doc = layers_only(load_document(SPEC))
    result = design_document(doc)
    assert result.status == "met" and result.exit_code == 0, result.reasons
    S, R, designed, geometry, resp = forward(result, tmp_path)
    # the spec's own numbers (configs/fingertip.yaml), not the code's output
    assert np.all(np.abs(S / [0.26, 0.08, 0.03] - 1) <= 0.02)
    assert np.all(np.abs(R / [1.5, 6.0, 16.2] - 1) <= 0.02)
    assert geometry.violations(designed.printer) == []
    box = VERIFIED_BOX
    for cell in geometry.layers:
        assert box["theta_deg"][0] <= cell.theta_deg <= box["theta_deg"][1]
        assert box["t_mm"][0] <= cell.t_mm <= box["t_mm"][1] and box["h_mm"][0] <= cell.h_mm <= box["h_mm"][1]
        assert cell.cavity_height_mm >= designed.printer.min_gap_mm
    assert [r.layer for r in resp.regimes] == [1, 2, 3]  # locks bottom to top
    assert R[1] >= 1.1 * R[0] and R[2] >= 1.1 * R[1]  # with the lock margin
    assert resp.B_full_T <= 0.9 * 50e-3 and not resp.saturated
    # the table and the report carry the forward-model numbers
    rows = result.targets
    assert [r["achieved_range_N"] for r in rows] == pytest.approx(R, rel=1e-12)
    assert [r["achieved_sensitivity_per_N"] for r in rows] == pytest.approx(S, rel=1e-12)


def test_same_spec_and_seed_give_byte_identical_design_yaml():
    doc = layers_only(load_document(SPEC))
    a = yaml.safe_dump(design_document(doc, seed=7).design_yaml_dict(), sort_keys=False)
    b = yaml.safe_dump(design_document(doc, seed=7).design_yaml_dict(), sort_keys=False)
    assert a == b


# --------------------------------------------------------------------------- round trip
@pytest.mark.parametrize("n_layers", [1, 2, 3, 4, 5, 6])
def test_round_trip_recovers_random_valid_designs_targets(n_layers, tmp_path):
    """Simulate a random valid design, take its S and R as targets, design, recover them."""
    for k, targets in enumerate(random_specs(n_layers, 3, seed=100 + n_layers)):
        result = design_document(spec_doc(targets), seed=k)
        assert result.status == "met", (n_layers, k, result.reasons)
        S, R, designed, geometry, _ = forward(result, tmp_path)
        S_t, R_t = np.array(targets).T
        assert np.all(np.abs(S / S_t - 1) <= 0.02) and np.all(np.abs(R / R_t - 1) <= 0.02)
        assert geometry.violations(designed.printer) == []


# --------------------------------------------------------------------------- the design loop's kernels
@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_layers=st.integers(1, 6))
def test_vectorised_problem_agrees_with_the_forward_model(seed, n_layers):
    """The batched S_i, R_i the optimiser sees are the forward model's, for any valid design."""
    probe = DesignProblem(spec_doc([(1.0, i + 1.0) for i in range(n_layers)], load_path="part"))
    theta, t, h = probe.sample_feasible(np.random.default_rng(seed), 1)
    ev = probe.evaluate_physical(theta[0], t[0], h[0])
    cells = [probe.family.cell(*x) for x in zip(theta[0], t[0], h[0])]
    resp = simulate(probe.doc.geometry(cells), probe.doc.material)
    assert ev.S_per_N == pytest.approx([r.sensitivity_secant_per_N for r in resp.regimes], rel=1e-9)
    assert ev.R_N == pytest.approx([r.force_to_N for r in resp.regimes], rel=1e-9)
    assert float(ev.B_full_T) == pytest.approx(resp.B_full_T, rel=1e-9)
    assert float(ev.total_height_mm) == pytest.approx(probe.doc.geometry(cells).total_height_mm, rel=1e-12)


@pytest.mark.parametrize("gap_offset_mm", [0.27, -0.5])
def test_the_problem_builds_the_printers_gap_where_simulate_does(gap_offset_mm):
    """A printer whose magnet-chip gap is built 0.27 mm wider (what the calibration of
    tests/test_calibration_record fits) or 0.5 mm narrower: the optimiser's part is the forward
    model's part as built, the offset in the cover's air over the board (so the cover lands on it
    later or sooner) and, past that air, in the pocket floor; not only in the gap. The print is
    written into the file's keys by hand (the spec's air + offset, else 0 and the floor the rest)."""
    printer = {"wall_offset_mm": 0.05, "modulus_factor": 0.85, "gap_offset_mm": gap_offset_mm}
    probe = DesignProblem(replace(spec_doc([(1.0, 2.0), (0.5, 8.0)], load_path="part"), printer=Printer(**printer)))
    theta, t, h = probe.sample_feasible(np.random.default_rng(3), 1)
    ev = probe.evaluate_physical(theta[0], t[0], h[0])
    raw = yaml.safe_load(SPEC.read_text())
    raw["model"] = {"load_path": "part"}
    raw["material"]["youngs_modulus_MPa"] *= 0.85
    air_mm, floor_mm = raw["housing"].get("chip_clearance_mm", 0.3) + gap_offset_mm, 0.4
    if air_mm < 0:
        air_mm, floor_mm = 0.0, floor_mm + air_mm
    raw["housing"].update(chip_clearance_mm=air_mm, pocket_floor_mm=floor_mm)
    raw["layers"] = [{"theta_deg": a, "t_mm": b + 0.05, "h_mm": c} for a, b, c in zip(theta[0], t[0], h[0])]
    printed = parse_document(raw)
    resp = simulate(printed.geometry(), printed.material)
    assert ev.S_per_N == pytest.approx([r.sensitivity_secant_per_N for r in resp.regimes], rel=1e-9)
    assert ev.R_N == pytest.approx([r.force_to_N for r in resp.regimes], rel=1e-9)
    assert float(ev.gap0_mm) == pytest.approx(resp.gap_mm[0], rel=1e-12)


def test_unit_variables_map_onto_the_bounds_and_back():
    P = DesignProblem(layers_only(load_document(SPEC)))
    theta, t, h = P.to_physical(np.array([0, 0, 0, 1, 1, 1, 0.5, 0.5, 0.5]))
    lo, hi = DEFAULT_DESIGN["theta_deg_bounds"]
    (t0, t1), (h0, h1) = DEFAULT_DESIGN["t_mm_bounds"], DEFAULT_DESIGN["h_mm_bounds"]
    assert theta == pytest.approx([lo, hi, 0.5 * (lo + hi)]) and t == pytest.approx([t0, t1, math.sqrt(t0 * t1)])
    assert h == pytest.approx([h0, h1, math.sqrt(h0 * h1)])  # log scale: geometric mean
    u = np.random.default_rng(1).random(9)
    assert P.to_unit(*P.to_physical(u)) == pytest.approx(u)


def test_cell_margins_kernel_against_hand_geometry():
    """theta 45, t 1, h 4, W 30: p = 15 - 2/tan45 = 13; inner pad = 13 - tan(22.5 deg)."""
    m = cell_margins_mm(math.radians(45), 1.0, 4.0, 30.0, 0.1, 0.4, 0.4, 0.4)
    expect = [0.6, 2.0 - 0.4, 2.0 - 0.1, 13 - math.tan(math.radians(22.5)) - 0.4]
    assert m == pytest.approx(expect, abs=1e-12)
    cell = HexCell(45, 1.0, 4.0)
    assert [v.margin_mm for v in cell.margins()] == pytest.approx(expect, abs=1e-12)


# --------------------------------------------------------------------------- the preference
def _one_layer_family(P, th0, t0, h0):
    """Members of the one-parameter family of exact one-layer solutions, traced independently
    with scipy's fsolve: continuation in theta from the chosen design, 0.5 deg at a time in both
    directions, solving S(t, h) = S*, R(t, h) = R*, plus the members on the t bounds solved for
    (theta, h); only members inside the bounds that satisfy every rule."""

    def admissible(theta, t, h):
        ev = P.evaluate_physical([theta], [t], [h])
        inside = np.all(P.lo - 1e-9 <= [theta, t, h]) and np.all([theta, t, h] <= P.hi + 1e-9)
        return inside and np.max(np.abs(ev.log_err)) < 1e-8 and np.all(ev.constraints <= 0)

    members = []
    for direction in (+0.5, -0.5):
        guess = [math.log(t0), math.log(h0)]
        theta = th0
        while P.lo[0] <= theta + direction <= P.hi[0]:
            theta += direction
            x, _, ok, _ = fsolve(
                lambda x, theta=theta: P.evaluate_physical([theta], [math.exp(x[0])], [math.exp(x[1])]).log_err,
                guess,
                full_output=True,
            )
            if ok != 1:
                break
            guess = list(x)
            members.append((theta, math.exp(x[0]), math.exp(x[1])))
    for t_edge in P.lo[1], P.hi[1]:
        x, _, ok, _ = fsolve(
            lambda x, t_edge=t_edge: P.evaluate_physical([10 * x[0]], [t_edge], [math.exp(x[1])]).log_err,
            [th0 / 10, math.log(h0)],
            full_output=True,
        )
        members.append((10 * x[0], t_edge, math.exp(x[1])))
    return [m for m in members if admissible(*m)]


@pytest.mark.parametrize(
    "objective",
    [
        {"height": 0.0, "force_resolution": 0.0, "print_robustness": 1.0},  # most print-robust
        None,  # the default weights
        {"height": 1.0, "force_resolution": 0.0, "print_robustness": 0.0},  # shortest part
    ],
)
def test_chosen_design_minimises_the_preference_over_the_one_layer_solutions(objective):
    """One layer: 3 variables, 2 targets leave a one-parameter family of exact solutions; no
    member may have a lower preference (design.objective's weighted terms) than the design mst
    picked."""
    extra = {} if objective is None else {"objective": objective}
    doc = spec_doc([(0.1, 5.0)], theta_deg_bounds=[15.0, 60.0], **extra)
    result = design_document(doc)
    assert result.status == "met"
    P = DesignProblem(doc)
    row = result.targets[0]
    th0, t0, h0 = row["theta_deg"], row["t_mm"], row["h_mm"]

    def pref(theta, t, h):
        return float(P.preference(P.evaluate_physical([theta], [t], [h])))

    # fsolve's probes on the t bounds wander as far as theta 182 deg, h 1e11 mm, where |B|
    # underflows to 0 and S is nan: the admissibility filter drops them, so their divide
    # warnings say nothing here
    with np.errstate(divide="ignore", invalid="ignore"):
        members = _one_layer_family(P, th0, t0, h0)
    assert len(members) >= 5
    chosen = pref(th0, t0, h0)
    assert chosen <= min(pref(*m) for m in members) + 1e-3 * abs(chosen)


def test_preference_terms_are_height_resolution_and_print_shift():
    """The three terms from their definitions: ln of the part height the geometry gives, ln of
    noise / (B0 min S), and the RMS of the +-0.05 mm print shifts."""
    doc = layers_only(load_document(SPEC))
    P = DesignProblem(doc)
    th, t, h = np.array([25.0, 33.0, 37.0]), np.array([0.6, 1.0, 1.4]), np.array([2.0, 2.8, 3.5])
    ev = P.evaluate_physical(th, t, h)
    terms = P.objective_terms(ev)
    geom = doc.geometry([doc.family.cell(a, b, c) for a, b, c in zip(th, t, h)])
    assert terms[0] == pytest.approx(math.log(geom.total_height_mm), rel=1e-12)
    B0 = float(P.field_T(np.array(geom.gap0_mm)))
    assert terms[1] == pytest.approx(math.log(doc.noise_uT_rms * 1e-6 / (B0 * ev.S_per_N.min())), rel=1e-9)
    shifts = P.print_shift_log(th, t, h)
    assert terms[2] == pytest.approx(math.sqrt(np.mean(shifts**2)), rel=1e-12)
    w = np.array([0.5, 2.0, 3.0])
    assert float(P.preference(ev, w)) == pytest.approx(float(terms @ w), rel=1e-12)


def test_reported_print_error_is_the_forward_model_at_t_plus_minus_0p05(tmp_path):
    doc = layers_only(load_document(SPEC))
    result = design_document(doc)
    S, R, designed, geometry, _ = forward(result, tmp_path)
    cells = [designed.family.cell(c.theta_deg, c.t_mm + PRINT_ERROR_T_MM, c.h_mm) for c in geometry.layers]
    resp = simulate(designed.geometry(cells), designed.material, whole_part=designed.whole_part)
    for i, row in enumerate(result.print_error["layers"]):
        assert row["dS_rel_t_plus"] == pytest.approx(resp.regimes[i].sensitivity_secant_per_N / S[i] - 1, rel=1e-9)
        assert row["dR_rel_t_plus"] == pytest.approx(resp.regimes[i].force_to_N / R[i] - 1, rel=1e-9)
    # what the shift does, by geometry: each cavity loses exactly 2 x 0.05 mm of stroke, and
    # every wall gets stiffer (R can move either way)
    for thick, c in zip(cells, geometry.layers):
        assert thick.d_lock_mm == pytest.approx(c.d_lock_mm - 2 * PRINT_ERROR_T_MM, abs=1e-12)
    nominal = {r.layer: r for r in simulate(geometry, designed.material).regimes}
    for r in resp.regimes:
        assert r.k_layer_N_per_mm > nominal[r.layer].k_layer_N_per_mm


# --------------------------------------------------------------------------- impossible specs
def test_ranges_that_do_not_increase_are_contradictory():
    with pytest.raises(InputError) as exc:
        design_document(spec_doc([(0.26, 5.0), (0.08, 4.8)]))
    assert exc.value.field == "layers[1].target_range_N"


def test_ranges_closer_than_the_lock_margin_are_contradictory():
    with pytest.raises(InputError) as exc:
        design_document(spec_doc([(0.26, 4.5), (0.08, 4.6)]))
    assert exc.value.field == "layers[1].target_range_N" and "lock_margin_rel" in exc.value.allowed


def test_bounds_without_a_printable_wall_are_contradictory():
    with pytest.raises(InputError) as exc:
        design_document(spec_doc([(0.2, 1.0)], t_mm_bounds=[0.1, 0.3]))
    assert exc.value.field == "design.t_mm_bounds"


def test_a_design_file_is_not_a_spec():
    with pytest.raises(InputError) as exc:
        design_document(load_document(ROOT / "configs" / "mohammadi2021-forward.yaml"))
    assert "target_sensitivity_per_N" in exc.value.field


def test_force_too_small_for_any_printable_wall_is_named():
    # the softest printable cell of the box, found on a grid 3x finer than the diagnosis uses:
    # half its lock force is out of reach of every printable wall
    P = DesignProblem(spec_doc([(0.26, 0.9)]))
    axes = [np.linspace(P.lo[j], P.hi[j], 121) for j in range(3)]
    th, t, h = (a.ravel()[:, None] for a in np.meshgrid(*axes, indexing="ij"))
    ev = P.evaluate_physical(th, t, h)
    valid = np.all(ev.cell_margins_mm[..., 0, :] >= 0, axis=-1)
    floor = float(ev.R_N[valid, 0].min())
    result = design_document(spec_doc([(0.26, 0.5 * floor)]), max_evaluations=3000)
    assert result.status == "not met" and result.exit_code == 1
    assert result.binding == "R_1 too small" and "force too small" in result.reasons[0]


def test_field_change_beyond_the_magnet_is_named():
    doc = spec_doc([(1.0, 20.0)])  # needs B_full / B0 = 21
    lim = limits(DesignProblem(doc))
    assert lim.field_change_needed == pytest.approx(20.0)
    assert lim.field_change_max < 20.0
    result = design_document(doc, max_evaluations=3000)
    assert result.exit_code == 1 and result.binding == "total field change"
    # the nearest design is still written, printable
    assert result.geometry.violations(result.document.printer) == []


def test_field_change_bound_holds_for_random_valid_designs():
    """limits() is an upper bound: no valid design exceeds it (B_full/B0 - 1 <= bound)."""
    for n in (1, 3, 6):
        P = DesignProblem(spec_doc([(1e-3, i + 1.0) for i in range(n)]))
        theta, t, h = P.sample_feasible(np.random.default_rng(n), 200)
        ev = P.evaluate_physical(theta, t, h)
        B0 = P.field_T(ev.gap0_mm)
        assert np.all(ev.B_full_T / B0 - 1 <= limits(P).field_change_max)


def test_sensitivity_rising_with_force_is_named():
    result = design_document(spec_doc([(0.05, 1.0), (0.2, 5.0)]), max_evaluations=3000)
    assert result.exit_code == 1
    assert result.binding == "S_2 rises with force" and "rises with force" in result.reasons[0]


def test_off_axis_chip_designs_with_the_exact_cylinder_field(tmp_path):
    """A chip 1.5 mm off the magnet axis: the loop uses magpylib's field, like simulate does."""
    raw = yaml.safe_load(SPEC.read_text())
    raw["magnetometer"]["chip_offset_mm"] = [1.5, 0.0]
    raw["layers"] = raw["layers"][:2]
    result = design_document(parse_document(raw))
    assert result.status == "met" and result.response.field_model == "cylinder"
    S, R, _, _, resp = forward(result, tmp_path)
    assert resp.field_model == "cylinder"
    assert np.all(np.abs(S / [0.26, 0.08] - 1) <= 0.02) and np.all(np.abs(R / [1.5, 6.0] - 1) <= 0.02)


def test_designed_walls_stay_where_the_l0_corrections_were_fitted(tmp_path):
    # every wall at most as stubby as the stubbiest fitted one (the fit now spans the printable
    # box, so this constraint no longer binds inside the default bounds; it guards user bounds)
    from mst_cli.model.mechanics.correction import fitted_t_over_L_max

    result = design_document(layers_only(load_document(SPEC)))
    _, _, _, geometry, _ = forward(result, tmp_path)
    for c in geometry.layers:
        assert c.t_mm / c.wall_length_mm <= fitted_t_over_L_max() * (1 + 1e-6)


def test_nlopt_generic_failure_ends_a_run_not_the_command(monkeypatch):
    """nlopt >= 2.11 raises its own nlopt.runtime_error (not a RuntimeError) when SLSQP's line
    search fails; a 6-layer spec of the design benchmark hit it. The run must end like any
    other nlopt stop, with the best point kept."""
    import nlopt

    from mst_cli.design.solver import solve

    failure = getattr(nlopt, "runtime_error", RuntimeError)

    def broken(self, x0):
        raise failure("nlopt failure")

    monkeypatch.setattr(nlopt.opt, "optimize", broken)
    P = DesignProblem(layers_only(load_document(SPEC)))
    result = solve(P, max_evaluations=2000)
    assert "nlopt failure" in result.stops and result.u is not None
