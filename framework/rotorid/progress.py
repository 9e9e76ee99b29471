"""Progress of a run of similar steps (tasks, reduction steps, verified pairs): a text bar, the
count and the time left, for the progress lines the ``rotorid`` logger carries."""

from __future__ import annotations

import time
from collections.abc import Callable

#: Characters of the bar between its brackets.
BAR_WIDTH = 20


def duration_text(seconds: float) -> str:
    """A rounded duration: ``"12 s"`` below 100 s, else ``"3 min"``."""
    return f"{seconds:.0f} s" if seconds < 99.5 else f"{seconds / 60:.0f} min"


def counted(n: int, noun: str) -> str:
    """``"1 pair"``, ``"3 pairs"``: a count with its noun (regular plural)."""
    return f"{n} {noun}{'s' * (n != 1)}"


def ordinal(number: int) -> str:
    """``3`` → ``"3rd"``."""
    suffix = "th" if 10 <= number % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(
        number % 10, "th")
    return f"{number}{suffix}"


class Countdown:
    """Counts finished steps out of ``total`` and estimates the time left from the mean time
    of the steps finished since it was made.

    Args:
        total: how many steps there are, or at most (``at_most``).
        done: steps already finished before (e.g. reused on resume): counted, not timed.
        at_most: ``total`` is an upper bound (a reduction may stop early); the line says so.
        clock: seconds of a monotonic clock (default :func:`time.monotonic`).
    """

    def __init__(self, total: int, done: int = 0, at_most: bool = False,
                 clock: Callable[[], float] = time.monotonic):
        self.total, self.done, self.at_most, self.clock = total, done, at_most, clock
        self._first = done
        self._started = clock()

    def step(self) -> str:
        """Count one finished step; the line ``[#####      ] 3/12, about 40 s left`` (with
        ``at_most``: ``… 3 of at most 12, at most about 40 s left``)."""
        self.done += 1
        timed = self.done - self._first
        left = max(0, self.total - self.done)
        remaining = (self.clock() - self._started) / timed * left
        filled = round(BAR_WIDTH * min(self.done, self.total) / max(self.total, 1))
        count, bound = ((f"{self.done} of at most {self.total}", "at most ") if self.at_most
                        else (f"{self.done}/{self.total}", ""))
        return (f"[{'#' * filled}{' ' * (BAR_WIDTH - filled)}] {count}, {bound}about "
                f"{duration_text(remaining)} left")
