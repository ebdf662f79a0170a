"""An update's metrics when its two parts run on two threads (:meth:`TQCAgent.update
<bipedal_cli.agent.TQCAgent.update>`)."""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from concurrent.futures import Future

import torch


class MetricsWhenDone(Mapping):
    """An update's metrics, of which the critics' arrive when the worker finishes its part."""

    def __init__(self, critic_job: Future, actor_metrics: dict[str, torch.Tensor]) -> None:
        self._job, self._actor_metrics = critic_job, actor_metrics
        self._all: dict[str, torch.Tensor] | None = None

    def _resolved(self) -> dict[str, torch.Tensor]:
        if self._all is None:
            self._all = {**self._job.result(), **self._actor_metrics}
        return self._all

    def __getitem__(self, key: str) -> torch.Tensor:
        return self._resolved()[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._resolved())

    def __len__(self) -> int:
        return len(self._resolved())
