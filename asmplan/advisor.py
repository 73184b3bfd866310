"""The runtime advisor: follows a cell through the plan's policy, one observation at a time.

``Advisor(plan)`` starts at the policy's start state. Each observation is an event: an
operation ``started`` or ``finished`` by an agent. The advisor answers the robots' next
operations, the instruction to the person and the remaining guaranteed bound
(:class:`Advice`). An observation the plan cannot explain (an unknown operation or agent, an
agent that may not do the operation, an operation not enabled in the current state, a robot
move that is not the plan's, a finish of an operation that is not running) raises
:class:`ObservationError` naming it, and the advisor's state is unchanged.

Turn model ``alternate``: one operation runs at a time, by the side on turn. A ``finished``
event of an operation that was not seen to start counts as its start and finish (a sensor
may only see completions). Passes (a side with nothing it may do) are taken automatically.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

from asmplan.errors import GameError
from asmplan.planfile import check_plan

EVENT_KINDS = ("started", "finished")


class ObservationError(GameError):
    """An observation the plan cannot explain; the advisor's state is unchanged."""


@dataclass(frozen=True)
class Event:
    """An observation: ``kind`` (``started`` / ``finished``) of ``operation`` by ``agent``."""

    kind: str
    operation: str
    agent: str

    @classmethod
    def parse(cls, event) -> Event:
        """An :class:`Event` from itself or a mapping with ``kind``, ``operation``, ``agent``."""
        if isinstance(event, Event):
            return event
        if not isinstance(event, dict):
            raise ObservationError(f"event: expected an object, got {type(event).__name__}")
        missing = [k for k in ("kind", "operation", "agent") if k not in event]
        if missing:
            raise ObservationError(f"event: missing {', '.join(missing)}")
        kind = str(event["kind"])
        if kind not in EVENT_KINDS:
            raise ObservationError(f"event kind {kind!r}: expected 'started' or 'finished'")
        return cls(kind, str(event["operation"]), str(event["agent"]))


@dataclass(frozen=True)
class Advice:
    """What the advisor says in the current state.

    Attributes
    ----------
    state : int
        Policy state index.
    turn : str
        Side on turn (``robot`` / ``human``).
    done : list of str
        Operations done.
    parts : list of str
        Parts placed so far.
    tools : dict
        Tool values.
    running : list of dict
        ``{"agent", "operation", "remaining"}`` of each running operation.
    robots : list of dict
        The robots' next operations (``{"operation", "agent", "description"}``); empty:
        the robots wait.
    instruction : dict or None
        What the person is asked to do next (``None``: wait).
    options : list of dict
        At the person's turn, every operation the person may start with the worst case it
        leads to (``{"operation", "agent", "description", "cost", "worst"}``, ``worst``
        the guaranteed total cost after it).
    elapsed : float
        Cost so far.
    bound : float
        Remaining guaranteed cost (the robust robot's worst case from here).
    finished : bool
        The assembly is complete.
    """

    state: int
    turn: str
    done: list
    parts: list
    tools: dict
    running: list
    robots: list
    instruction: dict | None
    options: list
    elapsed: float
    bound: float
    finished: bool

    @property
    def total_bound(self) -> float:
        """Cost so far plus the remaining guaranteed bound."""
        return self.elapsed + self.bound

    def to_dict(self) -> dict:
        out = asdict(self)
        out["total_bound"] = self.total_bound
        return out


@dataclass
class _Cursor:
    state: int
    elapsed: float = 0.0
    running: int = -1  # move index of the running operation, or -1
    history: list = field(default_factory=list)


