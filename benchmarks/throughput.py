"""Training throughput: bipedal's TQC + D2RL against sb3-contrib's TQC at the paper's sizes.

    pip install -e ".[bench]"
    python benchmarks/throughput.py                 # both, 1 and 2 threads, a few minutes
    python benchmarks/throughput.py --threads 1 --steps 1000 --skip-sb3

Every measurement runs in its own subprocess (clean thread settings, clean peak memory). Both
implementations use 5 critics x 25 quantiles (drop 2 per net), critics 2 x 256, actor 2 x 512,
batch 64, one gradient step per env step, gamma 0.98, 1,000 random warm-up steps that are not
timed. "env steps/s" is full training after warm-up: env step, replay buffer, gradient step.
sb3's networks are plain MLPs; ours are D2RL (slightly more work per layer).

With 2 threads bipedal splits each update into the critics' and the actor's parts, run on two
threads (``train.split_update``); the "update not split" figure is the same code with the split
off (both threads used inside each op instead), to show what the split gains.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time

WARMUP = 1000


from device_speed import Clock, updates_per_s  # noqa: E402

from bipedal_cli.devices import cpu_name  # noqa: E402


def peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def measure_ours(threads: int, steps: int, device: str, eval_episodes: int, split: bool) -> dict:
    import torch

    from bipedal_cli.config import config_from_dict
    from bipedal_cli.evaluation import evaluate_actor
    from bipedal_cli.train import Trainer

    cfg = config_from_dict(
        {
            "device": device,
            "train": {
                "warmup_steps": WARMUP,
                "eval_every": 0,
                "checkpoint_every": 0,
                "threads": threads,
                "split_update": split,
                "buffer_size": 100_000,
            },
        }
    )

    sync = torch.cuda.synchronize if device != "cpu" else (lambda: None)
    clock = Clock(sync)
    trainer = Trainer(cfg, tempfile.mkdtemp(prefix="bipedal-bench-"), clock)
    trainer.run(total_steps=WARMUP + 100 + steps)
    train_sps = clock.steps_per_s(WARMUP + 100)

    update_sps = updates_per_s(trainer, 64, steps, sync)  # on batches drawn beforehand

    result = {"env_steps_per_s": train_sps, "updates_per_s": update_sps}
    if eval_episodes:
        actor, policy_source = trainer.agent.actor, "the benchmark's briefly trained actor"
        shipped = os.path.join(os.path.dirname(__file__), "..", "checkpoints", "bipedal_walker.pt")
        if os.path.exists(shipped):
            from bipedal_cli.checkpoint import actor_from_checkpoint, load_checkpoint

            actor, _ = actor_from_checkpoint(load_checkpoint(shipped))
            policy_source = "checkpoints/bipedal_walker.pt"
        seeds = list(range(eval_episodes))
        start = time.perf_counter()
        episodes = evaluate_actor(actor, cfg.agent, cfg.env, seeds, workers=0)
        result["eval_s"] = time.perf_counter() - start
        result["eval_episodes"] = eval_episodes
        result["eval_env_steps"] = sum(e.length for e in episodes)
        result["eval_policy"] = policy_source
    result["peak_rss_mb"] = peak_rss_mb()
    return result


def measure_sb3(threads: int, steps: int, flush_denormal: bool) -> dict:
    import gymnasium as gym
    import torch
    from sb3_contrib import TQC
    from stable_baselines3.common.callbacks import BaseCallback

    torch.set_num_threads(threads)
    torch.set_flush_denormal(flush_denormal)
    marks: dict[str, float] = {}

    class Clock(BaseCallback):
        def _on_step(self) -> bool:
            if self.num_timesteps == WARMUP + 50:
                marks["start"] = time.perf_counter()
            return True

    model = TQC(
        "MlpPolicy",
        gym.make("BipedalWalker-v3"),
        learning_rate=3.296e-4,
        buffer_size=100_000,
        learning_starts=WARMUP,
        batch_size=64,
        tau=0.005,
        gamma=0.98,
        train_freq=1,
        gradient_steps=1,
        top_quantiles_to_drop_per_net=2,
        policy_kwargs={
            "n_critics": 5,
            "n_quantiles": 25,
            "net_arch": {"pi": [512, 512], "qf": [256, 256]},
        },
        device="cpu",
        seed=0,
        verbose=0,
    )
    model.learn(total_timesteps=WARMUP + 50 + steps, callback=Clock())
    train_sps = steps / (time.perf_counter() - marks["start"])
    return {"env_steps_per_s": train_sps, "peak_rss_mb": peak_rss_mb()}


def child(args) -> None:
    if args.impl in ("ours", "ours-unsplit"):
        split = args.impl == "ours"
        out = measure_ours(args.threads, args.steps, args.device, args.eval_episodes, split)
    else:
        out = measure_sb3(args.threads, args.steps, args.child == "sb3-flush")
    print("RESULT " + json.dumps(out))


def run_child(impl: str, threads: int, steps: int, device: str, eval_episodes: int) -> dict:
    cmd = [
        sys.executable,
        __file__,
        "--child",
        impl,
        "--threads",
        str(threads),
        "--steps",
        str(steps),
        "--device",
        device,
        "--eval-episodes",
        str(eval_episodes),
    ]
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), MKL_NUM_THREADS=str(threads))
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
    for line in proc.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[len("RESULT ") :])
    raise RuntimeError(f"{impl} with {threads} threads failed:\n{proc.stderr[-3000:]}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--steps", type=int, default=2000, help="timed env steps per run")
    parser.add_argument("--sb3-steps", type=int, default=600, help="timed env steps for sb3")
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--eval-episodes", type=int, default=100)
    parser.add_argument("--skip-sb3", action="store_true")
    parser.add_argument("--json", help="also write the results here")
    parser.add_argument(
        "--child", choices=["ours", "ours-unsplit", "sb3", "sb3-flush"], help=argparse.SUPPRESS
    )
    args = parser.parse_args()
    if args.child:
        args.impl = args.child
        args.threads = args.threads[0]
        child(args)
        return

    import torch

    print(f"machine: {cpu_name()}, {os.cpu_count()} cores, {platform.platform()}")
    print(
        f"python {platform.python_version()}, torch {torch.__version__}"
        f" ({torch.backends.cpu.get_cpu_capability()} kernels), device {args.device}"
    )
    rows = []
    for threads in args.threads:
        eval_episodes = args.eval_episodes if threads == args.threads[0] else 0
        row = {"threads": threads}
        row["ours"] = run_child("ours", threads, args.steps, args.device, eval_episodes)
        if threads >= 2 and args.device == "cpu":  # what splitting each update gains
            row["ours_unsplit"] = run_child("ours-unsplit", threads, args.steps, "cpu", 0)
        if not args.skip_sb3:
            # as shipped, and with the same denormal flushing we use (a one-line change for them)
            row["sb3"] = run_child("sb3", threads, args.sb3_steps, "cpu", 0)
            row["sb3_flush"] = run_child("sb3-flush", threads, args.sb3_steps, "cpu", 0)
        rows.append(row)
        o = row["ours"]
        print(
            f"threads {threads}: bipedal {o['env_steps_per_s']:.1f} env steps/s "
            f"({o['updates_per_s']:.1f} updates/s alone, peak {o['peak_rss_mb']:.0f} MB)"
            + "".join(
                f"; {name} {row[key]['env_steps_per_s']:.1f} env steps/s"
                f" (peak {row[key]['peak_rss_mb']:.0f} MB)"
                for key, name in (
                    ("ours_unsplit", "bipedal with the update not split"),
                    ("sb3", "sb3-contrib"),
                    ("sb3_flush", "sb3-contrib+flush"),
                )
                if key in row
            ),
            flush=True,
        )
    print()
    print(
        "| threads | bipedal env steps/s | bipedal updates/s (alone) | bipedal, update not "
        "split | sb3-contrib TQC env steps/s | ratio | sb3-contrib TQC + flush_denormal | ratio |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        o = r["ours"]["env_steps_per_s"]
        cells = [str(r["threads"]), f"{o:.1f}", f"{r['ours']['updates_per_s']:.1f}"]
        unsplit = r.get("ours_unsplit")
        cells.append(
            f"{unsplit['env_steps_per_s']:.1f} ({unsplit['updates_per_s']:.1f} updates/s)"
            if unsplit
            else "-"
        )
        for key in ("sb3", "sb3_flush"):
            if key in r:
                peer = r[key]["env_steps_per_s"]
                cells += [f"{peer:.1f}", f"{o / peer:.1f}x"]
            else:
                cells += ["-", "-"]
        print("| " + " | ".join(cells) + " |")
    first = rows[0]["ours"]
    if "eval_s" in first:
        print(
            f"\n100-episode evaluation ({first['eval_policy']}, every core): "
            f"{first['eval_s']:.1f} s for {first['eval_episodes']} episodes, "
            f"{first['eval_env_steps']:,} env steps"
        )
    if args.json:
        with open(args.json, "w") as f:
            json.dump(
                {"machine": cpu_name(), "torch": torch.__version__, "rows": rows}, f, indent=2
            )


if __name__ == "__main__":
    main()
