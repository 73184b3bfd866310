"""A person playing one side of the game against the computer: pure session logic, no I/O.

:class:`GameSession` keeps the game state ``(node, player on turn)`` and the cost so far
(``../shared/DESIGN.md``, "The game": alternate turns, robot first, a side with no move
passes at zero cost). The person plays either side:

- the **human** side against a robot policy (the robust policy W* by default, the
  cooperative fastest path ``fast-greedy``, or any ``(n,)`` policy array, e.g. a trained
  one). The worst case shown is the robot policy's exact certified worst case
  (:func:`asp.game.solve.evaluate_policy`); for the robust robot it is the game value.
- the **robot** side against a best-response human (the exact maximiser). The worst case
  shown is the game value: what a perfect robot can still guarantee from the state.

Worst-case and cooperative figures are exact (backward induction), never sampled.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from asp.errors import GameError
from asp.game import rules
from asp.game.dag import GameDAG
from asp.game.rules import HUMAN, ROBOT, cost_at_most, costs_close
from asp.game.solve import NO_MOVE, Solution, as_policy_array, evaluate_policy, solve
from asp.numbers import cost_text

ROBOT_KINDS = ("robust", "fast-greedy")
"""Named robot policies; anything else is given as a policy array."""


def side_name(player: int) -> str:
    return rules.player_name(player)


def fmt(x: float) -> str:
    """A cost as text: ``3`` rather than ``3.0``."""
    return cost_text(x)


def fast_greedy_policy(dag: GameDAG, solution: Solution) -> np.ndarray:
    """The robot that follows the cooperative fastest path: at each node it takes the move
    minimising ``cost + coop`` (ties by lower move index), trusting the human to help."""
    policy = np.full(dag.n_nodes, NO_MOVE, dtype=np.int64)
    ok = np.flatnonzero(rules.move_mask(dag, ROBOT))
    if ok.size == 0:
        return policy
    src = dag.sources[ok]
    val = np.round(rules.move_costs(dag, ok) + solution.coop[dag.targets[ok], HUMAN], 9)
    order = np.lexsort((ok, val, src))
    first = np.ones(order.size, dtype=bool)
    first[1:] = src[order][1:] != src[order][:-1]
    policy[src[order][first]] = ok[order][first]
    return policy


@dataclass(frozen=True)
class Move:
    """A move open to the player on turn.

    Attributes
    ----------
    number : int
        The number the person types (1-based, in edge order).
    edge : int
        Edge index in the DAG.
    target : int
        Node index the move leads to (``target_id`` its original id).
    cost : float
    operation, agent, description : str
        Labels where the DAG / assembly knows them (else ``""``).
    worst_remaining : float
        Guaranteed worst-case cost from the current state if this move is taken
        (including its own cost): ``cost + worst(target, other side)``.
    coop_remaining : float
        Cooperative best cost from the current state through this move.
    """

    number: int
    edge: int
    target: int
    target_id: object
    cost: float
    operation: str
    agent: str
    description: str
    worst_remaining: float
    coop_remaining: float

    @property
    def label(self) -> str:
        """``operation agent description``, or ``to node X`` on an unlabelled graph."""
        parts = [p for p in (self.operation, self.agent, self.description) if p]
        return " ".join(parts) if parts else f"to node {self.target_id}"


@dataclass(frozen=True)
class Turn:
    """One played turn.

    ``move`` is ``None`` for a pass. ``by`` is ``"person"`` or ``"computer"`` (a pass is the
    computer's bookkeeping). ``worst_before`` / ``worst_after`` are guaranteed worst-case
    totals (cost so far included) before and after the turn; ``reason`` explains a computer
    move in words.
    """

    step: int
    player: int
    node: int
    node_id: object
    move: Move | None
    by: str
    cost_before: float
    worst_before: float
    worst_after: float
    reason: str = ""

    @property
    def passed(self) -> bool:
        return self.move is None


@dataclass(frozen=True)
class Summary:
    """The outcome of a session (finished or quit)."""

    finished: bool
    person: int
    robot: str
    cost: float
    tct: float
    minimax: float
    robot_worst: float
    steps: int
    held: bool | None
    person_slips: tuple[tuple[int, str, float], ...]

    def lines(self) -> list[str]:
        """The summary as text lines (the CLI prints them)."""
        out = []
        if not self.finished:
            out.append(
                f"game not finished (quit after {_turns(self.steps)}): cost so far {fmt(self.cost)}"
            )
        else:
            out.append(f"game over after {_turns(self.steps)}: total cost {fmt(self.cost)}")
        out.append(f"TCT (both cooperate) {fmt(self.tct)}, W* (robust minimax) {fmt(self.minimax)}")
        if self.person == HUMAN:
            if self.robot != "robust":
                out.append(
                    f"the {self.robot} robot's certified worst case: "
                    f"{fmt(self.robot_worst)} (W* {fmt(self.minimax)})"
                )
            if self.held is not None:
                bound = "W*" if self.robot == "robust" else "its worst case"
                verdict = "held" if self.held else "BROKEN"
                out.append(
                    f"the robot's guarantee {verdict}: cost {fmt(self.cost)} "
                    f"{'<=' if self.held else '>'} {bound} {fmt(self.robot_worst)}"
                )
        else:
            if self.finished:
                gap = self.cost - self.minimax
                if cost_at_most(self.cost, self.minimax):
                    out.append(f"you matched the robust robot: cost {fmt(self.cost)} = W*")
                else:
                    out.append(
                        f"a robust robot holds this human to W* {fmt(self.minimax)}; "
                        f"your choices cost {fmt(gap)} more"
                    )
            for step, what, loss in self.person_slips:
                out.append(f"  step {step}: {what} raised the worst case by {fmt(loss)}")
        return out


class GameSession:
    """One game between a person and the computer.

    Parameters
    ----------
    dag : GameDAG
    person : int
        The side the person plays: ``HUMAN`` (default) or ``ROBOT``.
    robot : str or (n,) int array
        The computer robot when the person plays the human: ``"robust"``, ``"fast-greedy"``
        or a policy array (edge index per node; see :func:`asp.game.solve.as_policy_array`).
    robot_name : str, optional
        Name shown for a policy array (default ``"given"``).
    descriptions : dict, optional
        Operation id -> description.
    seed : int, optional
        When the person plays the robot, the best-response human breaks ties between equally
        delaying moves at random with this seed (default: lowest move index).
    solution : Solution, optional
        A precomputed :func:`asp.game.solve.solve` of ``dag``.
    """

    def __init__(
        self,
        dag: GameDAG,
        *,
        person: int = HUMAN,
        robot: str | np.ndarray = "robust",
        robot_name: str | None = None,
        descriptions: dict[str, str] | None = None,
        seed: int | None = None,
        solution: Solution | None = None,
    ) -> None:
        if person not in (ROBOT, HUMAN):
            raise GameError(f"person: expected {ROBOT} (robot) or {HUMAN} (human), got {person}")
        self.dag = dag
        self.person = person
        self.solution = solution if solution is not None else solve(dag)
        self.descriptions = dict(descriptions or {})
        self._rng = None if seed is None else np.random.default_rng(seed)
        if isinstance(robot, str):
            if robot == "robust":
                policy = self.solution.robot_policy
            elif robot == "fast-greedy":
                policy = fast_greedy_policy(dag, self.solution)
            else:
                raise GameError(
                    f"robot: expected one of {', '.join(ROBOT_KINDS)} or a policy, got {robot!r}"
                )
            self.robot_name = robot
        else:
            policy = as_policy_array(dag, robot)
            self.robot_name = robot_name or "given"
        self.robot_policy = policy
        if person == HUMAN:
            self.evaluation = evaluate_policy(dag, policy)  # raises on an invalid policy
            self.worst_table = self.evaluation.worst
        else:
            self.evaluation = None
            self.worst_table = self.solution.value
        self.node = dag.start
        self.player = rules.FIRST_PLAYER
        self.cost = 0.0
        self.history: list[Turn] = []

    # ------------------------------------------------------------------ state
    @property
    def finished(self) -> bool:
        return self.node == self.dag.end

    @property
    def node_id(self):
        return self.dag.node_ids[self.node]

    @property
    def node_label(self) -> str:
        """The node's readable label (assemblies: operations done and tool states) or ``""``."""
        labels = self.dag.node_labels
        return labels[self.node] if labels is not None else ""

    @property
    def persons_turn(self) -> bool:
        """True when the person must choose a move now."""
        return not self.finished and self.player == self.person and bool(self._edges())

    @property
    def worst_remaining(self) -> float:
        """Guaranteed worst-case cost from the current state to the end."""
        return float(self.worst_table[self.node, self.player])

    @property
    def minimax_remaining(self) -> float:
        """The game value (W* of the current state)."""
        return float(self.solution.value[self.node, self.player])

    @property
    def coop_remaining(self) -> float:
        """Cooperative best cost from the current state to the end."""
        return float(self.solution.coop[self.node, self.player])

    def _edges(self) -> list[int]:
        return rules.moves(self.dag, self.node, self.player)

    def moves(self) -> list[Move]:
        """The moves open to the player on turn (empty: it must pass, or the game is over)."""
        dag, other = self.dag, rules.other(self.player)
        out = []
        for k, e in enumerate(self._edges(), start=1):
            t = int(dag.targets[e])
            c = rules.move_cost(dag, e)
            op = dag.operations[e] if dag.operations is not None else ""
            out.append(
                Move(
                    number=k,
                    edge=e,
                    target=t,
                    target_id=dag.node_ids[t],
                    cost=c,
                    operation=op,
                    agent=dag.agents[e] if dag.agents is not None else "",
                    description=self.descriptions.get(op, ""),
                    worst_remaining=c + float(self.worst_table[t, other]),
                    coop_remaining=c + float(self.solution.coop[t, other]),
                )
            )
        return out

    # ------------------------------------------------------------------ moves
    def play(self, number: int) -> Turn:
        """The person takes move ``number`` (1-based, as listed by :meth:`moves`)."""
        if not self.persons_turn:
            raise GameError("it is not the person's turn")
        moves = self.moves()
        if not 1 <= number <= len(moves):
            raise GameError(f"move: expected a number from 1 to {len(moves)}, got {number}")
        move = moves[number - 1]
        return self._apply(move, by="person", reason="")

    def step(self) -> Turn:
        """The computer's turn: a pass (either side) or the computer side's move."""
        if self.finished:
            raise GameError("the game is over")
        if self.persons_turn:
            raise GameError("it is the person's turn: call play()")
        moves = self.moves()
        if not moves:
            return self._pass()
        edge = self._computer_edge(moves)
        move = next(m for m in moves if m.edge == edge)
        return self._apply(move, by="computer", reason=self._reason(move, moves))

    def advance(self) -> list[Turn]:
        """Play passes and computer moves until the person must choose or the game ends."""
        turns = []
        while not self.finished and not self.persons_turn:
            turns.append(self.step())
        return turns

    def _pass(self) -> Turn:
        worst = self.cost + self.worst_remaining
        turn = Turn(
            step=len(self.history) + 1,
            player=self.player,
            node=self.node,
            node_id=self.node_id,
            move=None,
            by="computer",
            cost_before=self.cost,
            worst_before=worst,
            worst_after=worst,
            reason=f"the {side_name(self.player)} has no move it may do: passes at zero cost",
        )
        self.history.append(turn)
        self.node, self.player, cost = rules.step(self.dag, self.node, self.player, rules.PASS)
        self.cost += cost
        return turn

    def _apply(self, move: Move, *, by: str, reason: str) -> Turn:
        turn = Turn(
            step=len(self.history) + 1,
            player=self.player,
            node=self.node,
            node_id=self.node_id,
            move=move,
            by=by,
            cost_before=self.cost,
            worst_before=self.cost + self.worst_remaining,
            worst_after=self.cost + move.worst_remaining,
            reason=reason,
        )
        self.history.append(turn)
        self.node, self.player, cost = rules.step(self.dag, self.node, self.player, move.edge)
        self.cost += cost
        return turn

    def _computer_edge(self, moves: list[Move]) -> int:
        if self.player == ROBOT:
            edge = int(self.robot_policy[self.node])
            if edge not in {m.edge for m in moves}:
                raise GameError(
                    f"robot policy has no valid move at node {self.node_id!r} (got edge {edge})"
                )
            return edge
        # The best-response human: maximise the guaranteed worst case.
        best = max(m.worst_remaining for m in moves)
        ties = [m.edge for m in moves if costs_close(m.worst_remaining, best)]
        if self._rng is None or len(ties) == 1:
            return ties[0]
        return int(ties[int(self._rng.integers(len(ties)))])

    def _reason(self, move: Move, moves: list[Move]) -> str:
        total = self.cost + move.worst_remaining
        others = [m for m in moves if m.edge != move.edge]
        if self.player == HUMAN:
            text = f"delays as much as it can: the worst case becomes {fmt(total)}"
            if others:
                lowest = min(m.worst_remaining for m in others)
                if not cost_at_most(move.worst_remaining, lowest):
                    text += f" (other moves allow as little as {fmt(self.cost + lowest)})"
            return text
        alt = min(others, key=lambda m: m.worst_remaining, default=None)
        if self.robot_name == "robust":
            text = f"keeps the worst case at {fmt(total)}"
            if alt is not None and not cost_at_most(alt.worst_remaining, move.worst_remaining):
                text += f" ({alt.label} would allow up to {fmt(self.cost + alt.worst_remaining)})"
            elif alt is not None:
                ex = self.solution.expected
                tied = [m for m in moves if costs_close(m.worst_remaining, move.worst_remaining)]
                exp = {m.edge: m.cost + float(ex[m.target, HUMAN]) for m in tied}
                if not costs_close(max(exp.values()), min(exp.values())):
                    best = fmt(round(self.cost + exp[move.edge], 3))
                    text += (
                        f"; of {len(tied)} such moves it has the lowest expected cost "
                        f"against a random human ({best})"
                    )
                elif len(tied) == len(moves):
                    text += " (every move open to it keeps that)"
            return text
        if self.robot_name == "fast-greedy":
            fast = fmt(self.cost + move.coop_remaining)
            return (
                f"takes the cooperative fastest path (best case {fast}); "
                f"its worst case is {fmt(total)}, W* from here "
                f"{fmt(self.cost + self.minimax_remaining)}"
            )
        return (
            f"the {self.robot_name} policy's choice; its worst case is {fmt(total)}, "
            f"W* from here {fmt(self.cost + self.minimax_remaining)}"
        )

    # ---------------------------------------------------------------- summary
    def summary(self) -> Summary:
        sol = self.solution
        if self.evaluation is not None:
            robot_worst = float(self.evaluation.worst[self.dag.start, ROBOT])
        else:
            robot_worst = sol.minimax
        held = None
        if self.finished and self.person == HUMAN:
            held = bool(cost_at_most(self.cost, robot_worst))
        slips = tuple(
            (t.step, t.move.label, t.worst_after - t.worst_before)
            for t in self.history
            if self.person == ROBOT
            and t.by == "person"
            and t.move is not None
            and not cost_at_most(t.worst_after, t.worst_before)
        )
        return Summary(
            finished=self.finished,
            person=self.person,
            robot=self.robot_name if self.person == HUMAN else "you",
            cost=self.cost,
            tct=sol.tct,
            minimax=sol.minimax,
            robot_worst=robot_worst,
            steps=len(self.history),
            held=held,
            person_slips=slips,
        )


def _turns(k: int) -> str:
    return f"{k} turn" if k == 1 else f"{k} turns"


__all__ = [
    "ROBOT_KINDS",
    "GameSession",
    "Move",
    "Summary",
    "Turn",
    "fast_greedy_policy",
    "fmt",
    "side_name",
]
