"""A progress line for long work on rank 0: stage, step, spring, Newton iteration, elapsed time and
an estimate of the time left.

On a terminal the line is live: redrawn in place (carriage return) at every Newton iteration and
every second while a stage is busy (meshing, JIT), with the run's ordinary lines scrolling above
it. When the output is not a terminal (a log file, CI), nothing is redrawn: a plain line
``[stage: step k/n · elapsed, ~left]`` is printed after a step at most every
:data:`PLAIN_EVERY` seconds, and when nothing at all was printed for that long (a long meshing or
JIT), so a short run prints what it did before. With ``quiet`` (``--quiet``) or on ranks other
than 0, nothing is printed.

The run sets the line with :func:`active`; the stages reach it with :func:`current` (a silent
line when there is none), so no function needs it as an argument.
"""

from __future__ import annotations

import math
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import TextIO

#: Seconds between two plain progress lines (output not a terminal).
PLAIN_EVERY = 30.0
#: Seconds between two redraws of the live line while nothing reports (meshing, JIT).
TICK = 1.0


def format_duration(seconds: float) -> str:
    """``42 s``, ``3:07`` (min:s) or ``1:02:05`` (h:min:s)."""
    s = max(round(seconds), 0)
    if s < 60:
        return f"{s} s"
    h, rest = divmod(s, 3600)
    m, s = divmod(rest, 60)
    return f"{h}:{m:02d}:{s:02d}" if h else f"{m}:{s:02d}"


def time_left(elapsed: float, done: float, total: float | None) -> float | None:
    """The time left if the rest of the work goes at the pace so far: ``elapsed`` × (``total``
    − ``done``) / ``done``. None when nothing is done yet or the total is unknown; 0 when the
    done work reaches the total."""
    if total is None or done <= 0 or elapsed < 0:
        return None
    return elapsed * max(total - done, 0.0) / done


def expected_solves(steps: int, sew_steps: int, c0: float, ratio: float, c_zero: float) -> int:
    """Solves of a dressing on the fixed schedule (:mod:`fenics_garment.scene.dressing`): the
    ``steps`` grow steps, the ``sew_steps`` of a garment sewn from flat pieces (0 otherwise) and,
    with a spring (``c0`` > 0), its release through c₀·``ratio``ᵏ down to c₀·``c_zero`` then 0.
    Cuts, shortcuts of the release and multiplier passes are not foreseen (an estimate)."""
    release = 0
    if c0 > 0:
        release = math.ceil(math.log(c_zero) / math.log(ratio)) + 1
    return steps + sew_steps + release


@dataclass
class State:
    """What the line shows."""

    stage: str = ""
    started: float = 0.0  # clock at the stage's start
    step: int = 0  # steps done in the stage
    total: int | None = None  # steps expected in the stage
    what: str = ""  # the current step's kind (shrink, sew, spring release, ...)
    spring: float | None = None  # c of the stabilising spring [Pa/m]
    newton: int | None = None  # Newton iteration of the solve under way
    residual: float | None = None  # its residual norm


def format_line(state: State, now: float) -> str:
    """The progress line of ``state`` at clock ``now``, e.g. ``dressing: step 3/11 (shrink) ·
    spring c 6.2e+03 Pa/m · Newton 2, ‖F‖ 3.5e-02 · 12 s, ~25 s left``."""
    parts = [state.stage]
    over = bool(state.total) and state.step > state.total  # cut steps added to the plan
    if state.total:
        step = f"step {state.step}" + (f", {state.total} planned" if over else f"/{state.total}")
        parts[0] += f": {step}" + (f" ({state.what})" if state.what else "")
    if state.spring is not None:
        parts.append(f"spring c {state.spring:.2g} Pa/m")
    if state.newton is not None:
        its = f"Newton {state.newton}"
        parts.append(its + (f", ‖F‖ {state.residual:.1e}" if state.residual is not None else ""))
    elapsed = now - state.started
    left = None if over else time_left(elapsed, state.step, state.total)
    parts.append(format_duration(elapsed) + (f", ~{format_duration(left)} left" if left else ""))
    return " · ".join(parts)


