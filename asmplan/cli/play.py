"""Command ``asmplan play``: a person plays one side of the game, turn by turn.

The game logic is :class:`asp.game.play.GameSession`; this module only reads and prints. The
person types a move number or an operation id (``?`` help, ``q`` quit); end of input quits
cleanly (exit 0). ``--moves 2,1,3`` plays those first (scripted demos and tests), then reads
stdin.

Alike parts: an assembly's game is reduced by symmetry (:mod:`asp.graph.symmetry`), so its moves
name one canonical order of interchangeable operations. The moves are shown in the person's
physical operation ids with the alike ones as good (``or alike: ...``), and a typed id of any
of them plays the canonical move it maps onto (:class:`asp.game.alike.AlikeMap`).
"""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import typer

from asmplan.cli.app import app, choices
from asmplan.cli.options import CostModel, seed_option
from asp.game.rules import SIDE_NAMES, cost_at_most, costs_close
from asp.numbers import cost_unit

HELP_TEXT = """\
How to play
  Type the number of a move and press Enter; '?' shows this help, 'q' quits. You may type
  an operation id instead of its number (of alike parts, any of them: 'or alike: ...').
  The robot moves first; then the turns alternate. A side with no move it may do passes
  at zero cost. The robot minimises the total cost, the human maximises it.
  'worst' = the guaranteed worst-case total if that move is taken: the most the game can
  still cost (cost so far included) when the robot plays its policy and the human delays
  as much as possible. 'coop' = the total if both sides cooperate from there on."""


Side = choices("Side", SIDE_NAMES[:2], "The side the person plays.")


def _robot_policy(dag, robot: str):
    """``robust``/``fast-greedy`` as they are; anything else is a run folder of ``train``."""
    from asp.game.play import ROBOT_KINDS

    if robot in ROBOT_KINDS:
        return robot, robot
    run = Path(robot)
    if not run.is_dir():
        raise ValueError(
            f"--robot: expected {' or '.join(ROBOT_KINDS)} or a run folder of 'asmplan train', "
            f"got {robot!r}"
        )
    from arl.trainer import load_policies

    policy, _ = load_policies(dag, run)
    return policy, f"trained ({run.name})"


def _parse_moves(text: str | None, operations=()) -> list[str]:
    """The scripted moves: numbers, or ids of ``operations`` (the game's)."""
    if not text:
        return []
    known = set(operations)
    out = []
    for item in text.split(","):
        item = item.strip()
        if not (item.isdigit() or item in known):
            raise ValueError(
                f"--moves: expected comma-separated move numbers or operation ids, got {item!r}"
            )
        out.append(item)
    return out


class _Alike:
    """The person's physical operation ids over a game reduced by symmetry: the moves shown
    in them, a typed id mapped onto the canonical move (:class:`asp.game.alike.AlikeMap`)."""

    def __init__(self, session, classes):
        from asp.game.alike import AlikeMap

        self.session = session
        self.map = AlikeMap(classes)

    def _pattern(self, op: str) -> bool:
        return any(t.move is not None and t.move.operation == op for t in self.session.history)

    def move(self, move):
        """``move`` naming its physical operation, with the alike ones as good."""
        if move is None or not self.map or not move.operation:
            return move
        op = self.map.physical(move.operation)
        alike = self.map.alike(move.operation, self._pattern)
        note = f" (or alike: {', '.join(alike[1:])})" if len(alike) > 1 else ""
        description = self.session.descriptions.get(op, move.description) + note
        return replace(move, operation=op, description=description.strip())

    def turn(self, turn):
        return turn if turn.move is None else replace(turn, move=self.move(turn.move))

    def number(self, text: str) -> int | None:
        """The number of the move a typed operation id stands for (None: none)."""
        moves = self.session.moves()
        for op, perm in self.map.candidates(text, self._pattern) if text else ():
            for m in moves:
                if m.operation and m.operation == op:
                    self.map.adopt(perm)
                    return m.number
        return None


def _unit(dag) -> str:
    return cost_unit(dag.cost_model)


