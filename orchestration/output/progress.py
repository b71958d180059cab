"""Progress of long work for people: a bar in a terminal (``tqdm``), a plain line every
``interval`` seconds when the output is not a terminal (CI logs, files), nothing when quiet.
Written to stderr, so stdout keeps only the results.

A run's progress counts simulated seconds (:meth:`Progress.simulating`: the runner gives
the step), anything else its units (FMUs built, say).  Messages while the bar is shown
(an FMU's warnings) go through :meth:`Progress.write`: above the bar, never into it.
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
        self.step: float | None = None  # simulated seconds per unit counted, if a run's

    def __enter__(self):
        return self

    def simulating(self, step: float) -> None:
        """The units counted are macro steps of ``step`` seconds: show simulated seconds."""
        self.step = step

    def __call__(self, done: int, total: int) -> None:
        self.done, self.total = done, total
        if self.quiet:
            return
        scale, unit = (1, self.unit) if self.step is None else (self.step, "s")
        if self.stream.isatty():
            if self.bar is None:
                from tqdm import tqdm

                self.bar = tqdm(
                    total=total * scale,
                    desc=self.label,
                    unit=unit,
                    file=self.stream,
                    leave=False,
                    dynamic_ncols=True,
                    **(
                        {}
                        if self.step is None
                        else {
                            "bar_format": "{desc}: {percentage:3.0f}%|{bar}| {n:.4g}/{total:.4g} "
                            "s simulated [{elapsed}<{remaining}]"
                        }
                    ),
                )
            self.bar.update(done * scale - self.bar.n)
        elif time.perf_counter() - self.last >= self.interval:
            self.last = time.perf_counter()
            counted = (
                f"{done}/{total} {unit}s"
                if self.step is None
                else f"{done * scale:.4g}/{total * scale:.4g} s simulated"
            )
            self.stream.write(
                f"{self.label}: {counted} ({100 * done / max(total, 1):.0f} %), "
                f"{self.last - self.start:.0f} s\n"
            )
            self.stream.flush()

    def write(self, text: str) -> None:
        """A line for people on the progress's stream, above the bar if one is shown."""
        if self.bar is not None:
            self.bar.write(text, file=self.stream)
        else:
            print(text, file=self.stream, flush=True)

    def __exit__(self, *exc):
        if self.bar is not None:
            self.bar.close()
        return False
