"""Ctrl-C and SIGTERM during training: the first asks the loop to checkpoint and stop, the second
aborts at once.

Schedulers, ``timeout`` and a machine shutting down send SIGTERM; a terminal sends SIGINT. The
exit status says which one stopped the run: 128 + the signal's number (130 for SIGINT, 143 for
SIGTERM), the shell's convention.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


def exit_status(signum: int) -> int:
    return 128 + int(signum)


@contextmanager
def stop_on_signals(request_stop: Callable[[int], None]) -> Iterator[None]:
    """While inside, the first SIGINT or SIGTERM calls ``request_stop(signum)``; the second
    raises KeyboardInterrupt. Only the main thread can install handlers; elsewhere a no-op."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    received: list[int] = []

    def handler(signum, frame):
        if received:
            raise KeyboardInterrupt
        received.append(signum)
        request_stop(signum)

    previous = {s: signal.signal(s, handler) for s in STOP_SIGNALS}
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)
