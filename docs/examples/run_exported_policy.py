"""Run a policy exported by `bipedal export` in a plain Gymnasium loop: torch and gymnasium only.

python docs/examples/run_exported_policy.py hardcore.pt2 BipedalWalkerHardcore-v3 0
"""

import collections
import json
import sys

import gymnasium as gym
import numpy as np
import torch

path, env_id, seed = sys.argv[1], sys.argv[2], int(sys.argv[3])
extra = {"bipedal.json": ""}
policy = torch.export.load(path, extra_files=extra).module()
meta = json.loads(extra["bipedal.json"])  # {"history": H, "action_repeat": k, ...}
H, k = meta["history"], meta["action_repeat"]

env = gym.make(env_id)
obs, _ = env.reset(seed=seed)
frames = collections.deque([obs] * H, maxlen=H)  # the last H observations, oldest first
ret, done = 0.0, False
while not done:
    x = torch.as_tensor(np.stack(frames), dtype=torch.float32)  # (H, 24)
    with torch.no_grad():
        action = policy(x[None] if H > 1 else x[-1:])[0].numpy()  # (H, 24) or (24,) in, (4,) out
    for _ in range(k):  # hold the action for k env steps
        obs, reward, terminated, truncated, _ = env.step(action)
        ret += float(reward)
        done = terminated or truncated
        if done:
            break
    frames.append(obs)
print(f"return {ret:.2f}")
