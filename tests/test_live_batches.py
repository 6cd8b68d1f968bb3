"""The live session's batch steps (issue 45, item 4): a bare-number line read by the fast path
gives what the general forms give, and a batch of samples checked at once gives, sample by
sample, the fields, flags and errors of the one-sample check (loadtest.field_of)."""

from __future__ import annotations

import numpy as np
import pytest

from mst_cli.calibration.loadtest import field_of, setting_of
from mst_cli.errors import InputError
from mst_cli.io.line_columns import column_map
from mst_cli.io.serial_lines import BadLine, LineSample, parse_line
from mst_cli.readout.live import StreamRecord


def _numbers(rng, k: int, raw: bool) -> list[str]:
    if raw:
        return [str(int(v)) for v in rng.integers(-40000, 40000, k)]
    digits = rng.integers(0, 5, k)
    values = rng.normal(0, 3e3, k)
    return [f"{v:.{d}f}" + ("." if d == 0 and rng.random() < 0.2 else "") for v, d in zip(values, digits)]


@pytest.mark.parametrize("raw", [False, True])
def test_the_fast_path_reads_bare_lines_as_the_general_forms_do(raw):
    rng = np.random.default_rng(5)
    for _ in range(400):
        chips = int(rng.integers(1, 4))
        per = int(rng.choice([3, 4]))
        sep = str(rng.choice([",", ";", "\t", " "]))
        line = sep.join(_numbers(rng, per * chips, raw)) + ("\t" if rng.random() < 0.3 else "")
        columns = column_map(str(rng.choice(["xyz", "xyzt", "txyz"]))) if rng.random() < 0.5 else None
        # the same line with a space before a separator misses the fast path: the general one reads it
        general = line.replace(sep, " " + sep, 1) if sep != " " else line.replace(" ", "  ", 1)
        try:
            want = parse_line(general, raw, columns, chips)
        except BadLine as exc:
            with pytest.raises(BadLine, match=str(exc).split(":")[0]):
                parse_line(line, raw, columns, chips)
            continue
        assert parse_line(line, raw, columns, chips) == want, (line, general)
    assert parse_line("-0.45,1.50,3072.19") == LineSample((-0.45, 1.5, 3072.19), ("-0.45", "1.50", "3072.19"))
    with pytest.raises(BadLine, match="not a finite number"):
        parse_line("1" * 400 + ",1,1")


@pytest.mark.parametrize("raw", [False, True])
def test_a_batch_checked_at_once_is_every_sample_checked_alone(raw):
    setting = setting_of(7, 0)  # GAIN_SEL 7, RES 0: +-50 mT reads, codes within +-32767
    rng = np.random.default_rng(2)
    limit = 32767 if raw else 1e6 * setting.z_range_T
    values = rng.uniform(-1.2, 1.2, (300, 6)) * limit
    if raw:
        values = np.round(values)
        values[::17, 1] += 0.5  # a fraction where a code belongs
    samples = [LineSample(tuple(float(x) for x in v), tuple(f"{x:g}" for x in v)) for v in values]
    values[50:52] = 0.0  # two good samples ...
    samples[50] = LineSample((0.0,) * 6, ("0",) * 6)
    samples[51] = LineSample((0.0,) * 6, ("0",) * 6, 25.0, "25.0")  # ... the second with a T the first had not
    record = StreamRecord("port", raw, 2, setting)
    errors = dict(record.add_many(samples, 1.5))
    kept, with_T = 0, None
    for i, s in enumerate(samples):
        where = f"port sample {kept + 1}"
        try:
            if with_T is not None and (s.T_C is not None) != with_T:
                raise InputError(where, s.T_cell, "the first sample's lines had no T")
            fields = [field_of(s.values[3 * k : 3 * k + 3], raw, setting, where, record._names(k)) for k in range(2)]
        except InputError as exc:
            assert str(errors.pop(i)) == str(exc)
            continue
        with_T = s.T_C is not None
        np.testing.assert_array_equal(record.B_T[kept], [f[0] for f in fields])
        assert record.readings().saturated[kept] == any(f[1] for f in fields)
        kept += 1
    assert not errors and len(record) == kept and 0 < kept < len(samples)
    assert record.times_s == [1.5] * kept
