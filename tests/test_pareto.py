"""mst design --pareto: the trade among designs that meet the targets."""

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from mst_cli.cli.app import main
from mst_cli.design.pareto import non_dominated
from mst_cli.design.solver import pareto_weights
from mst_cli.model.response import simulate
from mst_cli.sensor.document import load_document

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "configs" / "fingertip.yaml"


def test_non_dominated_by_hand():
    pts = np.array(
        [
            [1, 5, 3],  # kept: best in column 0
            [2, 2, 2],  # kept
            [3, 3, 3],  # dominated by row 1
            [2, 2, 2.5],  # dominated by row 1 (equal in two, worse in one)
            [5, 1, 9],
        ]
    )  # kept: best in column 1
    assert non_dominated(pts).tolist() == [True, True, False, False, True]
    assert non_dominated(np.array([[1.0, 1.0], [1.0, 1.0]])).tolist() == [True, True]  # ties stay


@pytest.mark.parametrize("count", [3, 7, 12, 30])
def test_pareto_weights_lie_on_the_simplex(count):
    w = pareto_weights(count)
    assert w.shape == (count, 3)
    assert np.all(w >= 0) and np.allclose(w.sum(axis=1), 1.0)
    assert np.allclose(w[:3], np.eye(3))  # each term alone first
    assert len({tuple(np.round(r, 9)) for r in w}) == count  # no weighting twice
    assert np.allclose(pareto_weights(2 * count)[:count], w)  # a longer run extends a shorter one


@pytest.fixture(scope="module")
def front_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("pareto")
    r = CliRunner().invoke(main, ["design", str(SPEC), "--out", str(out), "--pareto", "6", "--pareto-designs"])
    assert r.exit_code == 0, r.output
    with open(out / "pareto.csv") as f:
        rows = list(csv.DictReader(f))
    return out, rows, r.output


def test_front_files_and_header_units(front_run):
    out, rows, output = front_run
    assert (out / "pareto.png").stat().st_size > 10_000
    assert 2 <= len(rows) <= 6
    header = rows[0].keys()
    for col in (
        "total_height_mm",
        "worst_force_resolution_mN",
        "print_robustness_rms_pct",
        "layer1_theta_deg",
        "layer3_h_mm",
    ):
        assert col in header
    assert sum(int(r["chosen"]) for r in rows) == 1
    assert "Pareto front" in output and "<-- chosen" in output


def test_front_is_mutually_non_dominated_and_spans_a_trade(front_run):
    """Every design but the chosen one is dominated by none (the chosen one, the design ``mst
    design`` writes, is listed and marked whatever: mst_cli.design.pareto.pareto_front)."""
    _, rows, _ = front_run
    M = np.array(
        [
            [float(r["total_height_mm"]), float(r["worst_force_resolution_mN"]), float(r["print_robustness_rms_pct"])]
            for r in rows
        ]
    )
    chosen = np.array([int(r["chosen"]) == 1 for r in rows])
    assert non_dominated(M)[~chosen].all()
    assert non_dominated(M[~chosen]).all()
    # a front of more than one design trades: the shortest part is not the most robust one
    assert np.argmin(M[:, 0]) != np.argmin(M[:, 2])


def test_every_front_design_meets_the_targets_when_simulated_again(front_run):
    """Each pareto/design-NN.yaml loaded back and run through the forward model meets every
    target within the tolerance, and its height and force resolution are the CSV's."""
    out, rows, _ = front_run
    for k, row in enumerate(rows):
        doc = load_document(out / "pareto" / f"design-{k + 1:02d}.yaml")
        geometry = doc.geometry()
        resp = simulate(geometry, doc.material)
        tol = doc.design["tolerance_rel"]
        for i, la in enumerate(doc.layers):
            reg = next(r for r in resp.regimes if r.layer == i + 1)
            assert reg.force_to_N == pytest.approx(la.target_range_N, rel=tol)
            S = resp.regimes[i].sensitivity_secant_per_N
            assert S == pytest.approx(la.target_sensitivity_per_N, rel=tol)
        assert geometry.total_height_mm == pytest.approx(float(row["total_height_mm"]), abs=1e-3)
        worst = max(r.force_resolution_N for r in resp.regimes)
        assert 1e3 * worst == pytest.approx(float(row["worst_force_resolution_mN"]), abs=1e-3)
        for i, la in enumerate(doc.layers):
            assert la.theta_deg == pytest.approx(float(row[f"layer{i + 1}_theta_deg"]), abs=1e-9)


