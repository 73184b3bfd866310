"""Figure 11 of the paper: training rewards of the robot and the human per episode.

Drawn on a :class:`matplotlib.figure.Figure` (no pyplot, no global backend), so it is safe
to call from any library code, thread or process.
"""

from __future__ import annotations

import io
import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from asp.atomic import write_bytes

COLORS = {"robot": "tab:blue", "human": "tab:orange"}
MOVING_AVERAGE = 50


def moving_average(values: np.ndarray, window: int = MOVING_AVERAGE) -> np.ndarray:
    """Trailing moving average; the first ``window - 1`` points average what there is."""
    values = np.asarray(values, dtype=np.float64)
    if values.size == 0:
        return values
    csum = np.cumsum(np.insert(values, 0, 0.0))
    idx = np.arange(1, values.size + 1)
    lo = np.maximum(idx - window, 0)
    return (csum[idx] - csum[lo]) / (idx - lo)


def rewards_png(
    episode_rewards: Mapping[str, Sequence[float]],
    title: str = "Training rewards (alternating PPO)",
    window: int = MOVING_AVERAGE,
) -> bytes:
    """PNG of per-episode rewards (faint) and their ``window``-episode moving averages.

    Parameters
    ----------
    episode_rewards : mapping
        ``{"robot": [...], "human": [...]}`` in episode order.
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(9, 4.8))
    ax = fig.subplots()
    for agent, color in COLORS.items():
        rewards = np.asarray(episode_rewards.get(agent, ()), dtype=np.float64)
        if rewards.size == 0:
            continue
        x = np.arange(1, rewards.size + 1)
        ax.plot(x, rewards, color=color, alpha=0.18, linewidth=0.6)
        label = f"{agent.capitalize()} agent (MA {window})"
        ax.plot(x, moving_average(rewards, window), color=color, linewidth=2, label=label)
    ax.set_xlabel("Episode (of the agent's training)")
    ax.set_ylabel("Episode reward")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="best")
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=120, bbox_inches="tight")
    return buffer.getvalue()


def plot_rewards(
    episode_rewards: Mapping[str, Sequence[float]],
    path: str | os.PathLike[str],
    window: int = MOVING_AVERAGE,
    title: str = "Training rewards (alternating PPO)",
) -> Path:
    """Write :func:`rewards_png` to ``path`` atomically; return the path."""
    return write_bytes(path, rewards_png(episode_rewards, title, window))
