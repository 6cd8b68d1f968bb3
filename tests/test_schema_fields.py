"""Every input field is declared once (issue 12): the validation rules, the defaults,
document_to_dict and the tables of docs/file-format.md (tests/test_docs.py) are all read from
the dataclass fields made with ``spec`` (mst_cli.sensor.document, mst_cli.model.cell). These tests
sweep every declared field: its rule is the one parsing enforces, its default is what a file
without it gets, it survives a write and a read, and each of its bounds refuses the value just
outside it, naming the field."""

import math
from dataclasses import fields

import pytest

from mst_cli.errors import InputError
from mst_cli.model.cell import HexCell
from mst_cli.model.components import grade_remanence_T
from mst_cli.sensor.document import Rule, default_of, document_to_dict, parse_document, section_to_dict
from mst_cli.sensor.sections import LAYER_RULES, SECTION_TYPES, SECTIONS, CellFamily, LayerEntry

LAYER = {"theta_deg": 25.0, "t_mm": 0.6, "h_mm": 2.0}
NUMERIC = ("float", "int", "pair", "bounds", "weights")


def declared():
    """(section, field) of every key a file may set; section "layers" for a layer's keys."""
    for name, cls in SECTION_TYPES.items():
        for f in fields(cls):
            yield name, f
    for f in fields(LayerEntry):
        yield "layers", f


FIELDS = list(declared())
IDS = [f"{s}.{f.name}" for s, f in FIELDS]


def path_of(section: str, key: str) -> str:
    return f"layers[0].{key}" if section == "layers" else f"{section}.{key}"


def raw_with(section: str, key: str, value) -> dict:
    """A one-layer design that sets only ``section.key`` (or the layer's ``key``)."""
    raw = {"layers": [dict(LAYER)]}
    if section == "layers":
        raw["layers"][0][key] = value
    else:
        raw[section] = {key: value}
    return raw


def value_in(doc, section: str, key: str):
    return getattr(doc.layers[0] if section == "layers" else doc.section(section), key)


def written(doc) -> dict:
    """All a file can hold of ``doc``: document_to_dict plus the spec's design section."""
    out = document_to_dict(doc)
    out["design"] = section_to_dict(SECTION_TYPES["design"], doc.section("design"))
    return out


def outside(rule: Rule, bound: str) -> float:
    """The value just outside ``rule``'s lower or upper bound."""
    value, is_open = (rule.lo, rule.lo_open) if bound == "lo" else (rule.hi, rule.hi_open)
    if is_open:
        return value
    if rule.kind == "int":
        return value - 1 if bound == "lo" else value + 1
    return math.nextafter(value, -math.inf if bound == "lo" else math.inf)


def inside(rule: Rule) -> float:
    return 0.5 * (rule.lo + rule.hi)


# --------------------------------------------------------------------------- the declarations
@pytest.mark.parametrize("section,f", FIELDS, ids=IDS)
def test_every_field_is_declared_whole_and_its_rule_is_the_one_parsing_uses(section, f):
    rule = Rule.of(f)
    assert f.metadata["meaning"].strip(), "a declared field says what it means"
    assert rule == (LAYER_RULES if section == "layers" else SECTIONS[section])[f.name]
    if rule.kind in NUMERIC:
        assert rule.lo is not None and rule.hi is not None, "every number is bounded both ways"
        assert math.isfinite(rule.lo) and math.isfinite(rule.hi) and rule.lo < rule.hi
    default = default_of(f)
    if default is not None:  # None: "not given" (a layer's group) or a nullable null
        rule.check(path_of(section, f.name), list(default) if isinstance(default, tuple) else default)


def test_the_family_constants_are_the_cells_own():
    assert CellFamily().cell(30.0, 1.0, 3.0) == HexCell(30.0, 1.0, 3.0)


# --------------------------------------------------------------------------- defaults and round trip
def test_a_file_without_a_key_gets_its_declared_default():
    doc = parse_document({"layers": [LAYER]})
    for section, f in FIELDS:
        if section == "layers":
            continue
        expect = default_of(f)
        if (section, f.name) == ("magnet", "remanence_T"):  # null: the grade's value
            expect = grade_remanence_T(doc.magnet.grade)
        assert value_in(doc, section, f.name) == expect, f"{section}.{f.name}"


