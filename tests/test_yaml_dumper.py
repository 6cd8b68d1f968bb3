"""The YAML files mst writes come from libyaml's emitter where PyYAML has it
(mst_cli.io.outputs.YAML_DUMPER): the same text, to the byte, as PyYAML's own emitter."""

from pathlib import Path

import numpy as np
import pytest
import yaml

from mst_cli.io.outputs import YAML_DUMPER

ROOT = Path(__file__).resolve().parents[1]
# without libyaml the writer falls back to PyYAML's own emitter, and there is nothing to compare
pytestmark = pytest.mark.skipif(YAML_DUMPER is yaml.SafeDumper, reason="PyYAML built without libyaml")


def _both(data) -> tuple[str, str]:
    ours = yaml.dump(data, Dumper=YAML_DUMPER, sort_keys=False, default_flow_style=None)
    return ours, yaml.safe_dump(data, sort_keys=False, default_flow_style=None)


def test_the_bundled_files_dump_to_the_same_text_with_either_emitter():
    files = sorted((ROOT / "configs").glob("*.yaml")) + sorted((ROOT / "docs").rglob("*.yaml"))
    assert len(files) >= 4
    for path in files:
        ours, pyyaml = _both(yaml.safe_load(path.read_text()))
        assert ours == pyyaml, path


def test_numbers_nesting_and_repeated_objects_dump_alike():
    rng = np.random.default_rng(0)
    shared = {"theta_deg": 41.2345, "t_mm": 0.6}  # written twice: an anchor and an alias
    data = {
        "name": "a long name with spaces, commas: and colons " * 3,
        "numbers": [float(x) for x in rng.standard_normal(40) * 10.0 ** rng.integers(-12, 12, 40)],
        "edge": [0.0, -0.0, 1e-300, 1.7976931348623157e308, float("inf"), 3, -7, True, None, ""],
        "layers": [shared, shared, {"target_range_N": 0.9, "nested": {"deep": [[1.5, 2.5], {"x": "y"}]}}],
    }
    ours, pyyaml = _both(data)
    assert "&id001" in ours and ours == pyyaml
