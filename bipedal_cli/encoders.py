"""Observation encoders: what the actor's and the critics' dense networks read.

With ``agent.encoder: lstm`` an LSTM (Hochreiter & Schmidhuber 1997) reads the H stacked
observations o_{t-H+1}, ..., o_t of :class:`~bipedal_cli.envs.ObservationHistory` (oldest first)
and the network sees its last hidden state beside the newest observation. A recurrent encoder
over a window, as in the Hardcore thesis of Ozalp (ugurcanozalp/td3-sac-bipedal-walker-hardcore-v3,
12 observations), needs no sequence replay: the window is the stored observation, and each
sample's LSTM starts from zero state.

``agent.encoder: none`` leaves the flattened window as it is (the D2RL networks' input).
"""

from __future__ import annotations

from typing import Any

import torch
from torch import nn


class WindowLSTM(nn.Module):
    """(B, H * F) stacked window -> (B, hidden + F): [h_H, o_t].

    With x_s the s-th observation of the window (s = 1 oldest, s = H newest), h_0 = c_0 = 0::

        i_s = sigmoid(W_ii x_s + b_ii + W_hi h_{s-1} + b_hi)
        f_s = sigmoid(W_if x_s + b_if + W_hf h_{s-1} + b_hf)
        g_s = tanh(W_ig x_s + b_ig + W_hg h_{s-1} + b_hg)
        o_s = sigmoid(W_io x_s + b_io + W_ho h_{s-1} + b_ho)
        c_s = f_s * c_{s-1} + i_s * g_s
        h_s = o_s * tanh(c_s)

    (``torch.nn.LSTM``'s equations and gate order i, f, g, o.) The newest observation o_t = x_H
    is passed on unchanged beside h_H, so the dense network reads the present exactly and the
    LSTM adds what the window says about the past.
    """

    def __init__(self, history: int, frame_dim: int, hidden: int) -> None:
        super().__init__()
        self.history, self.frame_dim, self.hidden = history, frame_dim, hidden
        self.lstm = nn.LSTM(frame_dim, hidden, batch_first=True)
        self.out_dim = hidden + frame_dim

    def forward(self, window: torch.Tensor) -> torch.Tensor:
        frames = window.view(window.shape[0], self.history, self.frame_dim)  # (B, H, F)
        _, (h_last, _) = self.lstm(frames)  # h_last: (1, B, hidden)
        return torch.cat([h_last[0], frames[:, -1]], dim=-1)  # (B, hidden + F)


def make_encoder(cfg: Any, obs_dim: int) -> WindowLSTM | None:
    """The encoder of an :class:`~bipedal_cli.config.AgentConfig` for inputs of ``obs_dim``
    (H * F) floats; None for ``encoder: none``."""
    if cfg.encoder == "none":
        return None
    return WindowLSTM(cfg.history, obs_dim // cfg.history, cfg.encoder_hidden)
