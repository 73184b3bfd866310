"""How long a training takes: a cycle's estimate before training, a limit on it, and a
heartbeat while it runs.

One rule for both trainers: the alternating one (:func:`arl.trainer.train`) and the one on
the concurrent game's rules (:func:`arl.concurrent_trainer.train_concurrent`). Each measures
its own sample (throwaway models, :data:`SAMPLE_STEPS` game steps, the check of a cycle) and
gives a :class:`CycleEstimate`; what the estimate says, the refusal over
``--max-cycle-seconds`` and the heartbeat's line are written here once.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass

from asp.errors import GameError

HEARTBEAT_S = 60.0
"""Seconds between two lines of a training's heartbeat (:class:`Heartbeat`)."""

SAMPLE_STEPS = 256
"""Game steps of the sample a cycle's seconds are estimated from."""


def duration(seconds: float) -> str:
    """``40 ms``, ``0.4 s``, ``12 s``, ``7.5 min``, ``3.2 h``."""
    if seconds < 0.1:
        return f"{1000 * seconds:.0f} ms"
    if seconds < 10:
        return f"{seconds:.1f} s"
    if seconds < 600:
        return f"{seconds:.0f} s"
    return f"{seconds / 60:.1f} min" if seconds < 3 * 3600 else f"{seconds / 3600:.1f} h"


def phase_seconds(phase_steps: int, rollout: int, step_s: float) -> float:
    """Seconds of a phase of ``phase_steps`` game steps, rounded up to whole rollouts of
    ``rollout`` steps (as PPO does), at ``step_s`` seconds a step."""
    return -(-int(phase_steps) // int(rollout)) * int(rollout) * step_s


@dataclass(frozen=True)
class CycleEstimate:
    """The estimated seconds of a training cycle.

    Attributes
    ----------
    seconds : float
        One cycle: every learner's phase and the cycle's check.
    step_s : float
        One game step of PPO (rollout and updates), measured on the sample.
    sample_steps : int
        Game steps of the sample.
    cycles : int
        The cycles still allowed (the run's cycles less those done).
    size : str
        The game's size (``9,436 nodes, 30,000 edges``; ``12 operations, 3 workers``).
    check_s : float
        The measured part of the cycle's check (``check`` says what it is).
    check : str
        ``a tabulation of every node``, ``a certification (exact best response)``.
    """

    seconds: float
    step_s: float
    sample_steps: int
    cycles: int
    size: str
    check_s: float
    check: str

    def text(self) -> str:
        """``about 12 s a cycle (...), up to 20 min for 100 cycles``: one clause."""
        return (
            f"about {duration(self.seconds)} a cycle ({self.size}; {1000 * self.step_s:.2f} ms "
            f"a game step over a sample of {self.sample_steps:,}, {duration(self.check_s)} "
            f"{self.check}), up to {duration(self.cycles * self.seconds)} for "
            f"{self.cycles:,} cycle{'s' if self.cycles != 1 else ''}"
        )

    def refuse_over(self, max_cycle_seconds: float | None) -> None:
        """Raise :class:`asp.errors.GameError` (one line) when a cycle is estimated to take
        longer than ``max_cycle_seconds`` (None: no limit)."""
        if max_cycle_seconds is not None and self.seconds > max_cycle_seconds:
            raise GameError(
                f"training this game takes {self.text()}, over --max-cycle-seconds "
                f"{max_cycle_seconds:g} (max_cycle_seconds): raise it, or train a smaller game"
            )


class Heartbeat:
    """A line to ``say`` every :data:`HEARTBEAT_S` seconds while a run trains (a daemon
    thread; :meth:`line`: what the run is doing and the time so far).

    Parameters
    ----------
    say : callable or None
        Where the line goes (None: no heartbeat).
    elapsed : callable
        The run's seconds so far.
    doing : callable, optional
        What the run is doing now; without it, the attribute :attr:`doing`, which the
        trainer sets as it goes.
    """

    def __init__(
        self,
        say: Callable[[str], None] | None,
        elapsed: Callable[[], float],
        doing: Callable[[], str] | None = None,
    ) -> None:
        self.say, self.elapsed, self._doing = say, elapsed, doing
        self.doing = "starting"
        self._stop = threading.Event()
        self._thread = None

    def line(self) -> str:
        doing = self._doing() if self._doing is not None else self.doing
        return f"training: {doing}, {duration(self.elapsed())} so far"

    def start(self) -> None:
        if self.say is not None and self._thread is None:
            self._thread = threading.Thread(target=self._beat, daemon=True, name="heartbeat")
            self._thread.start()

    def _beat(self) -> None:
        while not self._stop.wait(HEARTBEAT_S):
            self.say(self.line())

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()

    def __enter__(self) -> Heartbeat:
        self.start()
        return self

    def __exit__(self, *exc) -> None:
        self.stop()


__all__ = [
    "HEARTBEAT_S",
    "SAMPLE_STEPS",
    "CycleEstimate",
    "Heartbeat",
    "duration",
    "phase_seconds",
]
