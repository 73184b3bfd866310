"""Plans as data: the relations summary and the robust plan as a list of steps.

The robust plan is the game played by the robust robot policy against the maximising human
(both minimax, :func:`asp.game.solve.solve`), step by step, with passes shown, and at each human
turn the operations the human could choose from. Their text renderings are in
:mod:`asmplan.report.plan`.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from asp.errors import GameError
from asp.game import rules
from asp.game.dag import GameDAG
from asp.game.rules import HUMAN, ROBOT
from asp.game.solve import Solution
from asp.numbers import plain
from cad.directions import DIRECTIONS


@dataclass(frozen=True)
class PlanStep:
    """One turn of a played game.

    Attributes
    ----------
    step : int
        Turn number from 1.
    player : str
        ``robot`` or ``human`` (the side on turn).
    operation, agent, description : str
        What was done (``operation`` is ``""`` for a pass).
    cost : float
        Cost of the move (0 for a pass).
    human_options : tuple of str
        At a human turn, every operation the human could have chosen.
    node : int or str
        Game DAG node id before the move.
    """

    step: int
    player: str
    operation: str
    agent: str
    description: str
    cost: float
    human_options: tuple[str, ...]
    node: object

    def to_dict(self) -> dict:
        out = asdict(self)
        out["human_options"] = list(self.human_options)
        out["node"] = plain(self.node)
        return out


def play_steps(
    dag: GameDAG,
    robot_policy: np.ndarray,
    human_choice,
    *,
    descriptions: dict[str, str] | None = None,
) -> list[PlanStep]:
    """Play from the start; ``human_choice(v, moves) -> edge`` picks the human's edge.

    ``human_choice`` may be an ``(n,)`` policy array (edge index per node) as well.
    """
    descriptions = descriptions or {}
    if isinstance(human_choice, np.ndarray):
        policy = human_choice

        def human_choice(v, moves, policy=policy):  # noqa: ARG001 - same signature
            return int(policy[v])

    steps: list[PlanStep] = []
    v, player = dag.start, rules.FIRST_PLAYER
    for k in range(2 * dag.n_nodes + 2):
        if v == dag.end:
            return steps
        moves = rules.moves(dag, v, player)
        options: tuple[str, ...] = ()
        if player == HUMAN:
            options = tuple(dict.fromkeys(dag.edge_label(e) for e in moves))
        if not moves:
            steps.append(
                PlanStep(
                    k + 1, _side(player), "", "", "pass", rules.PASS_COST, options, dag.node_ids[v]
                )
            )
            v, player, _ = rules.step(dag, v, player, rules.PASS)
        else:
            e = int(robot_policy[v]) if player == ROBOT else int(human_choice(v, moves))
            if e not in moves:
                raise GameError(f"no valid {_side(player)} move at node {dag.node_ids[v]!r}")
            op = dag.operations[e] if dag.operations else ""
            agent = dag.agents[e] if dag.agents else ""
            steps.append(
                PlanStep(
                    k + 1,
                    _side(player),
                    op,
                    agent,
                    descriptions.get(op, ""),
                    rules.move_cost(dag, e),
                    options,
                    dag.node_ids[v],
                )
            )
            v, player, _ = rules.step(dag, v, player, e)
    raise GameError("the game did not reach the end node")


def robust_plan(
    dag: GameDAG, solution: Solution, descriptions: dict[str, str] | None = None
) -> list[PlanStep]:
    """The robust robot policy against the maximising human, step by step."""
    return play_steps(dag, solution.robot_policy, solution.human_policy, descriptions=descriptions)


def _side(player: int) -> str:
    return rules.player_name(player)


def relations_summary(relations) -> list[dict]:
    """Per part: the parts it touches (with directions) and its free directions.

    A free direction ``d`` of part ``p`` is one with ``TT_d(p, j)`` for every other part
    ``j``: ``p`` can leave the complete assembly along ``d``.
    """
    tc = np.asarray(relations.tc, dtype=bool)
    tt = np.asarray(relations.tt, dtype=bool)
    parts = tuple(str(p) for p in relations.parts)
    n = len(parts)
    out = []
    for i, p in enumerate(parts):
        contacts = {
            parts[j]: [DIRECTIONS[d] for d in range(6) if tc[i, j, d]]
            for j in range(n)
            if j != i and tc[i, j].any()
        }
        others = [j for j in range(n) if j != i]
        free = [DIRECTIONS[d] for d in range(6) if all(tt[i, j, d] for j in others)]
        out.append({"part": p, "contacts": contacts, "free": free})
    return out
