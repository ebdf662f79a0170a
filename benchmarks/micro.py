"""The measurements behind README's "what made it fast" list (one thread, paper sizes).

    python benchmarks/micro.py

1. quantile Huber loss + backward: pairwise (B x N x M x K tensor) against the sorted closed form;
2. Adam step over the critics' parameters: foreach against fused;
3. TQC updates/s after 3,000 training steps with and without flushing denormal floats.
"""

from __future__ import annotations

import tempfile
import time

import numpy as np
import torch

from bipedal_cli.config import config_from_dict
from bipedal_cli.losses import quantile_huber_loss, quantile_huber_loss_pairwise
from bipedal_cli.networks import QuantileCritics
from bipedal_cli.train import Trainer


def per_call_ms(fn, repeats: int) -> float:
    for _ in range(5):
        fn()
    start = time.perf_counter()
    for _ in range(repeats):
        fn()
    return (time.perf_counter() - start) / repeats * 1e3


def loss_timings() -> None:
    B, N, M = 64, 5, 25
    K = N * M - 2 * N
    atoms = torch.randn(B, N, M, requires_grad=True)
    target = torch.sort(torch.randn(B, K), dim=1).values
    for fn in (quantile_huber_loss_pairwise, quantile_huber_loss):
        ms = per_call_ms(lambda fn=fn: fn(atoms, target).backward(), 100)
        print(f"{fn.__name__}: {ms:.2f} ms per call with backward (batch {B})")


def adam_timings() -> None:
    critics = QuantileCritics(24, 4)
    for p in critics.parameters():
        p.grad = torch.randn_like(p)
    for kind in ("foreach", "fused"):
        opt = torch.optim.Adam(critics.parameters(), lr=3e-4, **{kind: True})
        ms = per_call_ms(opt.step, 200)
        print(f"Adam ({kind}) over the critics: {ms:.2f} ms per step")


def denormal_timings(steps: int = 3000) -> None:
    cfg = config_from_dict(
        {
            "device": "cpu",
            "train": {
                "eval_every": 0,
                "checkpoint_every": 0,
                "threads": 1,
                "buffer_size": 100_000,
                "flush_denormal": False,
            },
        }
    )
    trainer = Trainer(cfg, tempfile.mkdtemp(prefix="bipedal-micro-"))
    trainer.run(total_steps=steps)
    rng = np.random.default_rng(0)
    batches = [trainer.agent.batch_to_tensors(trainer.buffer.sample(64, rng)) for _ in range(200)]
    for flush in (False, True):
        torch.set_flush_denormal(flush)
        start = time.perf_counter()
        for b in batches:
            trainer.agent.update(b)
        rate = len(batches) / (time.perf_counter() - start)
        print(f"after {steps:,} training steps, flush_denormal={flush}: {rate:.1f} updates/s")


def main() -> None:
    torch.set_num_threads(1)
    print(f"torch {torch.__version__}, 1 thread")
    loss_timings()
    adam_timings()
    denormal_timings()


if __name__ == "__main__":
    main()
