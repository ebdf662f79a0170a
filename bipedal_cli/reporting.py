"""What a training loop tells the outside world. The CLI implements it with rich
(:mod:`bipedal_cli.display`); library callers and tests pass :class:`NullReporter`."""

from __future__ import annotations

from typing import Any, Protocol


class Reporter(Protocol):
    def start(self, start_step: int, total_steps: int) -> None: ...
    def update(self, snapshot: dict[str, Any]) -> None: ...
    def log(self, text: str) -> None: ...
    def close(self) -> None: ...


class NullReporter:
    """Says nothing."""

    def start(self, start_step: int, total_steps: int) -> None:
        pass

    def update(self, snapshot: dict[str, Any]) -> None:
        pass

    def log(self, text: str) -> None:
        pass

    def close(self) -> None:
        pass