class Advisor:
    """Follows one cell (one game) through a plan's policy.

    Parameters
    ----------
    plan : dict
        A plan document (``asmplan-plan/2``), as read by :func:`asmplan.planfile.read_plan`.
    """

    def __init__(self, plan: dict):
        check_plan(plan)
        if plan["policy"]["turn_model"] != "alternate":
            raise ValueError(
                f"advisor: turn model {plan['policy']['turn_model']!r} is not supported yet"
            )
        self.plan = plan
        self._policy = plan["policy"]
        self._ops = self._policy["operations"]
        self._op_index = {op: k for k, op in enumerate(self._ops)}
        self._agents = self._policy["agents"]
        self._agent_index = {a: k for k, a in enumerate(self._agents)}
        self._operations = plan.get("operations", {})
        self._cursor = _Cursor(self._policy["start"])
        self._cursor.state = self._skip_passes(self._cursor.state)

    # ------------------------------------------------------------------ queries
    @property
    def history(self) -> list[Event]:
        """The events observed so far (in order)."""
        return list(self._cursor.history)

    @property
    def finished(self) -> bool:
        return self._moves(self._cursor.state) == range(0) and self._cursor.running < 0

    def advice(self) -> Advice:
        """The advice in the current state."""
        c = self._cursor
        states, moves = self._policy["states"], self._policy["moves"]
        i = c.state
        done = self._done(i)
        tools = {
            name: values[k]
            for (name, values), k in zip(
                self._policy["tools"].items(), states["tools"][i], strict=False
            )
        }
        running = [
            {"agent": a, "operation": op, "remaining": r} for a, op, r in states["running"][i]
        ]
        robots: list = []
        instruction = None
        options: list = []
        bound = states["bound"][i]
        if c.running >= 0:
            j = c.running
            running.append(
                {
                    "agent": self._agents[moves["agent"][j]],
                    "operation": self._ops[moves["operation"][j]],
                    "remaining": moves["cost"][j],
                }
            )
            bound = moves["cost"][j] + states["bound"][moves["next"][j]]
        else:
            robots = [self._op_dict(op, agent) for op, agent in states["robots"][i]]
            if states["instruction"][i] is not None:
                instruction = self._op_dict(*states["instruction"][i])
            if states["turn"][i] == "human":
                for j in self._moves(i):
                    if moves["operation"][j] < 0:
                        continue
                    item = self._op_dict(moves["operation"][j], moves["agent"][j])
                    item["cost"] = moves["cost"][j]
                    item["worst"] = c.elapsed + moves["cost"][j] + states["bound"][moves["next"][j]]
                    options.append(item)
        return Advice(
            state=i,
            turn=states["turn"][i],
            done=done,
            parts=[p for op in done for p in self._operations.get(op, {}).get("parts", [])],
            tools=tools,
            running=running,
            robots=robots,
            instruction=instruction,
            options=options,
            elapsed=c.elapsed,
            bound=bound,
            finished=self.finished,
        )

    # ------------------------------------------------------------------ observing
    def observe(self, event) -> Advice:
        """Take one observation; return the new advice.

        Raises
        ------
        ObservationError
            The plan cannot explain the observation (the state is unchanged).
        """
        ev = Event.parse(event)
        if ev.operation not in self._op_index:
            raise ObservationError(f"unknown operation {ev.operation!r}")
        if ev.agent not in self._agent_index:
            raise ObservationError(f"unknown agent {ev.agent!r}")
        allowed = self._operations.get(ev.operation, {}).get("agents")
        if allowed is not None and ev.agent not in allowed:
            raise ObservationError(
                f"agent {ev.agent} may not do operation {ev.operation} "
                f"(allowed: {', '.join(allowed)})"
            )
        c = self._cursor
        if self.finished:
            raise ObservationError(f"{ev.kind} {ev.operation} by {ev.agent}: the game is over")
        if c.running >= 0:
            run_op, run_agent = self._move_names(c.running)
            if ev.kind == "started":
                raise ObservationError(
                    f"{ev.operation} by {ev.agent} cannot start: {run_op} by {run_agent} is "
                    "still running (one operation at a time in the alternating game)"
                )
            if (ev.operation, ev.agent) != (run_op, run_agent):
                raise ObservationError(
                    f"{ev.operation} by {ev.agent} is not running (running: {run_op} by "
                    f"{run_agent})"
                )
            self._finish(c.running)
        else:
            j = self._find_move(ev)
            if ev.kind == "started":
                c.running = j
            else:
                self._finish(j)
        c.history.append(ev)
        return self.advice()

    def _finish(self, j: int) -> None:
        moves = self._policy["moves"]
        c = self._cursor
        c.elapsed += moves["cost"][j]
        c.running = -1
        c.state = self._skip_passes(moves["next"][j])

    def _find_move(self, ev: Event) -> int:
        """The move of the current state matching ``ev``, or an error saying why none does."""
        states, moves = self._policy["states"], self._policy["moves"]
        i = self._cursor.state
        op, agent = self._op_index[ev.operation], self._agent_index[ev.agent]
        for j in self._moves(i):
            if moves["operation"][j] == op and moves["agent"][j] == agent:
                return j
        what = f"{ev.operation} by {ev.agent}"
        if ev.operation in self._done(i):
            raise ObservationError(f"{what}: operation {ev.operation} is already done")
        side = self.plan.get("agents", {}).get(ev.agent, "")
        turn = states["turn"][i]
        if turn == "robot":
            plan = ", ".join(f"{self._ops[o]} by {self._agents[a]}" for o, a in states["robots"][i])
            if side == "human":
                raise ObservationError(
                    f"{what}: it is the robots' turn (the plan: {plan or 'wait'}); the person waits"
                )
            raise ObservationError(f"{what} is not the plan's move here (the plan: {plan})")
        if side == "robot":
            raise ObservationError(f"{what}: it is the person's turn; the robots wait")
        raise ObservationError(f"{what}: operation {ev.operation} is not enabled in this state")

    # ------------------------------------------------------------------ helpers
    def _moves(self, i: int) -> range:
        ptr = self._policy["moves"]["ptr"]
        return range(ptr[i], ptr[i + 1])

    def _skip_passes(self, i: int) -> int:
        moves = self._policy["moves"]
        while True:
            r = self._moves(i)
            if len(r) == 1 and moves["operation"][r.start] < 0:
                i = moves["next"][r.start]
                continue
            return i

    def _done(self, i: int) -> list[str]:
        mask = int(self._policy["states"]["done"][i], 16)
        return [op for k, op in enumerate(self._ops) if mask >> k & 1]

    def _move_names(self, j: int) -> tuple[str, str]:
        moves = self._policy["moves"]
        return self._ops[moves["operation"][j]], self._agents[moves["agent"][j]]

    def _op_dict(self, op: int, agent: int) -> dict:
        name = self._ops[op]
        return {
            "operation": name,
            "agent": self._agents[agent],
            "description": self._operations.get(name, {}).get("description", ""),
        }

    @classmethod
    def replay(cls, plan: dict, events: list) -> Advisor:
        """An advisor that has observed ``events`` (raises on the first it cannot explain)."""
        advisor = cls(plan)
        for ev in events:
            advisor.observe(ev)
        return advisor
