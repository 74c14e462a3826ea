"""Progress wherever output goes: the time-left estimate on recorded stage timings, lines in a file, a line
rewritten in place where someone watches."""

from __future__ import annotations

import io
import json
import statistics
import time
from pathlib import Path

import pytest

from curiosity_cli.progress import Eta, Progress, duration

RECORDED = sorted((Path(__file__).parent / "data" / "progress").glob("*.json"))


def estimates(recorded: Path) -> list[float]:
    """The time left :class:`Eta` gives over the time that was left, at each unit of a recorded stage once a
    tenth of its units are done and while a tenth of its time is still ahead."""
    stage = json.loads(recorded.read_text())
    total, wall = sum(units for _, units in stage["units"]), stage["wall"]
    eta, done, ratios = Eta(total, 0.0), 0, []
    for finished, units in stage["units"]:
        done += units
        if done >= total / 10 and wall - finished >= wall / 10:
            ratios.append(eta.remaining(done, finished) / (wall - finished))
    return ratios


def test_the_time_left_on_recorded_label_stages_is_within_twice_the_truth_at_most_checks():
    # label stages of the declared study on 2 cores: blocks of 5 to 20 runs finish in pairs, costliest first
    assert len(RECORDED) == 4
    ratios = [ratio for recorded in RECORDED for ratio in estimates(recorded)]
    within = sum(0.5 <= ratio <= 2 for ratio in ratios)
    assert len(ratios) == 22 and within >= 14, sorted(ratios)
    assert 0.5 <= statistics.median(ratios) <= 2
    assert max(max(ratios), 1 / min(ratios)) < 4  # the worst: the first pair of a stage's costliest blocks


def test_no_estimate_before_the_first_unit_and_none_left_at_the_end():
    eta = Eta(10, started=100.0)
    assert eta.remaining(0, 150.0) is None
    assert eta.remaining(5, 150.0) == 50.0 and eta.remaining(10, 190.0) == 0.0


@pytest.mark.parametrize("seconds, words", [(42.4, "42 s"), (185, "3 min 5 s"), (3725, "1 h 2 min")])
def test_durations_read_as_a_person_says_them(seconds, words):
    assert duration(seconds) == words


class Clock:
    def __init__(self):
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


def test_a_stage_written_to_a_file_gets_a_line_when_it_starts_every_few_seconds_and_when_it_ends():
    out, clock = io.StringIO(), Clock()
    with Progress(out, every=0.05, clock=clock) as progress:
        assert not progress.watched  # a StringIO is no terminal
        progress.stage("words and exploration set-up", 0)
        progress.stage("labelling runs", 10)
        time.sleep(0.2)  # ticks before any run is done: alive, no estimate
        clock.now += 50
        for _ in range(5):
            progress.advance()
        before = out.getvalue().count("\n")
        time.sleep(0.2)
        assert out.getvalue().count("\n") > before
    lines = out.getvalue().splitlines()
    assert lines[:2] == ["words and exploration set-up", "labelling runs: 0/10"]
    assert "  labelling runs: 0/10 (0 %), 0 s so far, no estimate before the first is done" in lines
    assert "  labelling runs: 5/10 (50 %), 0.10/s, about 50 s left" in lines
    assert lines[-1] == "labelling runs: 5/10 in 50 s"


def watched_stage() -> str:
    """What a watched stage of 4 units, one a second, draws."""
    out, clock = io.StringIO(), Clock()
    with Progress(out, watched=True, clock=clock) as progress:
        progress.stage("exploring", 4)
        for _ in range(4):
            clock.now += 1
            progress.advance()
    return out.getvalue()


def test_a_watched_stage_is_one_line_rewritten_in_place():
    text = watched_stage()
    assert text.count("\n") == 1 and text.endswith(" in 4 s\n")
    assert text.split("\r")[-1].startswith("exploring [########################] 4/4 (100 %), 1.00/s, about 0 s left")


def test_a_watched_line_is_cut_to_the_terminal_s_width_so_it_never_wraps(monkeypatch):
    """Issue 64: with COLUMNS=5 the line stayed about 80 columns and wrapped, a new row at every redraw."""
    monkeypatch.setenv("COLUMNS", "30")
    drawn = [part for part in watched_stage().split("\r") if part]
    assert drawn and all(len(part.split(" in ")[0].rstrip()) <= 29 for part in drawn)
    assert drawn[-1].startswith("exploring [##################")


def test_in_a_notebook_a_long_function_given_no_callbacks_shows_its_own_progress(monkeypatch):
    import sys
    import types

    from curiosity_cli.api.pipeline import _shown

    given = (lambda *_: None, None)
    with _shown(*given) as shown:
        assert shown == given  # callbacks given are used as they are, anywhere
    with _shown(None, None) as shown:
        assert shown == (None, None)  # outside a notebook nothing is shown unasked
    monkeypatch.setitem(sys.modules, "ipykernel", types.ModuleType("ipykernel"))
    with _shown(None, None) as (on_stage, on_done):
        assert isinstance(on_stage.__self__, Progress) and on_stage.__self__.watched
        assert on_done.__self__ is on_stage.__self__
