"""Where a run's maths happens: the torch device, intra-op threads and denormal flushing."""

from __future__ import annotations

import functools
import os
import platform

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


@functools.cache  # read once: every checkpoint and kept policy records it
def cpu_name() -> str:
    """The CPU's model name (``/proc/cpuinfo`` on Linux), else what ``platform`` knows."""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def machine_summary(device: torch.device) -> str:
    """Where a run's maths happens, as policy files and training states record it: the CPU and
    the widest vector instructions torch's kernels use on it (AVX2, AVX512...), and the GPU on
    CUDA. A seed fixes a run's bits only on one such machine: matrix products on AVX512 round
    differently from AVX2 (docs/hardcore.md, session 33)."""
    cpu = f"{cpu_name()} ({torch.backends.cpu.get_cpu_capability()} kernels)"
    if device.type == "cuda":
        return f"{torch.cuda.get_device_name(device)}; {cpu}"
    return cpu
