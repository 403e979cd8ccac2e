# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Progress of a long job on stderr.

A bar with an ETA on a terminal, a line every few seconds otherwise (CI logs), nothing when
quiet.

Jobs advance it as their pieces finish (:func:`ipomdp_gaze.simulation.executor.track`), so what it
shows
is work done wherever it ran.
"""
from __future__ import annotations

import sys
import threading
import time

# Seconds between two lines when stderr is not a terminal.
LINE_EVERY_S = 5.0


def _clock(seconds: float) -> str:
    seconds = int(round(seconds))
    return f'{seconds // 60}:{seconds % 60:02d}' if seconds < 3600 else \
        f'{seconds // 3600}:{seconds // 60 % 60:02d}:{seconds % 60:02d}'


class Progress:
    """
    Count ``total`` units of work labelled ``desc``; ``update(n)`` after each piece.

    On a terminal a tqdm bar (rate and ETA); on anything else a line ``desc: done/total
    (pct) elapsed, ETA`` every ``every_s`` seconds (from a timer thread, so a long piece does
    not leave the log silent) and once at the end; with ``quiet`` nothing. ``add(n)`` grows
    the total (a job that learns its size as it submits), ``note(text)`` shows a status.
    ``stream`` defaults to stderr. Safe to update from several threads. Use it as a context
    manager, or call :meth:`close`.
    """

    def __init__(self, total: float, desc: str, unit: str = 'piece', quiet: bool = False,
                 stream=None, every_s: float = LINE_EVERY_S, terminal: bool | None = None):
        self.total, self.desc, self.unit = total, desc, unit
        self.stream = sys.stderr if stream is None else stream
        self.quiet, self.every_s = bool(quiet), float(every_s)
        if terminal is None:
            isatty = getattr(self.stream, 'isatty', None)
            terminal = bool(isatty and isatty())
        self.done, self._lock = 0, threading.Lock()
        self._start = self._last = time.monotonic()
        self._bar, self._closed, self._note = None, False, ''
        if not self.quiet and terminal:
            from tqdm import tqdm
            self._bar = tqdm(total=total, desc=desc, unit=unit, file=self.stream,
                             dynamic_ncols=True)
        self._stop = threading.Event()
        if not self.quiet and not terminal and self.every_s > 0:
            # A line every few seconds, pieces done or not (0: a line at every update only).
            threading.Thread(target=self._tick, daemon=True, name='progress').start()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def _tick(self) -> None:
        while not self._stop.wait(self.every_s):
            with self._lock:
                now = time.monotonic()
                if not self._closed and now - self._last >= self.every_s * 0.999:
                    self._last = now
                    self._line(now)

    def note(self, text: str) -> None:
        """Show ``text`` after the count (the bar's postfix, or the end of the next line)."""
        self._note = str(text)
        if self._bar is not None:
            self._bar.set_postfix_str(self._note, refresh=False)

    def add(self, n: float) -> None:
        """Count ``n`` more units to do (a job that learns its size as it submits)."""
        with self._lock:
            self.total += n
            if self._bar is not None:
                self._bar.total = self.total
                self._bar.refresh()

    def update(self, n: float = 1) -> None:
        """Count ``n`` more units done."""
        if self.quiet or self._closed:
            return
        with self._lock:
            self.done += n
            if self._bar is not None:
                self._bar.update(n)
                return
            now = time.monotonic()
            if now - self._last >= self.every_s:
                self._last = now
                self._line(now)

    def _line(self, now: float) -> None:
        elapsed = now - self._start
        text = f'{self.desc}: {self.done:g}/{self.total:g} {self.unit}s'
        if self.total:
            text += f' ({100 * self.done / self.total:.0f}%)'
        text += f', {_clock(elapsed)} elapsed'
        if 0 < self.done < self.total:
            text += f', ETA {_clock(elapsed * (self.total - self.done) / self.done)}'
        if self._note:
            text += f' ({self._note})'
        print(text, file=self.stream, flush=True)

    def close(self) -> None:
        """Finish the bar, or print the closing line."""
        if self.quiet or self._closed:
            return
        with self._lock:
            self._closed = True
            if self._bar is not None:
                self._bar.close()
            else:
                self._stop.set()
                self._line(time.monotonic())
