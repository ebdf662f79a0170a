"""Where a CUDA update's time goes: GPU time against wall time, kernel launches and host syncs.

    python benchmarks/cuda_update_profile.py --config configs/hardcore-lrdecay-cvar25-g99.yaml

Trains ``--warmup`` random policy steps and 100 learning steps on CUDA (the actor's CVaR
objective on from the start, as late in a run), then profiles ``--updates`` updates on batches
drawn beforehand with torch.profiler. Prints per update: wall milliseconds, milliseconds the GPU
was busy in kernels, kernel launches, host-device copies and synchronisations; then the ten
host-side operations that take the most time. An update whose GPU time is a small part of its
wall time is bound by launching work, not by the GPU. Needs a CUDA GPU.
"""

from __future__ import annotations

import argparse
import tempfile
import time

import numpy as np
import torch
from torch.profiler import ProfilerActivity, profile

from bipedal_cli.config import resolve_config
from bipedal_cli.reporting import NullReporter
from bipedal_cli.train import Trainer


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--config", default="configs/hardcore-lrdecay-cvar25-g99.yaml")
    parser.add_argument("--batch", type=int, default=64)
    parser.add_argument("--warmup", type=int, default=1000)
    parser.add_argument("--updates", type=int, default=100)
    args = parser.parse_args()
    sets = ["device=cuda", f"agent.batch_size={args.batch}", "agent.actor_cvar_start=0"]
    sets += [f"train.warmup_steps={args.warmup}", "train.eval_every=0", "train.threads=1"]
    sets += ["train.checkpoint_every=0", "train.keep_policies=false", "train.buffer_size=100000"]
    cfg = resolve_config(args.config, sets)
    trainer = Trainer(cfg, tempfile.mkdtemp(prefix="bipedal-profile-"), NullReporter())
    trainer.run(total_steps=args.warmup + 100)
    agent, rng = trainer.agent, np.random.default_rng(0)
    batches = [
        agent.batch_to_tensors(trainer.buffer.sample(args.batch, rng)) for _ in range(args.updates)
    ]
    torch.cuda.synchronize()
    with profile(activities=[ProfilerActivity.CPU, ProfilerActivity.CUDA]) as prof:
        start = time.perf_counter()
        for b in batches:
            agent.update(b)
        agent.sync()
        torch.cuda.synchronize()
        wall = time.perf_counter() - start
    events = prof.key_averages()
    n = args.updates
    gpu_us = sum(e.self_device_time_total for e in events)  # each kernel counted once
    counts = {e.key: e.count for e in events}
    launches = sum(c for k, c in counts.items() if k in ("cudaLaunchKernel", "cuLaunchKernel"))
    copies = sum(c for k, c in counts.items() if k.startswith("cudaMemcpy"))
    syncs = sum(c for k, c in counts.items() if "Synchronize" in k)
    print(f"{torch.cuda.get_device_name(0)}, batch {args.batch}, {n} updates")
    print(f"wall {1000 * wall / n:.2f} ms per update, GPU busy {gpu_us / 1000 / n:.2f} ms")
    print(f"per update: {launches / n:.0f} kernel launches, {copies / n:.1f} host-device copies,")
    print(f"{syncs / n:.1f} synchronisations")
    print(events.table(sort_by="self_cpu_time_total", row_limit=10, max_name_column_width=40))


if __name__ == "__main__":
    main()