def _state_lines(session, fmt) -> list[str]:
    u = _unit(session.dag)
    label = session.node_label
    state = f"node {session.node_id}" + (f"  [{label}]" if label else "")
    line = (
        f"  cost so far {fmt(session.cost)}{u} | worst case remaining "
        f"{fmt(session.worst_remaining)}{u} (total {fmt(session.cost + session.worst_remaining)})"
        f" | cooperative best remaining {fmt(session.coop_remaining)}{u}"
    )
    out = [f"  state: {state}", line]
    if not costs_close(session.minimax_remaining, session.worst_remaining):
        out.append(f"  (W* from here: {fmt(session.minimax_remaining)}{u} remaining)")
    return out


def _moves_table(session, fmt, alike: _Alike) -> list[str]:
    moves = [alike.move(m) for m in session.moves()]
    width = max(len(m.label) for m in moves)
    width = min(max(width, 4), 60)
    head = f"    {'#':>3}  {'move':<{width}}  {'cost':>6}  {'to':>6}  {'worst':>7}  {'coop':>7}"
    lines = [head]
    for m in moves:
        label = m.label if len(m.label) <= width else m.label[: width - 3] + "..."
        lines.append(
            f"    {m.number:>3}  {label:<{width}}  {fmt(m.cost):>6}  {str(m.target_id):>6}  "
            f"{fmt(session.cost + m.worst_remaining):>7}  {fmt(session.cost + m.coop_remaining):>7}"
        )
    return lines


def _turn_line(turn, fmt, person: int) -> str:
    from asp.game.dag import HUMAN, ROBOT
    from asp.game.play import side_name

    who = side_name(turn.player)
    if turn.passed:
        return f"  {who} passes: {turn.reason}"
    m = turn.move
    name = m.label if (m.operation or m.agent) else "moves"
    what = f"{name} -> node {m.target_id} [cost {fmt(m.cost)}]"
    if turn.by == "person":
        note = ""
        delta = turn.worst_after - turn.worst_before
        if person == HUMAN and not cost_at_most(turn.worst_before, turn.worst_after):
            note = f"  (that helps: the worst case drops to {fmt(turn.worst_after)})"
        elif person == ROBOT and not cost_at_most(turn.worst_after, turn.worst_before):
            note = f"  (that raises the worst case to {fmt(turn.worst_after)}, +{fmt(delta)})"
        return f"  you ({who}): {what}{note}"
    return f"  {who}: {what}: {turn.reason}"


def _read_line() -> str | None:
    line = sys.stdin.readline()
    return None if line == "" else line.strip()


