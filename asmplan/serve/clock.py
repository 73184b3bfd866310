"""The real-time clock of a session: operations take their durations in wall-clock time.

In a real-time session (``asmplan serve --realtime SPEED``, or a study's ``realtime:
{speed}``) the game clock runs at ``speed`` game seconds per wall-clock second from the
session's last event, and the service itself finishes operations when their time comes: a
robot's, and the person's own (the page shows them running; nobody clicks "R2 finishes").
The person only starts operations.

The game decides at events (the start and each completion), so the clock *holds* while a
free person must choose what to start (the concurrent game: a person with something to do
never idles unless told to wait; the alternating game: the person's turn): the time she
takes to choose is her decision time, kept in the record as the wall-clock gap between the
event and her start, not added to the makespan. When she is told to wait, the clock runs.

:func:`due` says which completion is due at a wall-clock time; the store takes it as an
event (``source: clock``, recorded at the wall-clock time it fell due), so a restart goes on
from the same place. :func:`clock_view` is the session's ``clock`` in the API.
"""

from __future__ import annotations

from asp.game.turns import turn_of


def _anchor(session) -> tuple[float, float]:
    """(wall-clock time, game time) of the session's last event (its creation at first)."""
    wall = session.events[-1]["t"] if session.events else session.created
    return wall, float(session.current().elapsed)


def _next(session) -> tuple[dict | None, float | None, bool]:
    """The next event the clock makes (with its game time; None: none), and whether the
    clock holds for the person's choice."""
    advice = session.current()
    if advice.finished:
        return None, None, False
    if turn_of(advice.turn_model).simultaneous:  # the game advances by completions
        if not advice.finishes:
            return None, None, bool(advice.options)
        f = min(advice.finishes, key=lambda x: (x["time"], x["operation"], x["agent"]))
        event = {"kind": "finished", "operation": f["operation"], "agent": f["agent"]}
        return {**event, "time": f["time"], "source": "clock"}, float(f["time"]), False
    if advice.running:
        r = advice.running[-1]
        event = {"kind": "finished", "operation": r["operation"], "agent": r["agent"]}
        return {**event, "source": "clock"}, advice.elapsed + float(r["remaining"]), False
    if advice.turn == "robot" and advice.robots:
        r = advice.robots[0]
        event = {"kind": "started", "operation": r["operation"], "agent": r["agent"]}
        return {**event, "source": "clock"}, float(advice.elapsed), False
    return None, None, True


def due(session, now: float) -> tuple[dict | None, float | None]:
    """The clock's next event if due by wall-clock time ``now``, with the wall-clock time it
    fell due; ``(None, None)`` if nothing is due (or the clock holds)."""
    event, at_game, _ = _next(session)
    if event is None:
        return None, None
    wall, game = _anchor(session)
    at_wall = wall + max(0.0, at_game - game) / session.speed
    if at_wall > now:
        return None, None
    return event, at_wall


def clock_view(session, now: float) -> dict | None:
    """``{"speed", "game_time", "holding", "next": {"operation", "agent", "time", "wall"}}``
    of a real-time session (None for another): the game time now, whether the clock waits
    for the person, and the next completion the clock will make."""
    if session.speed is None:
        return None
    wall, game = _anchor(session)
    event, at_game, holding = _next(session)
    game_now = game if holding or session.finished_at else game + (now - wall) * session.speed
    nxt = None
    if event is not None:
        game_now = min(game_now, at_game)
        nxt = {
            "kind": event["kind"],
            "operation": event["operation"],
            "agent": event["agent"],
            "time": at_game,
            "wall": wall + max(0.0, at_game - game) / session.speed,
        }
    return {"speed": session.speed, "game_time": game_now, "holding": holding, "next": nxt}
