"""Progress of long work for people: a bar in a terminal (``tqdm``), a plain line every
``interval`` seconds when the output is not a terminal (CI logs, files), nothing when quiet.
Written to stderr, so stdout keeps only the results.
"""

from __future__ import annotations

import sys
import time


class Progress:
    """``with Progress("scan_pitch", unit="step") as p: p(done, total)``."""

    def __init__(
        self,
        label: str,
        *,
        unit: str = "step",
        quiet: bool = False,
        stream=None,
        interval: float = 10.0,
    ):
        self.label, self.unit, self.quiet = label, unit, quiet
        self.stream = stream or sys.stderr
        self.interval = interval
        self.bar = None
        self.start = self.last = time.perf_counter()
        self.done = self.total = 0

    def __enter__(self):
        return self

    def __call__(self, done: int, total: int) -> None:
        self.done, self.total = done, total
        if self.quiet:
            return
        if self.stream.isatty():
            if self.bar is None:
                from tqdm import tqdm

                self.bar = tqdm(
                    total=total,
                    desc=self.label,
                    unit=self.unit,
                    file=self.stream,
                    leave=False,
                    dynamic_ncols=True,
                )
            self.bar.update(done - self.bar.n)
        elif time.perf_counter() - self.last >= self.interval:
            self.last = time.perf_counter()
            self.stream.write(
                f"{self.label}: {done}/{total} {self.unit}s "
                f"({100 * done / max(total, 1):.0f} %), "
                f"{self.last - self.start:.0f} s\n"
            )
            self.stream.flush()

    def __exit__(self, *exc):
        if self.bar is not None:
            self.bar.close()
        return False
