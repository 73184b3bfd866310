"""Figure 11 of the paper: training rewards of the robot and the human per episode."""

from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np

from asp.atomic import write_bytes

COLORS = {"robot": "tab:blue", "human": "tab:orange"}


def moving_average(values: np.ndarray, window: int = 50) -> np.ndarray:
    """Trailing moving average; the first ``window - 1`` points average what there is."""
    values = np.asarray(values, dtype=np.float64)
    if values.size == 0:
        return values
    csum = np.cumsum(np.insert(values, 0, 0.0))
    idx = np.arange(1, values.size + 1)
    lo = np.maximum(idx - window, 0)
    return (csum[idx] - csum[lo]) / (idx - lo)


def plot_rewards(
    episode_rewards: dict[str, list[float]],
    path: str | os.PathLike[str],
    window: int = 50,
    title: str = "Training rewards (alternating PPO)",
) -> Path:
    """Plot per-episode rewards (faint) and their ``window``-episode moving averages.

    Parameters
    ----------
    episode_rewards : dict
        ``{"robot": [...], "human": [...]}`` in episode order.
    path : path-like
        PNG file, written atomically.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4.5))
    try:
        for agent, rewards in episode_rewards.items():
            if not len(rewards):
                continue
            x = np.arange(1, len(rewards) + 1)
            color = COLORS.get(agent)
            ax.plot(x, rewards, color=color, alpha=0.15, linewidth=0.6)
            label = f"{agent.capitalize()} (MA {window})"
            ax.plot(x, moving_average(rewards, window), color=color, linewidth=2, label=label)
        ax.set_xlabel("Episode (of the agent's training)")
        ax.set_ylabel("Episode reward")
        ax.set_title(title)
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend()
        buffer = io.BytesIO()
        fig.savefig(buffer, format="png", dpi=120, bbox_inches="tight")
    finally:
        plt.close(fig)
    return write_bytes(path, buffer.getvalue())
