"""Progress of long commands on a terminal: a tqdm bar when tqdm is installed, a plain
one-line counter otherwise, and nothing at all when stdout is not a terminal or the user
asked for ``--quiet``.

The bar is written to stderr (stdout stays clean for the results) and appears only once
the work has lasted ``delay`` seconds, so short runs print nothing extra.
"""

from __future__ import annotations

import sys
import time
from typing import IO, Any

__all__ = ["PROGRESS_DELAY", "Progress", "progress_wanted"]

#: Seconds of work before a bar appears (shorter runs print nothing extra).
PROGRESS_DELAY = 2.0


def progress_wanted(quiet: bool, stdout: IO[str] | None = None) -> bool:
    """Whether to show progress: not ``quiet`` and stdout is a terminal."""
    out = sys.stdout if stdout is None else stdout
    isatty = getattr(out, "isatty", None)
    return not quiet and callable(isatty) and bool(isatty())


class Progress:
    """A progress counter over ``total`` units of work.

    Parameters
    ----------
    total : int
        Units of work (runs, scenarios).
    desc : str
        Label in front of the bar.
    enabled : bool
        ``False``: every method is a no-op (see :func:`progress_wanted`).
    stream : file, optional
        Where the bar goes (default: ``sys.stderr``).
    delay : float, optional
        Seconds before the bar first appears (default :data:`PROGRESS_DELAY`).

    Examples
    --------
    >>> with Progress(3, "runs", enabled=False) as bar:
    ...     for _ in range(3):
    ...         bar.update(note="one run")
    """

    def __init__(self, total: int, desc: str = "", *, enabled: bool = True,
                 stream: IO[str] | None = None, delay: float | None = None) -> None:
        self.total, self.desc, self.enabled = int(total), desc, bool(enabled)
        self.stream = sys.stderr if stream is None else stream
        self.delay = float(PROGRESS_DELAY if delay is None else delay)
        self.count = 0
        self._start = time.perf_counter()
        self._last = -1.0
        self._shown = False
        self._bar: Any = None
        if self.enabled:
            try:
                from tqdm import tqdm
            except ImportError:  # the plain counter below
                tqdm = None
            if tqdm is not None:
                self._bar = tqdm(total=self.total, desc=desc, file=self.stream, delay=self.delay,
                                 leave=False, dynamic_ncols=True, unit="run")

    def update(self, n: int = 1, note: str = "") -> None:
        """Count ``n`` more units done; ``note`` says what was just finished."""
        if not self.enabled:
            return
        self.count += n
        if self._bar is not None:
            if note:
                self._bar.set_postfix_str(note, refresh=False)
            self._bar.update(n)
            return
        now = time.perf_counter() - self._start
        if now < self.delay or (now - self._last < 0.2 and self.count < self.total):
            return
        self._last, self._shown = now, True
        width = len(str(self.total))
        self.stream.write(f"\r{self.desc} [{self.count:{width}d}/{self.total}] "
                          f"{now:6.1f} s {note[:50]:<50}")
        self.stream.flush()

    def close(self) -> None:
        """Remove the bar (tqdm) or end the counter's line."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None
        elif self._shown:
            self.stream.write("\n")
            self.stream.flush()
            self._shown = False

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
