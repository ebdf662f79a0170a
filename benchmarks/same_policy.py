"""Do two checkpoints hold the same policy? Compare their actors tensor for tensor (issue 14's
item 2: the shipped policy, retrained from scratch by its committed command).

    python benchmarks/same_policy.py checkpoints/bipedal_hardcore.pt RUN/policies/step-1740000.pt

Either file may be a policy file or a training state. It prints how many actor tensors are
equal (``torch.equal``: same shape, same bits), the largest absolute difference, and the
counters both files record (env, policy steps, env steps, episodes, last evaluation); the exit
status is 1 when a tensor or a counter differs, 2 on bad input.
"""

from __future__ import annotations

import sys
from pathlib import Path

import torch

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bipedal_cli.checkpoint import POLICY_FORMAT, actor_weights, load_checkpoint  # noqa: E402
from bipedal_cli.checkpoint_contents import training_progress  # noqa: E402
from bipedal_cli.errors import UserError  # noqa: E402

COUNTERS = ("steps", "env_steps", "episodes")


def counters_of(data: dict) -> dict[str, object]:
    """What the file records about where the policy was taken: env, policy steps, env steps,
    episodes and the last periodic evaluation's mean."""
    meta = data["meta"] if data["format"] == POLICY_FORMAT else training_progress(data)
    last = meta.get("last_eval")
    return {
        "env": data["config"]["env"],
        **{k: meta.get(k) for k in COUNTERS},
        "last_eval": round(float(last["mean"]), 3) if last else None,
    }


def compare_actors(
    a: dict[str, torch.Tensor], b: dict[str, torch.Tensor]
) -> tuple[list[str], float]:
    """The names of the tensors that differ (or exist in one actor only) and the largest
    absolute difference between tensors of the same name and shape."""
    differing = sorted(a.keys() ^ b.keys())
    largest = 0.0
    for name in sorted(a.keys() & b.keys()):
        x, y = a[name], b[name]
        if x.shape != y.shape:
            differing.append(name)
            continue
        if not torch.equal(x, y):
            differing.append(name)
        largest = max(largest, (x.double() - y.double()).abs().max().item())
    return differing, largest


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print(__doc__.strip().splitlines()[3].strip(), file=sys.stderr)
        return 2
    try:
        first, second = (load_checkpoint(p, f"file {i + 1}") for i, p in enumerate(argv))
    except UserError as err:
        print(err, file=sys.stderr)
        return 2
    a, b = actor_weights(first), actor_weights(second)
    differing, largest = compare_actors(a, b)
    n = len(a.keys() | b.keys())
    print(f"{n - len(differing)} of {n} actor tensors equal; largest difference {largest:.3g}")
    if differing:
        print(f"differ: {', '.join(differing)}")
    ca, cb = counters_of(first), counters_of(second)
    for key in ca:
        mark = "same" if ca[key] == cb[key] else "DIFFERENT"
        print(f"{key:<10} {ca[key]!s:<28} {cb[key]!s:<28} {mark}")
    # where each was written (files since 2026-12-05): a hint, not a difference, because a
    # policy is the same policy wherever it was trained, but its bits are only expected to
    # match when both were trained on one kind of CPU
    machines = [written_on(data) for data in (first, second)]
    if all(machines) and machines[0] != machines[1]:
        print(f"written on {machines[0]} and on {machines[1]}")
    return 1 if differing or ca != cb else 0


def written_on(data: dict) -> str | None:
    """The machine a file records (``bipedal_cli.devices.machine_summary``), if any."""
    meta = data["meta"] if data["format"] == POLICY_FORMAT else data
    return meta.get("machine")


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