def test_the_default_document_round_trips():
    doc = parse_document({"layers": [LAYER]})
    raw = written(doc)
    again = parse_document(raw)
    assert again == doc
    assert written(again) == raw


def candidates(rule: Rule, default) -> list:
    """In-range values other than the default, some of which the housing rules accept."""
    if rule.kind == "weights":
        return [{rule.choices[0]: 2.0}]
    if rule.choices:
        return [c for c in rule.choices if c != default]
    if rule.kind == "str":
        return ["another name"]
    mid, lo, hi = inside(rule), rule.lo, rule.hi
    near = mid + 0.05 * (hi - mid)  # a chip on the 30 mm face (one off it is refused at load)
    if rule.kind == "pair":
        return [[mid, lo], [hi, mid], [near, mid]]
    if rule.kind == "pairs":  # chips: the first at the default chip_offset_mm
        return [[[0.0, 0.0], [hi, mid]], [[0.0, 0.0], [near, mid]]]
    if rule.kind == "bounds":
        return [[lo + 0.25 * (hi - lo), mid]]
    if rule.kind == "int":
        return [int(mid), rule.lo + 1]
    values = [mid, default * 1.1 if default else mid / 3, rule.lo if not rule.lo_open else mid / 7]
    return [v for v in values if v != default]


@pytest.mark.parametrize("section,f", FIELDS, ids=IDS)
def test_every_field_round_trips_a_value_other_than_its_default(section, f):
    rule = Rule.of(f)
    values = candidates(rule, default_of(f))
    if not values:
        pytest.skip("one allowed value: the default, which the default document round-trips")
    accepted = 0
    for value in values:
        rule.check(path_of(section, f.name), value)  # the key's own rule accepts it ...
        try:
            doc = parse_document(raw_with(section, f.name, value))
        except InputError:  # ... a rule across keys (housing, board, layer grid) may not
            continue
        accepted += 1
        got = value_in(doc, section, f.name)
        if rule.kind == "weights":
            assert got == {**default_of(f), **value}
        else:
            want = tuple(tuple(v) if isinstance(v, list) else v for v in value) if isinstance(value, list) else value
            assert got == want
        raw = written(doc)
        again = parse_document(raw)
        assert again == doc and value_in(again, section, f.name) == got
    assert accepted, f"no value other than the default was accepted for {path_of(section, f.name)}"


# --------------------------------------------------------------------------- every bound enforced
def bound_cases():
    for section, f in FIELDS:
        rule = Rule.of(f)
        if rule.kind not in NUMERIC:
            continue
        for bound in ("lo", "hi"):
            bad = outside(rule, bound)
            path = path_of(section, f.name)
            if rule.kind == "pair":
                yield section, f.name, [bad, inside(rule)], path + "[0]"
                yield section, f.name, [inside(rule), bad], path + "[1]"
            elif rule.kind == "bounds":
                pair = [bad, inside(rule)] if bound == "lo" else [inside(rule), bad]
                yield section, f.name, pair, path
            elif rule.kind == "weights":
                yield section, f.name, {rule.choices[0]: bad}, f"{path}.{rule.choices[0]}"
            else:
                yield section, f.name, bad, path


BOUND_CASES = list(bound_cases())


@pytest.mark.parametrize("section,key,value,field", BOUND_CASES, ids=[c[3] + f"={c[2]!r}" for c in BOUND_CASES])
def test_a_value_just_outside_each_bound_is_refused_naming_the_field(section, key, value, field):
    with pytest.raises(InputError) as exc:
        parse_document(raw_with(section, key, value))
    assert exc.value.field == field, str(exc.value)
    rule = (LAYER_RULES if section == "layers" else SECTIONS[section])[key]
    assert f"{rule.lo:g}" in exc.value.allowed and f"{rule.hi:g}" in exc.value.allowed, str(exc.value)


@pytest.mark.parametrize("section,f", FIELDS, ids=IDS)
def test_closed_bounds_themselves_are_allowed_and_null_only_where_declared(section, f):
    rule, path = Rule.of(f), path_of(section, f.name)
    for bound, is_open in ((rule.lo, rule.lo_open), (rule.hi, rule.hi_open)):
        if rule.kind in ("float", "int") and not is_open:
            assert rule.check(path, bound) == bound
    if rule.nullable:
        assert rule.check(path, None) is None
    else:
        with pytest.raises(InputError) as exc:
            parse_document(raw_with(section, f.name, None))
        assert exc.value.field == path
