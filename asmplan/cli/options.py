"""Option ranges and choices shared by the commands (derived from the domain, never copied).

Every numeric option has a range: a value outside it is the one-line usage error
``asmplan: error: Invalid value for '--seed': ...`` and exit 2.
"""

from __future__ import annotations

import math
from pathlib import Path

import typer

from asmplan.cli.app import choices
from asp.game.rules import COST_MODELS
from asp.spec import TURN_MODELS

SEED_MAX = 2**32 - 1
"""Seeds are 32-bit: numpy, torch and CP-SAT all accept them."""
GAMES_MAX = 1_000_000
"""Simulated random-human games per evaluation (about 100 bytes each: 1,000,000 is 100 MB)."""
TIME_LIMIT_MAX = 86_400.0
"""CP-SAT time limit: at most a day."""
WORKERS_MAX = 1_024
MEMORY_MAX_GB = 1e6
"""``--max-memory``: at most a million GB (a petabyte; the bound only keeps it a number)."""

CostModel = choices("CostModel", COST_MODELS, "Cost of a move.")
TurnModel = choices("TurnModel", TURN_MODELS, "Turn model of the game.")


def time_limit_option(
    default: float | None,
    help: str = "CP-SAT time limit, search seconds: its deterministic time, about a second of "
    "one core's search each, so the same answer at any load (the wall clock stops it only as "
    "a safety net, at 3x + 30 s).",
):
    """``--time-limit``: one definition for every command that runs CP-SAT (``help`` says
    what the default does when it is not a number)."""
    return typer.Option(default, "--time-limit", min=0.001, max=TIME_LIMIT_MAX, help=help)


def max_memory_option(help: str):
    """``--max-memory``, GB (0.001 to :data:`MEMORY_MAX_GB`): one definition for every
    command that bounds its memory; ``help`` says what it bounds and the default."""
    return typer.Option(None, "--max-memory", min=0.001, max=MEMORY_MAX_GB, help=help)


MAX_STATES_HELP = "State graph limit (default: spec's, else 20,000,000)."
"""Help of ``--max-states``: its default is :data:`asp.graph.state_graph.DEFAULT_MAX_STATES`
(not imported: the commands import the library only when they run; a test holds the two
equal)."""


def max_states_option():
    """``--max-states``: the state graph's limit (at least 1; default None: the spec's), one
    definition for every command that builds a state graph."""
    return typer.Option(None, "--max-states", min=1, help=MAX_STATES_HELP)


def seed_option(help: str, default: int | None = 0):
    """``--seed``: one definition (a 32-bit seed, :data:`SEED_MAX`) for every command; ``help``
    says what it seeds."""
    return typer.Option(default, "--seed", min=0, max=SEED_MAX, help=help)


def _tolerance(name: str):
    def check(value: float | None) -> float | None:
        from cad.tolerances import checked_tolerance

        try:
            return checked_tolerance(value, name)
        except ValueError as exc:
            raise typer.BadParameter(str(exc).partition(": ")[2]) from None

    return check


TOLERANCE_HELP = {
    "contact_tol": "Contact tolerance in mm for every pair: the largest gap that counts as "
    "touching (default: the spec's contact_tol, else per pair 2% of the smaller part's "
    "bounding-box diagonal, 0.01 to 0.2 mm, so clearance fits touch; cad/tolerances.py).",
    "penetration_tol": "Penetration tolerance in mm for every pair: the largest overlap that "
    "counts as touching (default: the spec's penetration_tol, else per part, scaled with its "
    "size and thickness, a pair gets the sum, at most 0.5 mm; cad/tolerances.py).",
}
"""Help of ``--contact-tol`` and ``--penetration-tol`` (the spec keys of the same names)."""


def tolerance_option(name: str):
    """``--contact-tol`` or ``--penetration-tol`` (``name``: the spec key): one definition
    for every command that computes relations."""
    return typer.Option(
        None, "--" + name.replace("_", "-"), callback=_tolerance(name), help=TOLERANCE_HELP[name]
    )


def turn_model_option(help: str):
    """``--turn-model`` (:data:`TurnModel`, default None: the spec's); ``help`` says what it
    chooses for that command."""
    return typer.Option(None, "--turn-model", help=help)


def finite_or_none(value: float | None) -> float | None:
    """Typer callback: a float option must be a finite number >= 0 (``nan``, ``inf`` fail)."""
    if value is not None and not (math.isfinite(value) and value >= 0):
        raise typer.BadParameter(f"expected a finite number >= 0, got {value}")
    return value


def check_output(path: Path | None, *, folder: bool) -> None:
    """Fail before any work when ``path`` cannot be written (a command's ``--output``).

    Raises ``NotADirectoryError``/``IsADirectoryError`` naming the path: a folder wanted
    where a file is, a file wanted where a folder is, or a file on the way to either.
    """
    if path is None:
        return
    if path.exists():
        if folder and not path.is_dir():
            raise NotADirectoryError(f"{path}: --output exists and is not a folder")
        if not folder and path.is_dir():
            raise IsADirectoryError(f"{path}: --output is a folder, expected a file name")
        return
    for parent in path.parents:
        if parent.exists():
            if not parent.is_dir():
                raise NotADirectoryError(f"{path}: --output lies under {parent}, a file")
            return


def units_option():
    """``--units``: the length unit of mesh files that declare none (STL, OBJ, PLY)."""
    return typer.Option(
        None,
        "--units",
        help="Unit of mesh files that declare none (STL, OBJ, PLY): mm, cm, m, in, ... "
        "(default: the spec's, else mm).",
    )


def gravity_option():
    """``--gravity``: the direction of gravity in the build frame, overruling the choice."""
    return typer.Option(
        None,
        "--gravity",
        help="Direction of gravity (+x -x +y -y +z -z) in the build frame; overrules the "
        "spec's, and the choice a generated spec makes from the geometry.",
    )