class ProgressLine:
    """The progress line (module doc). ``stream``: where it goes (stdout); ``enabled``: False
    prints nothing; ``live``: redraw in place (default: whether ``stream`` is a terminal)."""

    def __init__(
        self,
        stream: TextIO | None = None,
        *,
        enabled: bool = True,
        live: bool | None = None,
        clock: Callable[[], float] = time.monotonic,
    ):
        self.stream = stream or sys.stdout
        self.enabled = enabled
        self.live = enabled and (self.stream.isatty() if live is None else live)
        self.clock = clock
        self.state = State(started=clock())
        self._shown = False  # a live line is on the screen
        self._last_plain = clock()  # the last plain progress line
        self._last_output = clock()  # the last line of any kind
        self._lock = threading.RLock()
        self._ticker: threading.Thread | None = None
        self._stop = threading.Event()

    # -- what the run reports ----------------------------------------------------------------

    def stage(self, name: str, total: int | None = None) -> None:
        """A new stage (``total``: its steps, when known)."""
        with self._lock:
            self.state = State(stage=name, started=self.clock(), total=total)
            self._last_plain = self.state.started
            self._show(plain=False)

    def step(self, what: str = "", spring: float | None = None) -> None:
        """A step of the stage is done (``what``: its kind; ``spring``: c after it)."""
        with self._lock:
            s = self.state
            s.step += 1
            s.what, s.spring, s.newton, s.residual = what, spring, None, None
            self._show(plain=self.clock() - self._last_plain >= PLAIN_EVERY)

    def newton(self, iteration: int, residual: float) -> None:
        """A Newton iteration of the solve under way is done (live line only)."""
        with self._lock:
            self.state.newton, self.state.residual = iteration, residual
            self._show(plain=False)

    def say(self, *args: object) -> None:
        """Print an ordinary line (as ``print``), above the live line."""
        if not self.enabled:
            return
        with self._lock:
            self._erase()
            print(*args, file=self.stream, flush=True)
            self._last_output = self.clock()
            self._show(plain=False)

    def close(self) -> None:
        """Remove the live line and stop the ticker; lines said after it are plain."""
        self._stop.set()
        if self._ticker is not None:
            self._ticker.join()
        with self._lock:
            self._erase()
            self.state = State()

    # -- drawing ---------------------------------------------------------------------------

    def _show(self, plain: bool) -> None:
        if not self.enabled or not self.state.stage:
            return
        line = format_line(self.state, self.clock())
        if self.live:
            self.stream.write("\r\x1b[2K" + line)
            self.stream.flush()
            self._shown = True
        elif plain:
            print("  [" + line + "]", file=self.stream, flush=True)
            self._last_plain = self._last_output = self.clock()
        self._start_ticker()

    def _erase(self) -> None:
        if self._shown:
            self.stream.write("\r\x1b[2K")
            self.stream.flush()
            self._shown = False

    def _start_ticker(self) -> None:
        if self._ticker is not None:
            return

        def tick() -> None:
            while not self._stop.wait(TICK):
                with self._lock:
                    if self._shown:
                        self._show(plain=False)
                    elif not self.live and self.clock() - self._last_output >= PLAIN_EVERY:
                        self._show(plain=True)

        self._ticker = threading.Thread(target=tick, name="progress-line", daemon=True)
        self._ticker.start()


_CURRENT: list[ProgressLine] = []


def current() -> ProgressLine:
    """The line of the run under way, or a silent one."""
    return _CURRENT[-1] if _CURRENT else ProgressLine(enabled=False)


@contextmanager
def active(line: ProgressLine) -> Iterator[ProgressLine]:
    """Make ``line`` the :func:`current` one while the block runs; closed at its end."""
    _CURRENT.append(line)
    try:
        yield line
    finally:
        _CURRENT.remove(line)
        line.close()
