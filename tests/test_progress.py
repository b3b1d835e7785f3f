"""The progress line (``fenics_garment.progress``): its text, the estimate of the time left, live
redraws on a terminal, plain lines otherwise, and silence when disabled (``--quiet``)."""

import io

import pytest

from fenics_garment import progress
from fenics_garment.progress import (
    ProgressLine,
    State,
    expected_solves,
    format_duration,
    format_line,
    time_left,
)


class Clock:
    def __init__(self):
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_format_duration():
    assert format_duration(0.4) == "0 s"
    assert format_duration(42.4) == "42 s"
    assert format_duration(187) == "3:07"
    assert format_duration(3725) == "1:02:05"
    assert format_duration(-3) == "0 s"


def test_time_left_is_the_pace_so_far():
    assert time_left(30.0, 3, 9) == pytest.approx(60.0)
    assert time_left(30.0, 9, 9) == 0.0
    assert time_left(30.0, 12, 9) == 0.0  # more solves than foreseen (cuts): nothing left
    assert time_left(30.0, 0, 9) is None  # nothing done: no estimate
    assert time_left(30.0, 3, None) is None  # total unknown (adaptive schedule)


def test_expected_solves_of_the_fixed_schedule():
    # c0·0.25^k down to c0·1e-5: k = 0..9 (0.25^9 = 3.8e-6 < 1e-5), then c = 0
    assert expected_solves(4, 0, 1e3, 0.25, 1e-5) == 4 + 10
    assert expected_solves(4, 3, 1e3, 0.25, 1e-5) == 4 + 3 + 10
    assert expected_solves(4, 0, 0.0, 0.25, 1e-5) == 4  # no spring: no release


def test_format_line():
    s = State(stage="dressing", started=10.0, step=3, total=12, what="shrink", spring=6240.0,
              newton=2, residual=0.035)  # fmt: skip
    line = format_line(s, 40.0)
    assert line == ("dressing: step 3/12 (shrink) · spring c 6.2e+03 Pa/m · Newton 2, "
                    "‖F‖ 3.5e-02 · 30 s, ~1:30 left")  # fmt: skip
    assert format_line(State(stage="meshing", started=0.0), 5.2) == "meshing · 5 s"


def test_live_line_redraws_in_place_and_keeps_ordinary_lines():
    clock, out = Clock(), Terminal()
    line = ProgressLine(out, clock=clock)
    assert line.live
    line.stage("dressing", total=4)
    clock.t += 10
    line.newton(1, 0.5)
    line.step("shrink", spring=100.0)
    line.say("  shrink 1.00 mm   Newton its  1")
    line.close()
    text = out.getvalue()
    assert "\r\x1b[2Kdressing: step 0/4 · Newton 1, ‖F‖ 5.0e-01 · 10 s" in text
    assert "dressing: step 1/4 (shrink) · spring c 1e+02 Pa/m · 10 s, ~30 s left" in text
    # the ordinary line printed on a cleared row, then the live line drawn again below it
    assert "\r\x1b[2K  shrink 1.00 mm   Newton its  1\n\r\x1b[2Kdressing: step 1/4" in text
    assert text.endswith("\r\x1b[2K")  # closed: the live line removed
    assert "\n" not in text.replace("  shrink 1.00 mm   Newton its  1\n", "")


def test_plain_lines_when_not_a_terminal():
    clock, out = Clock(), io.StringIO()
    line = ProgressLine(out, clock=clock)
    assert not line.live
    line.stage("dressing", total=3)
    line.newton(1, 0.5)  # no line per Newton iteration
    clock.t += 1
    line.step("shrink")  # within PLAIN_EVERY of the last: no line
    clock.t += progress.PLAIN_EVERY
    line.step("shrink")
    line.close()
    lines = out.getvalue().splitlines()
    elapsed = 1 + progress.PLAIN_EVERY
    assert lines == [f"  [dressing: step 2/3 (shrink) · {format_duration(elapsed)}, "
                     f"~{format_duration(elapsed / 2)} left]"]  # fmt: skip
    assert "\r" not in out.getvalue()


def test_quiet_prints_nothing():
    out = Terminal()
    line = ProgressLine(out, enabled=False)
    line.stage("meshing")
    line.newton(1, 1.0)
    line.step()
    line.say("hello")
    line.close()
    assert out.getvalue() == "" and not line.live


def test_current_is_the_active_line_else_a_silent_one():
    assert not progress.current().enabled
    out = io.StringIO()
    with progress.active(ProgressLine(out)) as line:
        assert progress.current() is line
    assert not progress.current().enabled


def test_a_silent_stage_gets_a_plain_line(monkeypatch):
    """A long meshing or JIT (no steps, nothing printed) still shows that the run is alive."""
    import time

    monkeypatch.setattr(progress, "TICK", 0.01)
    clock, out = Clock(), io.StringIO()
    line = ProgressLine(out, clock=clock)
    line.stage("meshing")
    time.sleep(0.05)
    assert out.getvalue() == ""  # not yet: quiet for less than PLAIN_EVERY
    clock.t += progress.PLAIN_EVERY
    for _ in range(200):
        if out.getvalue():
            break
        time.sleep(0.01)
    line.close()
    assert (
        out.getvalue().splitlines()[0] == f"  [meshing · {format_duration(progress.PLAIN_EVERY)}]"
    )


def test_steps_past_the_plan_are_not_shown_as_a_fraction_above_one():
    """Cut steps add to the planned count: "step 22, 19 planned", with no time-left estimate
    (the pace of the plan no longer says how long the rest takes), not "step 22/19"."""
    line = progress.format_line(progress.State(stage="dressing", step=22, total=19), now=60.0)
    assert "step 22, 19 planned" in line and "/19" not in line and "left" not in line
