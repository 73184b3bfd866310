"""The turn models of the game, one entry each: what differs between them, named once.

A turn model says how the robots and the person take turns (``assembly.yaml``'s
``turn_model``, ``--turn-model``, ``plan.json``'s ``turn_model``). Code that behaves by turn
model looks its :class:`TurnModel` up (:func:`turn_of`) and reads a field, or compares with
``ALTERNATE.name`` / ``CONCURRENT.name`` where a field would be contrived; no other module
compares with a name written out (the layer test). Adding a game model means one entry here
plus its modules, an entry in each lookup above ``asp`` that names a model's classes and
functions (``asmplan.advisor.ADVISORS``, ``asmplan.cli.train.TRAINING_GAMES``) and a branch of
``asmplan.pipeline.plan``.

The entries name no functions: this room is the game DAG's (no assembly spec), the floor the
spec, the state graph and the concurrent game stand on, and the concurrent game's builder and
search live floors above (:mod:`asp.concurrent`); the layers that call them key their own
lookups by the entry's ``name``.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class TurnModel:
    """One turn model of the game.

    Attributes
    ----------
    name : str
        Its name in ``assembly.yaml``, on the command line and in ``plan.json``.
    game_file : bool
        Its game can be a game DAG file (JSON, GraphML, :mod:`asp.game.io`) and is solved by
        :func:`asp.game.solve.solve`: the sides move in turn, one operation per move.
    simultaneous : bool
        The sides work at once: operations run together, the game advances by completions
        and time passes on the person's replies (a runtime clock follows completions; the
        paper's per-move rewards of :mod:`arl.trainer` do not apply).
    move_columns : tuple of str
        The columns of ``plan.json``'s ``policy.moves`` that name what a move starts, besides
        ``ptr``, ``cost`` and ``next``.
    plan_curve : bool
        Its plan document holds the curve ``W*(k)`` itself (``robustness``, ``concurrent``,
        ``schedule``); else the plan's ``concurrent_preview`` holds it.
    plan_id_suffix : str
        Added to a plan's id in the advisor service (``vacuum-pump-concurrent``).
    """

    name: str
    game_file: bool
    simultaneous: bool
    move_columns: tuple[str, ...]
    plan_curve: bool
    plan_id_suffix: str


ALTERNATE = TurnModel(
    name="alternate",
    game_file=True,
    simultaneous=False,
    move_columns=("operation", "agent"),
    plan_curve=False,
    plan_id_suffix="",
)
"""Robots and person move in turn, one operation per move (the game DAG, :mod:`asp.game`)."""

CONCURRENT = TurnModel(
    name="concurrent",
    game_file=False,
    simultaneous=True,
    move_columns=("starts", "deviations"),
    plan_curve=True,
    plan_id_suffix="-concurrent",
)
"""Robots and person work at once, the person within a deviation budget (:mod:`asp.concurrent`)."""

TURNS: dict[str, TurnModel] = {t.name: t for t in (ALTERNATE, CONCURRENT)}
"""Every turn model by name, the default first."""

DEFAULT_TURN = ALTERNATE
"""The turn model of a spec that names none."""


def turn_of(name) -> TurnModel:
    """The turn model named ``name``; None or a name not in :data:`TURNS` (a document that
    names none): the default's behaviour, as before the registry."""
    return TURNS.get(name, DEFAULT_TURN) if isinstance(name, str) else DEFAULT_TURN


def expected_names(quote: bool = False) -> str:
    """``alternate or concurrent`` (``quote``: ``'alternate' or 'concurrent'``), for an error
    that refuses another name."""
    return " or ".join(repr(n) if quote else n for n in TURNS)