@app.command("play")
def play_command(
    source: Path = typer.Argument(
        ..., help="Game DAG (.json/.graphml) or assembly (folder, assembly.yaml, .IN2)."
    ),
    side: Side = typer.Option(Side.human, "--as", help="The side you play: human or robot."),
    robot: str = typer.Option(
        "robust",
        "--robot",
        help="The computer robot when you play the human: robust, fast-greedy, or a run "
        "folder of 'asmplan train'.",
    ),
    moves: str | None = typer.Option(
        None, "--moves", help="Scripted move numbers, e.g. 2,1,3 (then reads stdin)."
    ),
    seed: int | None = seed_option(
        "Break the computer human's ties at random with this seed.", default=None
    ),
    cost: CostModel | None = typer.Option(
        None, "--cost", help="Cost model of an assembly (default: the spec's)."
    ),
) -> None:
    """Play against the robust plan: you take one side, the computer the other."""
    from asmplan.pipeline import load_game
    from asp.game.dag import HUMAN, ROBOT
    from asp.game.play import GameSession, fmt

    game = load_game(source, cost=None if cost is None else cost.value)
    dag, descriptions = game.dag, game.descriptions
    script = _parse_moves(moves, () if dag.operations is None else dag.operations)
    person = HUMAN if side is Side.human else ROBOT
    if person == ROBOT and robot != "robust":
        raise ValueError("--robot applies when you play the human (--as human)")
    policy, name = _robot_policy(dag, robot) if person == HUMAN else ("robust", "robust")
    session = GameSession(
        dag,
        person=person,
        robot=policy,
        robot_name=name,
        descriptions=descriptions,
        seed=seed,
    )
    u = _unit(dag)
    sol = session.solution
    title = dag.metadata.get("assembly") or source.name
    typer.echo(f"{title}: game DAG ({dag.cost_model}), {dag.n_nodes} nodes, {dag.n_edges} edges")
    if person == HUMAN:
        typer.echo(f"you play the HUMAN side (you maximise the cost) against the {name} robot")
    else:
        typer.echo("you play the ROBOT side (you minimise the cost) against a best-response human")
    typer.echo(
        f"TCT {fmt(sol.tct)}{u}, W* {fmt(sol.minimax)}{u}. Type a move number, "
        "? for help, q to quit."
    )
    alike = _Alike(session, game.interchangeable)
    echo_input = not sys.stdin.isatty()

    while not session.finished:
        for turn in session.advance():
            who = "robot" if turn.player == ROBOT else "human"
            if turn.passed:
                typer.echo(
                    f"step {turn.step}: {who} at node {turn.node_id} has no move it may "
                    "do: passes at zero cost"
                )
                continue
            typer.echo(f"step {turn.step}: {who} to move")
            for line in _state_lines_at(turn, session, fmt):
                typer.echo(line)
            typer.echo(_turn_line(alike.turn(turn), fmt, person))
        if session.finished:
            break
        step = len(session.history) + 1
        typer.echo(f"step {step}: your move ({'human' if person == HUMAN else 'robot'})")
        for line in _state_lines(session, fmt) + _moves_table(session, fmt, alike):
            typer.echo(line)
        n = len(session.moves())
        while True:
            prompt = f"your move [1-{n}, ? help, q quit]: "
            if script:
                choice = script.pop(0)
                typer.echo(f"{prompt}{choice} (scripted)")
                number = int(choice) if choice.isdigit() else alike.number(choice)
                if number is None or not 1 <= number <= n:
                    raise ValueError(
                        f"--moves: move {choice} at step {step}: expected 1 to {n} or the id "
                        "of an operation the player may do"
                    )
                choice = str(number)
            else:
                typer.echo(prompt, nl=False)
                choice = _read_line()
                if choice is None:
                    typer.echo("")
                    typer.echo("end of input: quitting")
                    _finish(session)
                    return
                if echo_input:
                    typer.echo(choice)
            if choice.lower() in ("q", "quit", "exit"):
                _finish(session)
                return
            if choice in ("?", "h", "help"):
                typer.echo(HELP_TEXT)
                continue
            if choice.isdigit() and 1 <= int(choice) <= n:
                break
            number = None if choice.isdigit() else alike.number(choice)
            if number is not None:
                choice = str(number)
                break
            typer.echo(
                f"  please type a number from 1 to {n} (or an operation id), ? for help or q "
                "to quit"
            )
        turn = session.play(int(choice))
        typer.echo(_turn_line(alike.turn(turn), fmt, person))
    if script:
        typer.echo(f"({len(script)} scripted moves left unused: the game is over)")
    _finish(session)


def _state_lines_at(turn, session, fmt) -> list[str]:
    """State lines for a past computer turn (the session has already moved on)."""
    dag = session.dag
    u = _unit(dag)
    label = dag.node_labels[turn.node] if dag.node_labels is not None else ""
    state = f"node {turn.node_id}" + (f"  [{label}]" if label else "")
    remaining = turn.worst_before - turn.cost_before
    coop = float(session.solution.coop[turn.node, turn.player])
    return [
        f"  state: {state}",
        f"  cost so far {fmt(turn.cost_before)}{u} | worst case remaining {fmt(remaining)}{u} "
        f"(total {fmt(turn.worst_before)}) | cooperative best remaining {fmt(coop)}{u}",
    ]


def _finish(session) -> None:
    typer.echo("")
    for line in session.summary().lines():
        typer.echo(line)
