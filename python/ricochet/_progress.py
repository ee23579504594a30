"""The progress line of an in-process run (``Scene.run(progress=True)``): simulated time, its
share of the end time and the steps, on stderr, rewritten at most five times a second."""

from __future__ import annotations

import sys
import time


class ProgressLine:
    """A callable ``(t, end, steps)`` that redraws one line on stderr."""

    def __init__(self, name: str, every: float = 0.2) -> None:
        self.name = name
        self.every = every
        self.last = 0.0
        self.shown = False

    def __call__(self, t: float, end: float, steps: int) -> None:
        now = time.monotonic()
        if now - self.last < self.every and t < end:
            return
        self.last = now
        share = 100.0 * t / end if end > 0 else 100.0
        sys.stderr.write(f"\r{self.name}: t = {t:.4e} s of {end:.4e} s ({share:5.1f} %), {steps} steps")
        sys.stderr.flush()
        self.shown = True

    def close(self) -> None:
        """Ends the line (a newline when one was drawn)."""
        if self.shown:
            sys.stderr.write("\n")
            sys.stderr.flush()
            self.shown = False
