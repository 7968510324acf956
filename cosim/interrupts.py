"""Stopping a run on SIGINT (Ctrl-C) or SIGTERM without losing what it computed.

The signals set a flag instead of raising: the co-simulation loops check it every macro-step
(:func:`stop_requested`), stop where they are, and the run writes what it has (time series so
far, a summary, ``run.json`` with ``"status": "interrupted"``); the command then exits 130
(SIGINT) or 143 (SIGTERM). The main process forwards the signal to its worker processes, which
install the same handler (:func:`install_in_worker`). A second signal stops at once.

Helper pools (a sweep's workers, the figures drawn in parallel, an identification's model
evaluations) leave Ctrl-C to the parent instead (:func:`ignore_in_worker`): the parent stops
them, and no worker prints a ``KeyboardInterrupt`` traceback of its own into the command's
clean "interrupted" message.
"""
from __future__ import annotations

import multiprocessing
import os
import signal
import sys
from contextlib import contextmanager
from typing import Optional

_received: Optional[int] = None


def stop_requested() -> bool:
    return _received is not None


def received_signal() -> Optional[int]:
    """The signal that asked the run to stop (None: not interrupted)."""
    return _received


def exit_code() -> int:
    """128 + signal number: 130 for SIGINT, 143 for SIGTERM."""
    return 128 + int(_received or 0)


def _handler(signum, frame) -> None:
    global _received
    if _received is not None:                     # a second signal: stop at once
        print(f"\nstopped ({signal.Signals(signum).name} again)", file=sys.stderr, flush=True)
        os._exit(128 + signum)
    _received = signum
    for child in multiprocessing.active_children():
        try:
            os.kill(child.pid, signum)
        except ProcessLookupError:
            pass


def ignore_in_worker() -> None:
    """Initializer of helper pool processes: SIGINT is left to the parent (module doc)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def install_in_worker() -> None:
    """Initializer of worker processes: SIGINT and SIGTERM ask its cases to stop (module doc)."""
    global _received
    _received = None
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, _handler)


@contextmanager
def handled():
    """In the main process of a run: SIGINT and SIGTERM ask the run to stop (module doc); the
    previous handlers are restored afterwards. :func:`stop_requested` keeps its answer after the
    block, for the caller to report."""
    previous = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    install_in_worker()
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