def test_chosen_row_is_design_yaml(front_run):
    out, rows, _ = front_run
    chosen = next(r for r in rows if r["chosen"] == "1")
    doc = load_document(out / "design.yaml")
    assert doc.geometry().total_height_mm == pytest.approx(float(chosen["total_height_mm"]), abs=1e-3)
    for i, la in enumerate(doc.layers):
        assert la.t_mm == pytest.approx(float(chosen[f"layer{i + 1}_t_mm"]), abs=1e-9)


def test_objective_weights_move_the_design(tmp_path):
    """Pricing only height gives a part no taller than pricing only print robustness, and the
    robust one moves less with a 0.05 mm wall error: the weights do what they say."""
    import yaml

    raw = yaml.safe_load(SPEC.read_text())
    got = {}
    for name, w in (
        ("short", {"height": 1, "force_resolution": 0, "print_robustness": 0}),
        ("robust", {"height": 0, "force_resolution": 0, "print_robustness": 1}),
    ):
        raw.setdefault("design", {})["objective"] = w
        raw["name"] = name
        path = tmp_path / f"{name}.yaml"
        path.write_text(yaml.safe_dump(raw))
        r = CliRunner().invoke(main, ["design", str(path), "--out", str(tmp_path / name), "--json"])
        assert r.exit_code == 0, r.output
        rep = json.loads(r.output)
        got[name] = (rep["geometry"]["total_height_mm"], rep["design"]["print_error_sensitivity"]["rms_log_change"])
    assert got["short"][0] < got["robust"][0]
    assert got["robust"][1] < got["short"][1]


@pytest.mark.parametrize(
    "args, field",
    [
        (["--pareto-designs"], "--pareto-designs"),
        (["--pareto", "4", "--refine", "continuum"], "--pareto"),
    ],
)
def test_pareto_option_errors_are_one_line(tmp_path, args, field):
    r = CliRunner().invoke(main, ["design", str(SPEC), "--out", str(tmp_path / "o")] + args)
    assert r.exit_code == 2
    assert field in r.output and len(r.output.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


def test_bad_objective_key_is_refused(tmp_path):
    import yaml

    raw = yaml.safe_load(SPEC.read_text())
    raw.setdefault("design", {})["objective"] = {"hieght": 1}
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(raw))
    r = CliRunner().invoke(main, ["design", str(path), "--out", str(tmp_path / "o")])
    assert r.exit_code == 2 and "design.objective.hieght" in r.output


# --------------------------------------------------------------------------- shared work
@pytest.mark.parametrize("workers", ["1", "2"])
def test_batched_polishes_are_the_one_at_a_time_polishes(monkeypatch, workers):
    """prefer_many runs every weighting's own local run, only its kernel calls batched (in one
    process, or dealt to two forked workers): each ends where prefer alone ends, to the bit,
    with the same stop reasons in the weightings' order."""
    from mst_cli.design.batching import prefer_many
    from mst_cli.design.phase import Budget
    from mst_cli.design.problem import DesignProblem
    from mst_cli.design.solver import Search, _matched, prefer

    monkeypatch.setenv("MST_WORKERS", workers)
    problem = DesignProblem(load_document(ROOT / "configs" / "mohammadi2021.yaml"))
    sol = _matched(problem, 0, Search(Budget(20000, None, 120.0)))
    weights = list(pareto_weights(6))
    stops: list = []
    batched = prefer_many(problem, [sol.u] * len(weights), weights, max_evaluations=20000, stops=stops)
    stops_alone: list = []
    for w, (u, used) in zip(weights, batched):
        budget = Budget(20000, None, 120.0)
        alone, _, _ = prefer(problem, sol.u, Search(budget, "slsqp", stops_alone), w)
        assert np.array_equal(u, alone) and used == budget.used
        assert used > 0
    assert stops == stops_alone


