"""Progress of a long command on stderr: a rich bar fitted to the terminal on a terminal, log lines
otherwise (a line at each stage and every ~10 % of its count). `run` counts runs; `report`,
`surrogate export` and `calibrate` go through stages (analysing a file, drawing, sampling ...), each
with its own count (outputs, sections, steps)."""
from __future__ import annotations

import sys
import time

from ..text.console import clean


class Progress:
    """`done` of `total` `unit` (resumed runs included), the rate of this session and the ETA, under
    an optional `label` (the command) and the current stage's text."""

    def __init__(self, total: int, done: int = 0, quiet: bool = False, stream=sys.stderr, unit: str = "runs",
                 label: str = ""):
        self.quiet, self.stream, self.label = quiet, stream, label
        self._bar = None
        if stream.isatty() and not quiet and (total or label):
            from rich.console import Console
            from rich.progress import BarColumn, MofNCompleteColumn, TextColumn, TimeElapsedColumn, TimeRemainingColumn
            from rich.progress import Progress as Bar

            self._bar = Bar(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                            TextColumn("{task.fields[rate]}"), TimeElapsedColumn(), TextColumn("ETA"),
                            TimeRemainingColumn(), console=Console(file=stream), transient=False)
            self._bar.start()
            self._task = None
        self._count(total, done, unit, "")

    def _count(self, total: int, done: int, unit: str, text: str) -> None:
        self.total, self.done, self.unit, self.text = total, done, unit, text
        self.start, self.first = time.perf_counter(), done
        self._next_log = done / total + 0.1 if total else 1.0
        if self._bar is not None:  # a task per stage: its own count (none: "?") and elapsed time
            if self._task is not None:
                self._bar.remove_task(self._task)
            self._task = self._bar.add_task(self._description(), total=total or None, completed=done, rate="")

    def _description(self) -> str:
        if self.label:
            return clean(f"{self.label}: {self.text or 'starting'}")
        return clean(self.text or self.unit)

    def stage(self, text: str, total: int = 0, unit: str = "steps") -> None:
        """A new stage, counting `total` `unit` from 0 (0: a stage without a count); a log line off a terminal."""
        self._count(total, 0, unit, text)
        if self._bar is None and not self.quiet:
            count = f" (0/{total} {unit})" if total else ""
            self._write(f"{self.label + ': ' if self.label else ''}{text}{count}")

    def advance(self, n: int = 1, text: str | None = None) -> None:
        """`n` more done (at most the total); `text`, when given, what the stage is doing now."""
        self.done = min(self.done + n, self.total)
        if text is not None:
            self.text = text
            if self._bar is not None:
                self._bar.update(self._task, description=self._description())
        if self.quiet or self.total == 0:
            return
        elapsed = time.perf_counter() - self.start
        rate = (self.done - self.first) / elapsed if elapsed > 0 else 0.0
        if self._bar is not None:
            self._bar.update(self._task, completed=self.done, rate=f"{rate:.1f} {self.unit}/s")
            return
        fraction = self.done / self.total
        if fraction >= self._next_log or self.done == self.total:
            eta = (self.total - self.done) / rate if rate > 0 else float("inf")
            prefix = "".join(f"{part}: " for part in (self.label, self.text) if part)
            self._write(f"{prefix}{self.done}/{self.total} {self.unit} ({100 * fraction:.0f} %), "
                        f"{rate:.1f} {self.unit}/s, ETA {eta:.0f} s")
            self._next_log = fraction + 0.1

    def note(self, text: str) -> None:
        """A line for the reader (above the bar on a terminal); nothing when quiet."""
        if self.quiet:
            return
        if self._bar is not None:
            self._bar.console.print(clean(text), markup=False, highlight=False)
        else:
            self._write(text)

    def _write(self, text: str) -> None:
        self.stream.write(clean(text) + "\n")
        self.stream.flush()

    def close(self) -> None:
        if self._bar is not None:
            self._bar.stop()
            self._bar = None

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> bool:
        self.close()
        return False
