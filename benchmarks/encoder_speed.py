"""Training speed of a Hardcore config with each observation encoder (``agent.encoder``) and
window length (``agent.history``): policy steps/s of full training and updates/s alone.

    python benchmarks/encoder_speed.py --config configs/hardcore-lrdecay-cvar25.yaml \
        --variants none:4 lstm:12:32 lstm:12:64 lstm:12:128 --threads 2 --steps 1000

A variant is ``none:H`` (the flattened window of H observations) or ``lstm:H:W`` (an LSTM of
width W over H observations, :mod:`bipedal_cli.encoders`). Every measurement runs in its own
subprocess, on CPU with ``--threads`` (2: the critics' and actor's parts of each update on two
threads, as the runs train), after ``--warmup`` random policy steps that are not timed, with the
config's risk-averse actor on from the start (device_speed.py's ``measure``). The printed lines
and the machine go to benchmarks/results/encoder_speed-<date>.json.
"""

from __future__ import annotations

import argparse
import json
import sys

from device_speed import measure, run_child
from record import run_recorded


def overrides(variant: str) -> tuple[str, ...]:
    """``none:4`` or ``lstm:12:64`` -> the ``--set`` overrides it stands for."""
    kind, history, *width = variant.split(":")
    sets = (f"agent.encoder={kind}", f"agent.history={int(history)}")
    return sets + tuple(f"agent.encoder_hidden={int(w)}" for w in width)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--config", default="configs/hardcore-lrdecay-cvar25.yaml")
    parser.add_argument("--variants", nargs="+", default=["none:4", "lstm:12:64"])
    parser.add_argument("--steps", type=int, default=1000, help="timed policy steps")
    parser.add_argument("--warmup", type=int, default=1000)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--child", help=argparse.SUPPRESS)  # one variant
    args = parser.parse_args()
    if args.child:
        extra = overrides(args.child)
        out = measure(args.config, "cpu", 64, 1, args.steps, args.warmup, args.threads, extra)
        print("RESULT " + json.dumps(out))
        return

    print(f"config {args.config}, cpu, {args.threads} threads, {args.steps} timed policy steps")
    print("| encoder | history | width | policy steps/s | updates/s alone |")
    print("|---|---|---|---|---|")
    for variant in args.variants:
        kind, history, *width = variant.split(":")
        cmd = [sys.executable, __file__, "--config", args.config, "--steps", str(args.steps)]
        cmd += ["--warmup", str(args.warmup), "--threads", str(args.threads), "--child", variant]
        r = run_child(cmd)
        label = f"| {kind} | {history} | {width[0] if width else '-'} |"
        if "error" in r:
            print(f"{label} failed: {r['error']} | |")
            continue
        print(f"{label} {r['policy_steps_per_s']:.1f} | {r['updates_per_s']:.1f} |", flush=True)


if __name__ == "__main__":
    if "--child" in sys.argv:
        main()
    else:
        run_recorded("encoder_speed", main)