def test_batched_polish_hands_back_an_error():
    from mst_cli.design.batching import _SharedEvaluations
    from mst_cli.design.problem import DesignProblem

    problem = DesignProblem(load_document(ROOT / "configs" / "mohammadi2021.yaml"))

    def fine(p):
        return float(p.evaluate(np.full(problem.dim, 0.5)).objective)

    def broken(p):
        p.evaluate(np.full((2, problem.dim), 0.5))
        raise ValueError("inside a run")

    with pytest.raises(ValueError, match="inside a run"):
        _SharedEvaluations(problem).run([fine, broken, fine])
    one, two = _SharedEvaluations(problem).run([fine, fine])
    assert one == two == float(problem.evaluate(np.full(problem.dim, 0.5)).objective)


def test_an_interrupt_inside_a_batched_polish_stops_it_at_once():
    """A KeyboardInterrupt (or mst's Interrupted) in one run ends them all at once; only an
    Exception waits for the other runs."""
    from mst_cli.design.batching import _SharedEvaluations
    from mst_cli.design.problem import DesignProblem

    problem = DesignProblem(load_document(ROOT / "configs" / "mohammadi2021.yaml"))
    finished = []

    def fine(p):
        for _ in range(3):
            p.evaluate(np.full(problem.dim, 0.5) + 0.01 * len(finished))
        finished.append(1)

    def interrupted(p):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        _SharedEvaluations(problem).run([fine, interrupted, fine])
    assert finished == []


def test_front_matches_once_and_reuses_the_chosen_designs_match(monkeypatch):
    """The screening and the match run once for the whole front (the chosen design's)."""
    from mst_cli.design import pareto, solver

    calls = []
    real = solver._matched
    monkeypatch.setattr(solver, "_matched", lambda *a, **k: calls.append(1) or real(*a, **k))
    chosen, front = pareto.pareto_front(load_document(SPEC), 4)
    assert len(calls) == 1 and chosen.status == "met" and len(front) >= 2


def test_print_robustness_reuses_the_nominal_stack_exactly():
    from mst_cli.design.problem import DesignProblem

    problem = DesignProblem(load_document(ROOT / "configs" / "mohammadi2021.yaml"))
    ev = problem.evaluate(np.random.default_rng(3).random((200, problem.dim)))
    full = problem.print_robustness(ev.theta_deg, ev.t_mm, ev.h_mm)
    reused = problem.print_robustness(ev.theta_deg, ev.t_mm, ev.h_mm, nominal=(ev.S_per_N, ev.R_N))
    assert np.array_equal(full, reused, equal_nan=True)


@pytest.mark.parametrize("limit", [None, 0.5])
def test_one_kernel_call_for_nominal_and_shifted_stacks_gives_the_same_bits(tmp_path, limit):
    """evaluate_with_shifts (the batched polish's call) equals evaluate and print_shift_log
    called apart, every field to the bit, with and without the print-deviation constraints."""
    import yaml

    from mst_cli.design.problem import DesignProblem

    raw = yaml.safe_load((ROOT / "configs" / "mohammadi2021.yaml").read_text())
    if limit is not None:
        raw["design"] = {**(raw.get("design") or {}), "max_print_deviation_rel": limit}
    path = tmp_path / "spec.yaml"
    path.write_text(yaml.safe_dump(raw))
    problem = DesignProblem(load_document(path))
    U = np.random.default_rng(5).random((300, problem.dim))
    ev, shifts = problem.evaluate_with_shifts(U)
    apart = problem.evaluate(U)
    for name in vars(apart):
        assert np.array_equal(getattr(ev, name), getattr(apart, name), equal_nan=True), name
    alone = problem.print_shift_log(apart.theta_deg, apart.t_mm, apart.h_mm)
    assert np.array_equal(shifts, alone, equal_nan=True)


def test_no_runs_no_wait():
    from mst_cli.design.batching import _SharedEvaluations
    from mst_cli.design.problem import DesignProblem

    assert _SharedEvaluations(DesignProblem(load_document(SPEC))).run([]) == []
