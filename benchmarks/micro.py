"""The measurements behind README's "what made it fast" list (one thread, paper sizes).

    python benchmarks/micro.py

1. quantile Huber loss + backward: pairwise (B x N x M x K tensor) against the sorted closed form;
2. Adam step over the critics' parameters: foreach against fused;
3. sorting the pooled target atoms (64 x 125): torch.sort against NumPy's sort (``sort_rows``),
   and the loss's binary searches: torch.searchsorted against ``count_below``;
4. where one update's time goes: every ATen op timed by category (matrix products, optimizer,
   sort/search, the rest) against the update's wall time; the difference is Python and autograd;
5. the matrix products' floor: an update's FLOPs over one core's large-product GFLOP/s;
6. TQC updates/s after 3,000 training steps with and without flushing denormal floats.
"""

from __future__ import annotations

import tempfile
import time

import numpy as np
import torch

from bipedal_cli.config import config_from_dict
from bipedal_cli.losses import quantile_huber_loss, quantile_huber_loss_pairwise, sort_rows
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


def sort_timings() -> None:
    x = torch.randn(64, 125)
    torch_ms = per_call_ms(lambda: torch.sort(x, dim=1), 300)
    numpy_ms = per_call_ms(lambda: sort_rows(x), 300)
    print(f"sort (64, 125): torch.sort {torch_ms:.3f} ms, sort_rows (NumPy) {numpy_ms:.3f} ms")


def search_timings() -> None:
    """The loss's three searches of 64 x 125 atoms among 115 sorted targets, in float64."""
    from bipedal_cli.losses import count_below

    y = torch.sort(torch.randn(64, 115, dtype=torch.float64), dim=1).values
    theta = torch.randn(64, 125, dtype=torch.float64)

    def with_searchsorted():
        torch.searchsorted(y, theta - 1.0, side="left")
        torch.searchsorted(y, theta, side="left")
        torch.searchsorted(y, theta + 1.0, side="right")

    def with_count_below():
        count_below(y, torch.cat([theta - 1.0, theta], 1), theta + 1.0)

    a, b = per_call_ms(with_searchsorted, 300), per_call_ms(with_count_below, 300)
    print(f"loss searches: torch.searchsorted {a:.3f} ms, count_below (branch-free) {b:.3f} ms")


def _category(name: str) -> str:
    if name.startswith(("mm", "bmm", "baddbmm", "addmm", "matmul")):
        return "matrix products"
    if name.startswith(("_fused_adam", "_foreach")):
        return "Adam and Polyak"
    if name.startswith(("sort", "searchsorted", "gather", "cumsum")):
        return "sort, search, gather"
    return "other ops (elementwise, copies, RNG)"


def update_breakdown(updates: int = 200) -> None:
    from torch.utils._python_dispatch import TorchDispatchMode

    from bipedal_cli.agent import TQCAgent
    from bipedal_cli.config import AgentConfig

    torch.set_flush_denormal(True)  # as in training (train.flush_denormal)
    torch.manual_seed(0)
    agent = TQCAgent(AgentConfig(), 24, 4)
    gen = torch.Generator().manual_seed(0)

    def batch():
        return {
            "obs": torch.randn(64, 24, generator=gen),
            "action": torch.rand(64, 4, generator=gen) * 2 - 1,
            "reward": torch.randn(64, generator=gen),
            "next_obs": torch.randn(64, 24, generator=gen),
            "terminated": torch.zeros(64),
        }

    batches = [batch() for _ in range(50)]
    for b in batches:
        agent.update(b)
    start = time.perf_counter()
    for i in range(updates):
        agent.update(batches[i % 50])
    plain_ms = (time.perf_counter() - start) / updates * 1e3

    totals: dict[str, float] = {}
    counts = 0

    class OpTimer(TorchDispatchMode):
        def __torch_dispatch__(self, func, types, args=(), kwargs=None):
            nonlocal counts
            begin = time.perf_counter()
            out = func(*args, **(kwargs or {}))
            key = _category(func.__name__)
            totals[key] = totals.get(key, 0.0) + time.perf_counter() - begin
            counts += 1
            return out

    with OpTimer():
        for i in range(updates):
            agent.update(batches[i % 50])
    print(
        f"one update (batch 64, paper sizes): {plain_ms:.2f} ms; "
        f"{counts / updates:.0f} ATen ops per update"
    )
    for key, seconds in sorted(totals.items(), key=lambda kv: -kv[1]):
        print(f"  {key:40s} {seconds / updates * 1e3:6.2f} ms")
    ops_ms = sum(totals.values()) / updates * 1e3
    print(f"  {'Python, autograd, dispatch (the rest)':40s} {max(plain_ms - ops_ms, 0.0):6.2f} ms")


def matmul_floor(updates: int = 20) -> None:
    """The least time an update's matrix products can take on one core of this CPU.

    FLOPs of one update counted by ``FlopCounterMode`` (every mm/bmm/baddbmm, forward and
    backward), over the GFLOP/s of one large single-thread product (1024^3), which batch-64
    products do not beat.
    """
    from torch.utils.flop_counter import FlopCounterMode

    from bipedal_cli.agent import TQCAgent
    from bipedal_cli.config import AgentConfig

    torch.manual_seed(0)
    agent = TQCAgent(AgentConfig(), 24, 4)
    batch = {
        "obs": torch.randn(64, 24),
        "action": torch.rand(64, 4) * 2 - 1,
        "reward": torch.randn(64),
        "next_obs": torch.randn(64, 24),
        "terminated": torch.zeros(64),
    }
    counter = FlopCounterMode(display=False)
    with counter:
        agent.update(batch)
    flops = counter.get_total_flops()
    a, b = torch.randn(1024, 1024), torch.randn(1024, 1024)
    ms = per_call_ms(lambda: a @ b, updates)
    peak = 2 * 1024**3 / (ms / 1e3) / 1e9
    print(
        f"matrix products: {flops / 1e6:.0f} MFLOP per update; one core does {peak:.0f} GFLOP/s "
        f"on a 1024^3 product, so they need at least {flops / peak / 1e6:.2f} ms per update"
    )


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
    sort_timings()
    search_timings()
    update_breakdown()
    matmul_floor()
    denormal_timings()


if __name__ == "__main__":
    from record import run_recorded

    run_recorded("micro", main)
