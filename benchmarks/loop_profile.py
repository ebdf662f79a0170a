"""Where a training step's time goes on each thread, in the real loop (paper sizes, CPU).

    python benchmarks/loop_profile.py             # 2 threads: the update split over two threads
    python benchmarks/loop_profile.py --threads 1

Trains 1,000 warm-up steps plus ``--warm`` steps untimed, then ``--steps`` timed env steps, and
prints the milliseconds per env step spent in each part, by thread. With the split update the
worker thread runs the critics' gradients and step; the main thread waits for the worker's last
step (``sync``), takes the actor's gradients and step, acts, steps the env and samples the buffer.
The busier thread sets the pace. The timers wrap methods, so they add a little overhead.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from collections import defaultdict

from bipedal_cli.config import config_from_dict
from bipedal_cli.reporting import NullReporter
from bipedal_cli.train import Trainer

MAIN = ("sync", "actor_gradients", "actor_step", "act", "env.step", "sample", "batch_to_tensors")
WORKER = ("critic_gradients", "critic_step")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--warm", type=int, default=1000, help="untimed training steps")
    parser.add_argument("--steps", type=int, default=3000, help="timed env steps")
    args = parser.parse_args()
    cfg = config_from_dict(
        {
            "device": "cpu",
            "train": {
                "warmup_steps": 1000,
                "eval_every": 0,
                "checkpoint_every": 0,
                "threads": args.threads,
                "buffer_size": 100_000,
            },
        }
    )
    trainer = Trainer(cfg, tempfile.mkdtemp(prefix="bipedal-loop-"), NullReporter())
    trainer.run(total_steps=1000 + args.warm)

    seconds: dict[str, float] = defaultdict(float)

    def timed(name, fn):
        def wrapper(*a, **k):
            start = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                seconds[name] += time.perf_counter() - start

        return wrapper

    agent = trainer.agent
    for name in (*MAIN, *WORKER):
        if hasattr(agent, name):  # env.step and sample are not the agent's
            setattr(agent, name, timed(name, getattr(agent, name)))
    trainer.buffer.sample = timed("sample", trainer.buffer.sample)
    runner = trainer.runner  # owns the env: a new one every episode, so wrap each one's step
    fresh_env = runner._fresh_env

    def fresh_env_timed():
        fresh_env()
        runner.env.step = timed("env.step", runner.env.step)

    runner._fresh_env = fresh_env_timed
    runner.env.step = timed("env.step", runner.env.step)

    split = agent._worker is not None  # the trainer started it for 2+ threads
    start = time.perf_counter()
    trainer.run(total_steps=trainer.step + args.steps)
    per_step_ms = (time.perf_counter() - start) / args.steps * 1e3
    print(
        f"{args.threads} threads: {1e3 / per_step_ms:.1f} env steps/s, "
        f"{per_step_ms:.2f} ms per step"
    )
    groups = (
        (("main thread", MAIN), ("worker thread", WORKER))
        if split
        else (("one thread", MAIN + WORKER),)
    )
    for title, names in groups:
        parts = {n: seconds[n] / args.steps * 1e3 for n in names if n in seconds}
        if not split:
            parts.pop("sync", None)
        if not parts:
            continue
        busy = sum(v for n, v in parts.items() if n != "sync")
        waits = " (plus waiting for the worker in sync)" if split and "sync" in parts else ""
        print(f"  {title}: {busy:.2f} ms busy per step{waits}")
        for n, v in parts.items():
            print(f"    {n:20s} {v:6.3f} ms")


if __name__ == "__main__":
    from record import run_recorded

    run_recorded("loop_profile", main)
