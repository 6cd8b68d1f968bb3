"""``mst design``'s progress line (mst_cli/cli/progress.py): quiet for a short run, at most a line
every 5 s off a terminal, and a new phase said at once, so the whole-part rung's long section
rounds (model.load_path: section) are never hidden behind the seed's last line."""

import pytest

from mst_cli.cli import progress as pg


@pytest.fixture
def clock(monkeypatch):
    now = [100.0]
    monkeypatch.setattr(pg.time, "monotonic", lambda: now[0])
    return now


def test_a_new_phase_is_said_at_once_and_the_rounds_are_counted_as_designs(clock, capsys):
    bar = pg.DesignProgress(quiet=False)
    bar.tty = False
    clock[0] += 0.5
    bar(10, 20000, "seed", float("nan"))  # within the first second: a short run says nothing
    clock[0] += 5.0
    bar(2000, 20000, "seed", float("nan"))  # off a terminal, a line every 5 s
    clock[0] += 1.0
    bar(2500, 20000, "seed", float("nan"))  # the same phase within 5 s: not said
    clock[0] += 0.5
    bar(0, 4, "the whole-part rung on design 1", float("nan"))  # a new phase: said at once
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 2
    assert "2000/20000 evaluations, seed, no candidate yet" in lines[0]
    assert lines[1].endswith("the whole-part rung on design 1 of at most 4")


def test_quiet_says_nothing(clock, capsys):
    bar = pg.DesignProgress(quiet=True)
    clock[0] += 10.0
    bar(0, 4, "the whole-part rung on design 1", float("nan"))
    assert capsys.readouterr().err == ""
