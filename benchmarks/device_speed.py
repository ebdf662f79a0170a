"""Training speed of a run's config on each device, at its batch and update ratio and at the
larger ones a GPU might afford: policy steps/s of full training and updates/s alone.

    python benchmarks/device_speed.py --config configs/hardcore-lrdecay-cvar25-g99.yaml \
        --devices cuda cpu --variants 64x1 256x1 64x2 --steps 1000

A variant BxU is U gradient updates of B transitions per policy step. Every measurement runs in
its own subprocess (clean threads, one CUDA context), after ``--warmup`` random policy steps
that are not timed; the run's risk-averse actor objective (``agent.actor_cvar``), more
truncation, the target entropy's decay and the actor's smoothness term, where the config has
them, are switched on from the start so that each update is a late-run one. "policy steps/s"
is full training: the environment (with the config's action repeat), the replay buffer and U
updates per step. "updates/s alone" draws the batches beforehand. CPU measurements use
``--cpu-threads``. The printed lines and the machine go to
benchmarks/results/device_speed-<date>.json.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable

from record import run_recorded

from bipedal_cli.reporting import NullReporter


class Clock(NullReporter):
    """A reporter that notes when each of the loop's reports (every 50 steps) came."""

    def __init__(self, sync: Callable[[], None] = lambda: None) -> None:
        self.sync, self.marks = sync, []

    def update(self, snapshot) -> None:
        self.sync()  # on a GPU, the work queued so far is part of the span
        self.marks.append((snapshot["step"], time.perf_counter()))

    def steps_per_s(self, first_timed: int) -> float:
        """Steps per second from the first report at or after ``first_timed`` to the one before
        the last: the last comes after the final save."""
        timed = [(s, t) for s, t in self.marks if s >= first_timed]
        (s0, t0), (s1, t1) = timed[0], timed[-2]
        return (s1 - s0) / (t1 - t0)


def updates_per_s(trainer, batch: int, count: int, sync: Callable[[], None]) -> float:
    """Gradient updates per second alone, on ``count`` batches drawn from the run's buffer
    beforehand (generator seeded 0)."""
    import numpy as np

    rng = np.random.default_rng(0)
    agent = trainer.agent
    batches = [agent.batch_to_tensors(trainer.buffer.sample(batch, rng)) for _ in range(count)]
    sync()
    start = time.perf_counter()
    for b in batches:
        agent.update(b)
    agent.sync()  # the last critics' step may still run on the worker thread
    sync()
    return count / (time.perf_counter() - start)


def measure(
    config: str,
    device: str,
    batch: int,
    updates: int,
    steps: int,
    warmup: int,
    threads: int,
    extra: tuple[str, ...] = (),
) -> dict:
    """Both speeds of ``config`` with these settings; ``extra``: more ``key=value`` overrides."""
    import torch

    from bipedal_cli.config import resolve_config
    from bipedal_cli.train import Trainer

    overrides = {
        "device": device,
        "agent.batch_size": batch,
        "agent.actor_cvar_start": 0,
        "agent.drop_per_critic_start": 0,
        "agent.actor_smooth_start": 0,
        "agent.target_entropy_decay_start": 0,
        "train.updates_per_step": updates,
        "train.warmup_steps": warmup,
        "train.eval_every": 0,
        "train.checkpoint_every": 0,
        "train.keep_policies": False,
        "train.threads": threads,
        "train.buffer_size": 100_000,
    }
    cfg = resolve_config(config, [f"{k}={v}" for k, v in overrides.items()] + list(extra))
    sync = torch.cuda.synchronize if device.startswith("cuda") else (lambda: None)
    clock = Clock(sync)
    trainer = Trainer(cfg, tempfile.mkdtemp(prefix="bipedal-speed-"), clock)
    trainer.run(total_steps=warmup + 100 + steps)
    train_sps = clock.steps_per_s(warmup + 100)

    return {
        "policy_steps_per_s": train_sps,
        "updates_per_s": updates_per_s(trainer, batch, steps, sync),
    }


def run_child(cmd: list[str]) -> dict:
    """Run one measurement in its own process: the dict it printed after ``RESULT``, or
    ``{"error": the end of its stderr}``."""
    proc = subprocess.run(cmd, capture_output=True, text=True)
    lines = [x for x in proc.stdout.splitlines() if x.startswith("RESULT ")]
    if not lines:
        return {"error": proc.stderr.strip()[-300:]}
    return json.loads(lines[-1][len("RESULT ") :])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--config", default="configs/hardcore-lrdecay-cvar25-g99.yaml")
    parser.add_argument("--devices", nargs="+", default=["cuda", "cpu"])
    parser.add_argument("--variants", nargs="+", default=["64x1", "256x1", "64x2"])
    parser.add_argument("--cpu-variants", nargs="+", default=["64x1"])
    parser.add_argument("--steps", type=int, default=1000, help="timed policy steps")
    parser.add_argument("--warmup", type=int, default=1000)
    parser.add_argument("--cpu-threads", type=int, default=1)
    parser.add_argument("--child", nargs=3, help=argparse.SUPPRESS)  # device batch updates
    args = parser.parse_args()
    if args.child:
        device, batch, updates = args.child[0], int(args.child[1]), int(args.child[2])
        threads = args.cpu_threads if device == "cpu" else 1
        out = measure(args.config, device, batch, updates, args.steps, args.warmup, threads)
        print("RESULT " + json.dumps(out))
        return

    print(f"config {args.config}, {args.steps} timed policy steps after {args.warmup} warm-up")
    print("| device | batch x updates/step | policy steps/s | updates/s alone |")
    print("|---|---|---|---|")
    for device in args.devices:
        for variant in args.cpu_variants if device == "cpu" else args.variants:
            batch, updates = variant.split("x")
            cmd = [
                sys.executable,
                __file__,
                "--config",
                args.config,
                "--steps",
                str(args.steps),
                "--warmup",
                str(args.warmup),
                "--cpu-threads",
                str(args.cpu_threads),
                "--child",
                device,
                batch,
                updates,
            ]
            r = run_child(cmd)
            if "error" in r:
                print(f"| {device} | {variant} | failed: {r['error']} | |")
                continue
            name = f"{device} ({args.cpu_threads} thread)" if device == "cpu" else device
            print(
                f"| {name} | {batch} x {updates} | {r['policy_steps_per_s']:.1f} "
                f"| {r['updates_per_s']:.1f} |",
                flush=True,
            )


if __name__ == "__main__":
    if "--child" in sys.argv:
        main()
    else:
        run_recorded("device_speed", main)
