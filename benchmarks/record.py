"""Keep what a benchmark printed as a committed JSON file, with the machine it ran on.

    if __name__ == "__main__":
        run_recorded("micro", main)

writes ``benchmarks/results/micro-<date>-<time>.json``: the script, its arguments, the date, the
CPU, the core count, Python and torch versions, and every line it printed. README's figures cite
such files (see README, "Where the figures come from").
"""

from __future__ import annotations

import io
import json
import os
import platform
import sys
import time
from collections.abc import Callable
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"


def cpu_name() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def machine() -> dict:
    import torch

    return {
        "cpu": cpu_name(),
        "cores": os.cpu_count(),
        "platform": platform.platform(),
        "python": platform.python_version(),
        "torch": torch.__version__,
        # the widest vector instructions torch's CPU kernels use here (AVX2, AVX512...): two
        # machines that report the same CPU name can differ here, and in speed with it
        "cpu_capability": torch.backends.cpu.get_cpu_capability(),
        "cuda": torch.cuda.get_device_name(0) if torch.cuda.is_available() else None,
    }


class _Tee(io.TextIOBase):
    def __init__(self, stream) -> None:
        self.stream, self.buffer = stream, io.StringIO()

    def write(self, text: str) -> int:
        self.stream.write(text)
        return self.buffer.write(text)

    def flush(self) -> None:
        self.stream.flush()


def run_recorded(name: str, main: Callable[[], None]) -> Path:
    """Run ``main`` with its output shown and kept; write the JSON record; return its path."""
    started = time.strftime("%Y-%m-%d %H:%M:%S %Z")
    tee = _Tee(sys.stdout)
    sys.stdout = tee
    try:
        main()
    finally:
        sys.stdout = tee.stream
    RESULTS.mkdir(exist_ok=True)
    out = RESULTS / f"{name}-{time.strftime('%Y-%m-%d-%H%M')}.json"
    record = {
        "script": f"benchmarks/{name}.py",
        "argv": sys.argv[1:],
        "started": started,
        "machine": machine(),
        "output": tee.buffer.getvalue().splitlines(),
    }
    out.write_text(json.dumps(record, indent=2) + "\n")
    print(f"recorded in {out.relative_to(RESULTS.parent.parent)}")
    return out
