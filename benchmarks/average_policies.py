"""Average a run's kept policies (``train.keep_policies``) parameter by parameter, stochastic
weight averaging's way, into one policy file that `bipedal select` and `bipedal eval` read.

    python benchmarks/average_policies.py runs/hardcore/lrdecay-seed0 --from 1400000 \\
        --to 1500000 --out /tmp/avg-1.40-1.50.pt

theta_avg = (1 / K) sum_k theta_k over the K kept policies with from <= step <= to, summed in
float64. The file is the last of them with the averaged actor, and no periodic evaluation of its
own (its step is the last one's). docs/hardcore.md (session 4) records the test: on held-out
seeds the averages did not beat the single policies they came from.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import torch

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bipedal_cli.checkpoint import POLICIES_DIR, atomic_save, load_checkpoint  # noqa: E402


def average_actor(states: list[dict[str, torch.Tensor]]) -> dict[str, torch.Tensor]:
    """The parameter-wise mean of actor state dicts of one architecture."""
    return {
        name: torch.stack([s[name].double() for s in states]).mean(0).to(states[-1][name].dtype)
        for name in states[-1]
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("run", type=Path)
    parser.add_argument("--from", dest="first", type=int, required=True)
    parser.add_argument("--to", dest="last", type=int, required=True)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    kept = sorted(
        (int(p.stem.removeprefix("step-")), p) for p in (args.run / POLICIES_DIR).glob("step-*.pt")
    )
    chosen = [p for step, p in kept if args.first <= step <= args.last]
    if not chosen:
        raise SystemExit(f"{args.run}: no kept policy between {args.first} and {args.last}")
    policies = [load_checkpoint(p) for p in chosen]
    averaged = {k: v for k, v in policies[-1].items() if k != "path"}
    averaged["actor"] = average_actor([p["actor"] for p in policies])
    steps = [int(p["meta"]["steps"]) for p in policies]
    averaged["meta"] = {**averaged["meta"], "last_eval": None, "averaged_steps": steps}
    atomic_save(averaged, args.out)
    print(f"{args.out}: the mean of {len(steps)} kept policies, steps {steps[0]:,}..{steps[-1]:,}")


if __name__ == "__main__":
    main()
