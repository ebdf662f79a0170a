"""The second thread of a TQC update on CPU: it runs the critics' part while the calling thread
runs the actor's (:meth:`TQCAgent.update <bipedal_cli.agent.TQCAgent.update>`)."""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any

import torch


class CriticWorker:
    """One worker thread and the critics' step it may still be running.

    Meant for one intra-op thread per part, ``torch.set_num_threads(1)``: batch-64 matrix
    products split badly across cores, two independent parts split well. Denormal flushing is
    a per-thread CPU flag, so the worker sets its own.
    """

    def __init__(self, flush_denormal: bool = True) -> None:
        self._pool = ThreadPoolExecutor(
            1, "tqc-critic", initializer=torch.set_flush_denormal, initargs=(flush_denormal,)
        )
        self._pending: Future | None = None  # the last update's critics' step

    def submit(self, part: Callable[..., Any], *args: Any) -> Future:
        return self._pool.submit(part, *args)

    def hold(self, job: Future) -> None:
        """``job`` moves the critics: :meth:`wait` waits for it."""
        self._pending = job

    def wait(self) -> None:
        """Wait for the held job (and raise its error, if it failed)."""
        if self._pending is not None:
            job, self._pending = self._pending, None
            job.result()

    def shutdown(self) -> None:
        try:
            self.wait()
        finally:
            self._pool.shutdown()
