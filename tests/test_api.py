"""mst_cli.api: the verbs a script calls, and what the package re-exports of them."""

from __future__ import annotations

import importlib
import inspect
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest

import mst_cli
from mst_cli import api


def test_the_package_names_stay_the_verbs_after_every_subpackage_is_imported():
    for sub in ("design", "calibration", "estimation", "firmware", "readout", "cad", "model", "io", "bench", "cli.app"):
        importlib.import_module(f"mst_cli.{sub}")
    for name in mst_cli.__all__:
        if name != "api":
            assert getattr(mst_cli, name) is getattr(api, name), name
    # the verb named like a subpackage is the api's only; calibrate is the package's too
    assert inspect.ismodule(mst_cli.design) and inspect.isfunction(api.design)
    assert mst_cli.calibrate is api.calibrate


def test_every_verb_documents_itself():
    for name in api.__all__:
        obj = getattr(api, name)
        if inspect.isfunction(obj):
            assert obj.__doc__ and len(obj.__doc__.strip()) > 40, name


def test_importing_the_package_loads_no_dear_layer():
    # `import mst_cli` loads what `mst simulate` needs (the sensor, the model, numpy); the layers
    # that would cost `mst simulate` start-up time (design, CAD, calibration: scipy) load when called
    code = (
        "import sys, mst_cli; heavy = [m for m in sys.modules if m.startswith(('mst_cli.design', "
        "'mst_cli.cad', 'mst_cli.calibration', 'mst_cli.estimation', 'mst_cli.firmware', 'mst_cli.readout', "
        "'mst_cli.bench', 'scipy', 'nlopt', 'matplotlib', 'skfem'))]; "
        "print(heavy)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


FORWARD = Path(__file__).resolve().parents[1] / "configs" / "mohammadi2021-forward.yaml"


@pytest.mark.parametrize(
    "call, option",
    [
        (lambda: api.simulate(FORWARD, mechanics="beam"), "--mechanics"),
        (lambda: api.simulate(FORWARD, field_model="exact"), "--field-model"),
        (lambda: api.design(FORWARD, refine="spring"), "--refine"),
        (lambda: api.calibrate(FORWARD, "unused.csv", params=["modulus_factor", "stiffness"]), "--params"),
        (lambda: api.calibrate(FORWARD, "unused.csv", table_size=8), "--table-size"),
        (lambda: api.check(FORWARD.parent, nozzle_mm=-1.0), "--nozzle"),
    ],
)
def test_a_script_gets_the_commands_input_errors(call, option):
    with pytest.raises(api.InputError) as exc:
        call()
    assert exc.value.field == option


def test_simulate_models_the_part_as_printed():
    # a printer that prints every wall 0.05 mm thick: the same sensor as walls drawn 0.05 mm thicker
    doc = api.load_design(FORWARD)
    offset = replace(doc, printer=replace(doc.printer, wall_offset_mm=0.05))
    drawn = replace(doc, layers=tuple(replace(la, t_mm=la.t_mm + 0.05) for la in doc.layers))
    a, b = api.simulate(offset), api.simulate(drawn)
    assert [r.force_to_N for r in a.regimes] == pytest.approx([r.force_to_N for r in b.regimes], rel=1e-9)
    assert [r.force_to_N for r in a.regimes] != pytest.approx([r.force_to_N for r in api.simulate(doc).regimes])


def test_every_verb_is_documented_numpy_style():
    # issue 37: units and shapes under Parameters, Returns, Raises and Examples
    import inspect

    missing = {}
    for name in api.__all__:
        obj = getattr(api, name)
        if isinstance(obj, type) or not callable(obj):
            continue
        doc = inspect.getdoc(obj) or ""
        absent = [s for s in ("Parameters", "Returns", "Raises", "Examples") if f"{s}\n---" not in doc]
        if absent:
            missing[name] = absent
    assert missing == {}
