"""The progress bar of every long command (``slide``, ``bench``, ``sweep``).

One helper so the commands agree: a tqdm bar with ETA on stderr, shown on a
terminal only. With ``--json`` or when stderr is not a TTY (CI logs, pipes,
subprocesses) it stays quiet: a bar there is carriage-return noise mixed into
output that machines read. ``--progress on`` forces it (tests count its
ticks), ``--progress off`` silences it on a terminal.
"""

from __future__ import annotations

import sys

from tqdm import tqdm

MODES = ("auto", "on", "off")


def add_argument(parser) -> None:
    """The ``--progress {auto,on,off}`` option of a long command."""
    parser.add_argument(
        "--progress",
        choices=MODES,
        default="auto",
        help="progress bar on stderr: auto (default) shows it on a terminal unless --json; on; off",
    )


def wanted(mode: str = "auto", json_output: bool = False, stream=None) -> bool:
    """Whether to draw a bar: ``mode`` is one of MODES; ``auto`` means stream
    (default stderr) is a TTY and the command's output is not JSON."""
    if mode not in MODES:
        raise ValueError(f"progress mode {mode!r} is not one of {', '.join(MODES)}")
    if mode != "auto":
        return mode == "on"
    stream = sys.stderr if stream is None else stream
    isatty = getattr(stream, "isatty", None)
    return not json_output and bool(isatty and isatty())


class Progress:
    """A tqdm bar (count, rate, ETA) that does nothing when not enabled.

    ``step(label)`` counts one finished item and shows its label; ``update(n)``
    counts n (simulation steps, say). ``initial`` items count as done before
    the start (a resumed sweep), so the ETA is over the remaining ones."""

    def __init__(
        self,
        total: int,
        enabled: bool = True,
        stream=None,
        desc: str | None = None,
        unit: str = "it",
        initial: int = 0,
    ):
        self.total, self.done, self.enabled = total, initial, enabled
        self._bar = tqdm(
            total=total,
            initial=initial,
            desc=desc,
            unit=unit,
            disable=not enabled,
            file=sys.stderr if stream is None else stream,
            dynamic_ncols=True,
            smoothing=0.1,
        )

    def step(self, label: str | None = None) -> None:
        self.update(1, label)

    def update(self, n: int, label: str | None = None) -> None:
        self.done += n
        if label is not None:
            self._bar.set_postfix_str(label[:60], refresh=False)
        self._bar.update(n)

    def close(self) -> None:
        self._bar.close()

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
