"""Where a run's maths happens: the torch device, intra-op threads and denormal flushing."""

from __future__ import annotations

import os

import torch

from .config import TrainConfig
from .errors import UserError


def resolve_device(name: str) -> torch.device:
    """``auto`` is CUDA when present, else the CPU; ``cuda`` without CUDA is a one-line error."""
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if name.startswith("cuda") and not torch.cuda.is_available():
        raise UserError(f"--device {name}: CUDA is not available on this machine; use cpu or auto")
    try:
        return torch.device(name)
    except RuntimeError:
        raise UserError(f"--device {name}: expected auto, cpu or cuda") from None


def configure_threads(train: TrainConfig, device: torch.device) -> bool:
    """Set torch's threads for a run (process-wide); True when the update is split in two parts
    that run in parallel (``train.split_update`` on a CPU with 2+ threads), each with half."""
    threads = train.threads or os.cpu_count() or 1
    split = train.split_update and device.type == "cpu" and threads >= 2
    torch.set_num_threads(threads // 2 if split else threads)
    # see TrainConfig.flush_denormal (measured: benchmarks/throughput.py)
    torch.set_flush_denormal(train.flush_denormal)
    return split
