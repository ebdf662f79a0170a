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


def machine() -> dict:
    import torch

    from bipedal_cli.devices import cpu_name

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


def unused_path(folder: Path, stem: str) -> Path:
    """``folder/stem.json``, or ``stem-2.json``, ``stem-3.json``... when taken: two records in
    the same minute (two configs measured one after the other) must not overwrite each other."""
    folder.mkdir(exist_ok=True)
    out, n = folder / f"{stem}.json", 1
    while out.exists():
        n += 1
        out = folder / f"{stem}-{n}.json"
    return out


def run_recorded(name: str, main: Callable[[], None]) -> Path:
    """Run ``main`` with its output shown and kept; write the JSON record; return its path."""
    started = time.strftime("%Y-%m-%d %H:%M:%S %Z")
    tee = _Tee(sys.stdout)
    sys.stdout = tee
    try:
        main()
    finally:
        sys.stdout = tee.stream
    out = unused_path(RESULTS, f"{name}-{time.strftime('%Y-%m-%d-%H%M')}")
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
