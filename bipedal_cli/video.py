"""Recording the deterministic policy to H.264 MP4 or GIF, off-screen (``render_mode="rgb_array"``).

No window and no display: Box2D's renderer draws into an array (pygame surfaces off-screen), so
this works on a headless machine and in CI.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import imageio.v2 as imageio
import numpy as np
from PIL import Image, ImageDraw

from .config import AgentConfig
from .envs import make_policy_env
from .evaluation import EpisodeResult
from .paths import atomic_path

VIDEO_SUFFIXES = (".mp4", ".gif")


def caption(frame: np.ndarray, text: str) -> np.ndarray:
    """Draw ``text`` in the top-left corner of an (H, W, 3) uint8 frame."""
    image = Image.fromarray(frame)
    draw = ImageDraw.Draw(image)
    draw.rectangle((4, 4, 8 + 7 * len(text), 20), fill=(255, 255, 255))
    draw.text((7, 6), text, fill=(0, 0, 0))
    return np.asarray(image)


def _writer(path: Path, fps: float):
    if path.suffix.lower() == ".gif":
        # duration per frame in ms; loop forever
        return imageio.get_writer(path, format="GIF", mode="I", duration=1000.0 / fps, loop=0)
    # yuv420p + H.264 is what browsers and common players open; 600x400 frames are even-sized,
    # so macro_block_size=2 keeps them as they are (the default 16 would pad 600 to 608).
    return imageio.get_writer(
        path,
        format="FFMPEG",
        fps=fps,
        codec="libx264",
        pixelformat="yuv420p",
        macro_block_size=2,
        quality=7,
    )


def record(
    policy: Callable[[np.ndarray], np.ndarray],
    env_id: str,
    out: Path,
    seeds: list[int],
    fps: float | None = None,
    frame_step: int = 1,
    scale: float = 1.0,
    on_frame: Callable[[], None] | None = None,
    agent_cfg: AgentConfig | None = None,
) -> tuple[list[EpisodeResult], int, float]:
    """Play one episode per seed and write every ``frame_step``-th frame (scaled) to ``out``.

    The env is the policy's (``agent_cfg``'s action repeat and history), with a frame per env
    step, also inside an action repeat. Returns the episodes, the number of frames written and
    the frame rate. The file appears atomically: frames go to a temporary file that is renamed
    over ``out`` at the end.
    """
    episode = {"label": "", "ret": 0.0, "t": 0}

    def on_env_step(env_reward: float) -> None:
        episode["ret"] += env_reward
        episode["t"] += 1
        if episode["t"] % frame_step == 0:
            grab()

    def grab() -> None:
        frame = env.render()
        if scale != 1.0:
            h, w = frame.shape[:2]
            size = (2 * round(w * scale / 2), 2 * round(h * scale / 2))
            frame = np.asarray(Image.fromarray(frame).resize(size))
        writer.append_data(caption(frame, f"{episode['label']}  return {episode['ret']:7.1f}"))
        counts["frames"] += 1
        if on_frame:
            on_frame()

    env = make_policy_env(env_id, agent_cfg or AgentConfig(), True, on_env_step)
    fps = float(fps or env.metadata.get("render_fps", 50)) / (1 if fps else frame_step)
    episodes: list[EpisodeResult] = []
    counts = {"frames": 0}
    try:
        with atomic_path(out) as tmp, _writer(tmp, fps) as writer:
            for k, seed in enumerate(seeds):
                obs, _ = env.reset(seed=seed)
                episode.update(label=f"episode {k + 1}/{len(seeds)}  seed {seed}", ret=0.0, t=0)
                grab()
                done = False
                while not done:
                    action = policy(obs[None].astype(np.float32))[0]
                    obs, _, term, trunc, info = env.step(action)
                    done = term or trunc
                episodes.append(EpisodeResult(seed, episode["ret"], episode["t"], info["fell"]))
    finally:
        env.close()
    return episodes, counts["frames"], fps
