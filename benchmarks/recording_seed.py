"""Pick the env seed that README's Hardcore recording shows: the first episode of a `bipedal eval
--json` report that did not fall and whose course has stumps, pits and stairs (so the video
shows all three being crossed, not a course that happens to be easy).

    python benchmarks/recording_seed.py checkpoints/bipedal_hardcore.eval.json
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import gymnasium as gym

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bipedal_cli.terrain import course_obstacles  # noqa: E402


def obstacle_counts(env_id: str, seed: int) -> dict[str, int]:
    env = gym.make(env_id)
    env.reset(seed=seed)
    counts: dict[str, int] = {}
    for span in course_obstacles(env.unwrapped):
        counts[span.kind] = counts.get(span.kind, 0) + 1
    env.close()
    return counts


def main(report: str) -> None:
    data = json.loads(Path(report).read_text())
    env_id = data["summary"]["env"]
    for episode in data["episodes"]:
        if episode["fell"]:
            continue
        counts = obstacle_counts(env_id, episode["seed"])
        if {"stump", "pit", "stairs"} <= set(counts):
            print(
                f"env seed {episode['seed']}: return {episode['ret']:.1f}, "
                f"{episode['length']} env steps, course: "
                + ", ".join(f"{n} {kind}" for kind, n in sorted(counts.items()))
            )
            return
    print("no episode without a fall crosses all three obstacle kinds")


if __name__ == "__main__":
    main(sys.argv[1])
