"""The sweep's progress line: steps done of total, aggregate run-steps per second, time left."""

from __future__ import annotations

import math
import sys
import time


class Progress:
    """One line, rewritten in place on a terminal, one line per chunk otherwise. The rate is
    measured from the end of the first chunk, which also pays for compiling."""

    def __init__(self, start: int, total: int, n_runs: int, enabled: bool):
        self.start, self.total, self.n_runs, self.enabled = start, total, n_runs, enabled
        self.t0 = time.perf_counter()
        self.base = None  # (time, step) when the first chunk finished
        self.tty = sys.stderr.isatty()
        self.last = 0.0
        self.open_line = False

    def rate(self, step: int, now: float) -> float:
        t, s = self.base if self.base and step > self.base[1] else (self.t0, self.start)
        return (step - s) * self.n_runs / (now - t) if now > t else 0.0

    def update(self, step: int) -> None:
        now = time.perf_counter()
        if self.base is None:
            self.base = (now, step)
        if not self.enabled or (self.tty and now - self.last < 0.5 and step < self.total):
            return
        self.last = now
        rate = self.rate(step, now)
        left = (self.total - step) * self.n_runs / rate if rate > 0 else float("nan")
        width = 30
        filled = int(width * step / self.total)
        line = (f"[{'#' * filled}{'.' * (width - filled)}] step {step:,}/{self.total:,}  "
                f"{rate:,.1f} run-steps/s ({self.n_runs} runs)  elapsed {hms(now - self.t0)}  left {hms(left)}")
        print(("\r" + line) if self.tty else line, end="" if self.tty else "\n", file=sys.stderr, flush=True)
        self.open_line = self.tty

    def message(self, text: str) -> None:
        self.done()
        print(text, file=sys.stderr, flush=True)

    def done(self) -> None:
        if self.open_line:
            print(file=sys.stderr)
            self.open_line = False


def hms(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "?"
    s = int(round(seconds))
    return f"{s // 3600}:{s % 3600 // 60:02d}:{s % 60:02d}"
