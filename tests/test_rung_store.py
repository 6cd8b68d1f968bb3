"""The whole-part rung's solves kept between runs (mst_cli/sensor/rung_store.py): a kept solve is
read back as it was written, without solving; anything else under its name (a hand-edited file,
a number that is not one, rows of another part) is a miss that solves again, never a result."""

import json
import math

import pytest

import mst_cli as mst
from mst_cli.model.mechanics import rung_keep
from mst_cli.model.mechanics import whole_part as wp
from mst_cli.sensor import rung_store
from tests.conftest import CONFIGS

FORWARD = CONFIGS / "mohammadi2021-forward.yaml"
LOCKED_SETS = [(), (0,), (0, 1)]


@pytest.fixture
def store(tmp_path, monkeypatch):
    """A store of its own and an empty memo; every solve is counted, and gives a motion set by
    the layers it locks (no finite elements)."""
    solves = []

    def press(geometry, material, options):
        solves.append(options)
        drop = 0.1 / (1 + len(options.locked)) * (1.0 if options.member_factor == 1.0 else 0.5)
        return wp.MagnetMotion(drop, 0.0, 0.0, 1000, 0.01)

    monkeypatch.setattr(wp, "press", press)
    monkeypatch.setenv("MST_WORKERS", "1")  # solved here, where they are counted
    monkeypatch.setattr(wp, "_OUTSIDE_MEMO", {})
    monkeypatch.setattr(wp, "_GENERAL_MEMO", {})
    kept = rung_store.FileRungStore(tmp_path)
    monkeypatch.setattr(rung_keep, "_STORE", [kept])
    monkeypatch.setattr(rung_keep, "_LISTENER", [])  # a command's listener ends with the test
    doc = mst.load(FORWARD)
    return doc.geometry(), doc.material, solves, tmp_path


def test_a_kept_solve_is_read_back_without_solving(store, monkeypatch):
    g, m, solves, folder = store
    first = wp.outside_layers(g, m, LOCKED_SETS)
    assert len(solves) == 6 and len(list((folder / "rung").glob("outside-*.json"))) == 1
    monkeypatch.setattr(wp, "_OUTSIDE_MEMO", {})  # a new process
    assert wp.outside_layers(g, m, LOCKED_SETS) == first and len(solves) == 6
    # the members add what the two solves differ by: 0.1 / (1 + locked) less half of it
    assert [r["outside_mm_per_N"] for r in first] == pytest.approx([0.05, 0.025, 0.05 / 3])


def test_a_listener_hears_of_the_solves_to_come_and_not_of_kept_ones(store, monkeypatch):
    """The command's progress line: said before the solves start, with their count; a kept
    result is read in silence."""
    g, m, solves, _ = store
    heard: list[str] = []
    rung_keep.set_listener(heard.append)
    wp.outside_layers(g, m, LOCKED_SETS)
    assert len(heard) == 1 and heard[0].startswith("whole-part rung: 6 solves of the part's section")
    monkeypatch.setattr(wp, "_OUTSIDE_MEMO", {})  # a new process: the store has them
    wp.outside_layers(g, m, LOCKED_SETS)
    assert len(heard) == 1 and len(solves) == 6


@pytest.mark.parametrize(
    "edit",
    [
        lambda rows: "not json {",
        lambda rows: json.dumps([{**r, "part_mm_per_N": "NaN"} for r in rows]),
        lambda rows: json.dumps(rows[:2]),  # another part's regimes
        lambda rows: json.dumps([{**r, "locked": [2]} for r in rows]),
        lambda rows: json.dumps({"rows": rows}),
    ],
)
def test_a_kept_file_that_is_not_what_was_written_is_solved_again(store, monkeypatch, edit):
    g, m, solves, folder = store
    first = wp.outside_layers(g, m, LOCKED_SETS)
    (path,) = (folder / "rung").glob("outside-*.json")
    path.write_text(edit(json.loads(path.read_text())))
    monkeypatch.setattr(wp, "_OUTSIDE_MEMO", {})
    assert wp.outside_layers(g, m, LOCKED_SETS) == first and len(solves) == 12
    assert json.loads(path.read_text()) == first  # and kept again as solved


def test_a_general_motion_round_trips_through_plain_numbers():
    press = wp.MagnetMotion(0.11, -0.02, 3e-4, 150100, 12.5)
    motion = wp.GeneralMotion(press, wp.MagnetMotion(0.01, 0.3, -2e-3, 150100, 0.2), press, 2.93)
    again = wp.GeneralMotion.from_dict(json.loads(json.dumps(motion.as_dict())))
    assert again == motion and isinstance(again.press.dofs, int)
    assert again.turn_per_moment_rad_per_Nmm == motion.turn_per_moment_rad_per_Nmm
    broken = motion.as_dict()
    broken["pull"]["side_mm_per_N"] = math.inf
    with pytest.raises(ValueError):
        wp.GeneralMotion.from_dict(broken)


def test_the_name_is_the_key_and_the_models_source():
    key = ("geometry", "material", wp.PartOptions())
    name = rung_store.file_name("outside", key)
    assert name.startswith("rung/outside-") and name == rung_store.file_name("outside", key)
    assert name != rung_store.file_name("outside", (*key[:2], wp.PartOptions(locked=(0,))))
    assert name != rung_store.file_name("general", key)


def test_the_models_source_counts_its_fitted_data(tmp_path, monkeypatch):
    """A refit of a model's data file is another model, as an edit of its source is: a copy of
    mst_cli/model with one data file changed hashes otherwise."""
    import shutil
    from pathlib import Path

    model = Path(rung_keep.__file__).resolve().parents[1]
    copy = tmp_path / "model"
    shutil.copytree(model, copy, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(rung_keep, "__file__", str(copy / "mechanics" / "rung_keep.py"))

    def hashed() -> str:
        rung_store.model_source_hash.cache_clear()
        return rung_store.model_source_hash()

    as_shipped = hashed()
    with (copy / "data" / "tilt_lever.json").open("a") as f:
        f.write(" ")  # a refit's data file
    refitted = hashed()
    with (copy / "ladder.py").open("a") as f:
        f.write("# edited\n")  # a source edit
    edited = hashed()
    rung_store.model_source_hash.cache_clear()
    assert len({as_shipped, refitted, edited}) == 3


def test_mst_simulate_says_so_on_stderr_before_it_solves(store, tmp_path):
    from click.testing import CliRunner

    from mst_cli.cli.app import main

    spec = tmp_path / "section.yaml"
    spec.write_text(FORWARD.read_text() + "model:\n  load_path: section\n")
    args = ["simulate", str(spec), "--no-plot", "--out"]
    said = CliRunner().invoke(main, [*args, str(tmp_path / "a")]).stderr
    assert said.startswith("mst simulate: whole-part rung: 6 solves of the part's section"), said
    assert CliRunner().invoke(main, [*args, str(tmp_path / "b")]).stderr == ""  # kept: nothing to say


def test_a_kept_press_is_read_back_and_a_spoiled_one_solved_again(store):
    """``mst check --whole-part``'s attribution solves (each member class as printed in turn)."""
    g, m, solves, folder = store
    options = wp.PartOptions(member_factor=wp.RIGID_FACTOR, scaled=("base", "cap"))
    first = wp.kept_press(g, m, options)
    assert wp.kept_press(g, m, options) == first and len(solves) == 1
    (path,) = (folder / "rung").glob("press-*.json")
    path.write_text(json.dumps({**json.loads(path.read_text()), "drop_mm_per_N": "NaN"}))
    assert wp.kept_press(g, m, options) == first and len(solves) == 2
