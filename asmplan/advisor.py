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

Turn model ``concurrent`` (:class:`ConcurrentAdvisor`, which ``Advisor(plan)`` returns for
such a plan): decisions are taken at events, as in the game (``asp/concurrent/``). At the
start and after every completion the robots commit first: the advisor takes the plan's
commitment at once (the robots' next operations, ``robots``; a robot's ``started`` event
confirms it, any other robot start is refused) and says what each free person is asked to do
(``instruction``). The people's ``started`` events are their reply; a ``finished`` event is
the next completion: it picks the plan's move with those starts in which that operation
finishes, and time advances by that move's cost. Operations that finish at the same instant
are reported one after the other. A person's duration given as a range is seen only when the
operation finishes, so the advisor follows every move the observations leave possible (an
event's optional ``time``, seconds since the start, keeps those whose completion is nearest
to it) and answers for the worst of them; the robots do what it answered, which removes the
moves whose commitment differs.

Alike operations (both turn models): the policy knows one canonical order of each class of
interchangeable operations (``plan.json``'s ``interchangeable``, :mod:`asp.graph.symmetry`). An
observed operation of a class is mapped onto the operation the plan can take (the class's
next canonical one) by a permutation of the class's blocks (:class:`asp.game.alike.AlikeMap`):
a block of several operations (a dowel with its roller) moves as one, and later events of
the same physical operation (its finish after its start) map the same way. Observations,
history and advice are in physical operation ids; an instruction or option that names one
of several alike operations lists in ``alike`` every one that is as good (and their parts
in ``alike_parts``). The bound is the plan's: a symmetry keeps every cost.

Advice that explains itself (both turn models): each option carries the robots' reply to it
(``reply``), the worst line it leads to (``line``: every operation still to come, with its
start and end, when the person then does the worst she can) and a sentence saying so
(``why``), and so does each completion the person may let the cell run to (concurrent:
``finishes``); ``ahead`` is the line from now on when the person follows the instructions (the
Gantt chart of the plan ahead). The lines are the plan file's own (:func:`line_moves`).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace

from asmplan.errors import GameError
from asmplan.planfile import check_plan, line_moves, move_starts, worst_move
from asp.game.alike import AlikeMap
from asp.game.turns import ALTERNATE, CONCURRENT, TurnModel

EVENT_KINDS = ("started", "finished")


def quantity(x: float, cost: str | None) -> str:
    """A cost with its unit: ``12 s``, or ``3 steps`` when the plan counts operations."""
    if cost == "steps":
        return f"{x:g} step" if x == 1 else f"{x:g} steps"
    return f"{x:g} s"


def option_why(option: dict, cost: str | None) -> str:
    """The sentence that explains an option: what the robots do in reply and the worst that
    can still happen (``If you do 2.2 now, R2 does 1.3; the worst that can still happen is
    297 s.``)."""
    concurrent = "durations" in option
    reply = option.get("reply")
    if reply is None:
        then = "that completes the assembly"
    elif not reply["robots"]:
        then = f"at {quantity(reply['time'], cost)} " if concurrent else ""
        then += "the robots wait" if concurrent else "the robots have nothing to do"
    else:
        verb = "starts" if concurrent else "does"
        then = " and ".join(f"{r['agent']} {verb} {r['operation']}" for r in reply["robots"])
        if concurrent:
            then = f"at {quantity(reply['time'], cost)} {then}"
    verb = "start" if concurrent else "do"
    worst = quantity(option["worst"], cost)
    return (
        f"If you {verb} {option['operation']} now, {then}; the worst that can still happen is "
        f"{worst}."
    )


def finish_why(finish: dict, cost: str | None) -> str:
    """The sentence that explains a completion the person may let the cell run to: what the
    robots do then and the worst that can still happen (``If you let R1 finish 6 at 12 s,
    R1 starts 7; the worst that can still happen is 52 s.``)."""
    at = quantity(finish["time"], cost)
    reply = finish.get("reply")
    if reply is None:
        then = "the robots go on as planned"
    elif not reply["robots"]:
        then = "the robots wait"
    else:
        then = " and ".join(f"{r['agent']} starts {r['operation']}" for r in reply["robots"])
    op = finish["operation"]
    when = (
        f"If you finish {op} at {at} ({finish['agent']}) and start nothing more"
        if finish.get("side") == "human"
        else f"If you let {finish['agent']} finish {op} at {at} and start nothing more"
    )
    worst = quantity(finish["worst"], cost)
    return f"{when}, {then}; the worst that can still happen is {worst}."


def placed_parts(operations: dict[str, dict], done: list[str]) -> list[str]:
    """The parts the operations ``done`` have placed, each once, in the order placed (a
    unit's members are placed in its workspace, then inserted with it)."""
    return list(dict.fromkeys(p for op in done for p in operations.get(op, {}).get("parts", [])))


class ObservationError(GameError):
    """An observation the plan cannot explain; the advisor's state is unchanged."""


@dataclass(frozen=True)
class Event:
    """An observation: ``kind`` (``started`` / ``finished``) of ``operation`` by ``agent``,
    optionally at ``time`` (seconds since the start) and, for a start, the ``duration`` the
    agent will take (a person's duration given as a range; the concurrent game's robots know
    it when she starts)."""

    kind: str
    operation: str
    agent: str
    time: float | None = None
    duration: float | None = None

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
        numbers = []
        for key in ("time", "duration"):
            x = event.get(key)
            if x is not None:
                try:
                    x = float(x)
                except (TypeError, ValueError):
                    raise ObservationError(f"event {key} {x!r}: expected a number") from None
                if not math.isfinite(x) or x < 0:
                    raise ObservationError(f"event {key} {x!r}: expected a number >= 0")
            numbers.append(x)
        return cls(kind, str(event["operation"]), str(event["agent"]), *numbers)


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
        What the person is asked to do next (``None``: wait); ``alike`` lists every
        operation as good as ``operation`` (alike parts in interchangeable places, itself
        first) and ``alike_parts`` their parts.
    options : list of dict
        At the person's turn, every operation the person may start with the worst case it
        leads to (``{"operation", "agent", "description", "cost", "worst", "alike",
        "alike_parts", "deviation", "reply", "line", "why"}``, ``worst`` the guaranteed total
        cost after it, ``deviation`` not the instruction). ``reply``: what the robots do next
        (``{"time", "robots": [{"operation", "agent", "description"}]}``, ``robots`` empty:
        they wait; None: the option completes the assembly). ``line``: the worst line the
        option leads to, every operation from the option on (``{"operation", "agent",
        "description", "side", "start", "end", "deviation"}``, times since the start).
        ``why``: a sentence saying both. Concurrent: also ``durations`` (those the plan
        knows; ``cost`` the longest); the reply and line are the worst duration's.
    elapsed : float
        Cost so far.
    bound : float
        Remaining guaranteed cost (the robust robot's worst case from here).
    finished : bool
        The assembly is complete.
    deviations : int
        The person's deviations from the instructions so far.
    turn_model : str
        ``alternate`` or ``concurrent``.
    instructions : list of dict
        Concurrent: what each free person is asked to do (``{"agent", "operation",
        "description"}``, ``operation`` None: wait).
    finishes : list of dict
        Concurrent: the completions the plan can explain next, given the people's starts so
        far (``{"operation", "agent", "side", "time", "worst"}``: the operation finishing,
        by whom, at which time, and the guaranteed makespan after it; explained, also
        ``reply``, ``line`` and ``why`` as an option's); empty while a free person must still
        start something.
    budget : int or None
        Concurrent: deviations the person may still make (None: unbounded).
    ahead : list of dict
        The plan ahead: every operation still to start when the person follows the
        instructions from now on (entries as an option's ``line``; concurrent: of a
        person's duration range, the longest).
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
    deviations: int = 0
    turn_model: str = ALTERNATE.name
    instructions: list = field(default_factory=list)
    finishes: list = field(default_factory=list)
    budget: int | None = None
    ahead: list = field(default_factory=list)

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
    deviations: int = 0


class Advisor:
    """Follows one cell (one game) through a plan's policy.

    Parameters
    ----------
    plan : dict
        A plan document (``asmplan-plan/2``), as read by :func:`asmplan.planfile.read_plan`.
    """

    TURN_MODEL: TurnModel = ALTERNATE
    """The turn model of the plans it follows (:data:`ADVISORS`)."""

    def __new__(cls, plan: dict):
        turn = plan.get("policy", {}).get("turn_model") if isinstance(plan, dict) else None
        if cls is Advisor and isinstance(turn, str):
            return super().__new__(ADVISORS.get(turn, Advisor))
        return super().__new__(cls)

    def __init__(self, plan: dict):
        self._read(plan, self.TURN_MODEL.name)
        self._cursor = _Cursor(self._policy["start"])
        self._cursor.state = self._skip_passes(self._cursor.state)

    def _read(self, plan: dict, turn_model: str) -> None:
        """Check the plan and index its policy's operations and agents."""
        check_plan(plan)
        if plan["policy"]["turn_model"] != turn_model:
            got = plan["policy"]["turn_model"]
            raise ValueError(f"advisor: expected a plan of turn model {turn_model}, got {got!r}")
        self.plan = plan
        self._policy = plan["policy"]
        self._ops = self._policy["operations"]
        self._op_index = {op: k for k, op in enumerate(self._ops)}
        self._agents = self._policy["agents"]
        self._agent_index = {a: k for k, a in enumerate(self._agents)}
        self._operations = plan.get("operations", {})
        self._alike = AlikeMap(plan.get("interchangeable") or ())

    # ------------------------------------------------------------------ queries
    @property
    def history(self) -> list[Event]:
        """The events observed so far (in order)."""
        return list(self._cursor.history)

    @property
    def finished(self) -> bool:
        return self._moves(self._cursor.state) == range(0) and self._cursor.running < 0

    def advice(self) -> Advice:
        """The advice in the current state, in physical operation ids."""
        return self._physical(self._canonical_advice())

    def explain(self) -> Advice:
        """:meth:`advice` that explains itself: each option with the robots' reply, the
        worst line it leads to and the sentence saying both (:func:`option_why`), and the
        plan ahead (``ahead``). Its cost grows with the options times the operations left,
        so :meth:`observe` answers :meth:`advice` and a page asks for this one."""
        advice = self._physical(self._canonical_advice(explain=True))
        cost = self.plan.get("cost")
        return replace(
            advice,
            options=[{**o, "why": option_why(o, cost)} for o in advice.options],
            finishes=[{**f, "why": finish_why(f, cost)} for f in advice.finishes],
        )

    # ------------------------------------------------------------------ explanations
    def _explained(self, i: int, j: int, elapsed: float) -> dict:
        """An option's ``reply`` and ``line`` (:class:`Advice`): move ``j`` at state ``i``,
        then the worst line."""
        pairs = line_moves(self._policy, "worst", start=i, first=j)
        reply = None
        if len(pairs) > 1 and self._policy["states"]["turn"][pairs[1][0]] == "robot":
            robots = move_starts(self._policy, pairs[1][1])
            reply = {
                "time": elapsed + self._policy["moves"]["cost"][j],
                "robots": [self._op_dict(o, a) for o, a, _ in robots],
            }
        return {"reply": reply, "line": self._line(pairs, elapsed)}

    def _line(self, pairs: list[tuple[int, int]], elapsed: float) -> list[dict]:
        """The operations the moves ``pairs`` (:func:`line_moves`) start, from ``elapsed`` on,
        each with its side, start, end and whether it deviates from the instruction."""
        cost = self._policy["moves"]["cost"]
        out, t = [], elapsed
        for s, m in pairs:
            told = self._instructed(s)
            for o, a, d in move_starts(self._policy, m):
                side = self._side(s, a)
                entry = {**self._op_dict(o, a), "side": side, "start": t, "end": t + d}
                entry["deviation"] = side == "human" and a in told and told[a] != o
                out.append(entry)
            t += cost[m]
        return out

    def _instructed(self, i: int) -> dict[int, int]:
        """Agent index -> the operation index the person is asked to do at state ``i``
        (``-1``: wait)."""
        told = self._policy["states"]["instruction"][i]
        if not told:
            return {}
        if isinstance(told[0], list):
            return {a: o for o, a in told}
        return {told[1]: told[0]}

    def _side(self, i: int, a: int) -> str:
        """The side of agent ``a`` moving at state ``i`` (the side on turn)."""
        return self._policy["states"]["turn"][i]

    def _canonical_advice(self, explain: bool = False) -> Advice:
        """The advice in the policy's (canonical) operation ids (``explain``: with the
        explanations of :meth:`explain`)."""
        c = self._cursor
        states, moves = self._policy["states"], self._policy["moves"]
        i = c.state
        done = self._done(i)
        tools = self._tools(i)
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
                instruction = self._person_dict(*states["instruction"][i])
            if states["turn"][i] == "human":
                told = states["instruction"][i]
                for j in self._moves(i):
                    if moves["operation"][j] < 0:
                        continue
                    move = [moves["operation"][j], moves["agent"][j]]
                    item = self._person_dict(*move)
                    item["cost"] = moves["cost"][j]
                    item["worst"] = c.elapsed + moves["cost"][j] + states["bound"][moves["next"][j]]
                    item["deviation"] = told is not None and move != told
                    if explain:
                        item.update(self._explained(i, j, c.elapsed))
                    options.append(item)
        return Advice(
            state=i,
            turn=states["turn"][i],
            done=done,
            parts=placed_parts(self._operations, done),
            tools=tools,
            running=running,
            robots=robots,
            instruction=instruction,
            options=options,
            elapsed=c.elapsed,
            bound=bound,
            finished=self.finished,
            deviations=c.deviations,
            ahead=self._line(
                line_moves(self._policy, "plan", start=i, first=_move(c.running)), c.elapsed
            )
            if explain
            else [],
        )

    # ------------------------------------------------------------------ observing
    def observe(self, event) -> Advice:
        """Take one observation; return the new advice.

        An operation of a class of alike ones is taken as the canonical operation it maps
        onto (module docstring): the instruction's if it can be, else the current mapping's,
        else another alike one's the plan can take.

        Raises
        ------
        ObservationError
            The plan cannot explain the observation (the state is unchanged).
        """
        ev = Event.parse(event)
        self._check(ev)
        told = self._told(ev.agent)
        first = None
        for op, perm in self._alike.candidates(ev.operation, self._pattern, told):
            try:
                self._take(replace(ev, operation=op))
            except ObservationError as exc:
                if first is None:
                    first = exc if op == ev.operation else _as_alike(exc, ev.operation, op)
                continue
            self._alike.adopt(perm)
            self._record(ev)
            return self.advice()
        raise first

    def _take(self, ev: Event) -> None:
        """Take one observation in canonical ids (raises, state unchanged, if it cannot)."""
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
            told = self._policy["states"]["instruction"][c.state]
            moves = self._policy["moves"]
            if told is not None and [moves["operation"][j], moves["agent"][j]] != told:
                c.deviations += 1
            if ev.kind == "started":
                c.running = j
            else:
                self._finish(j)

    def _record(self, ev: Event) -> None:
        self._cursor.history.append(ev)

    def _told(self, agent: str) -> list[str]:
        """The canonical operations ``agent`` is asked to do now."""
        told = self._policy["states"]["instruction"][self._cursor.state]
        if self._cursor.running >= 0 or told is None or self._agents[told[1]] != agent:
            return []
        return [self._ops[told[0]]]

    def _pattern(self, op: str):
        """An alike operation's pattern (:data:`asp.game.alike.Pattern`): done or not; None
        while it runs."""
        c = self._cursor
        if c.running >= 0 and self._ops[self._policy["moves"]["operation"][c.running]] == op:
            return None
        return op in self._done(c.state)

    # ------------------------------------------------------------------ physical ids
    def _physical(self, advice: Advice) -> Advice:
        """``advice`` with every operation named by its physical id (the alike map)."""
        if not self._alike:
            return advice
        done = sorted((self._alike.physical(op) for op in advice.done), key=self._op_index.get)
        return replace(
            advice,
            done=done,
            parts=placed_parts(self._operations, done),
            running=[self._item(r) for r in advice.running],
            robots=[self._item(r) for r in advice.robots],
            instruction=None if advice.instruction is None else self._item(advice.instruction),
            options=_distinct([self._item(o) for o in advice.options]),
            instructions=[self._item(i) for i in advice.instructions],
            finishes=[self._item(f) for f in advice.finishes],
            ahead=[self._item(e) for e in advice.ahead],
        )

    def _item(self, item: dict) -> dict:
        """An advice entry naming a canonical operation, in physical ids; an instruction or
        option (it has a ``description``) also lists the alike operations as good as it."""
        op = item.get("operation")
        if op is None:
            return item
        out = {**item, "operation": self._alike.physical(op)}
        if "description" in item:
            out["description"] = self._operations.get(out["operation"], {}).get(
                "description", item["description"]
            )
        if "alike" in item:
            alike = self._alike.alike(op, self._pattern)
            out["alike"] = alike
            out["alike_parts"] = placed_parts(self._operations, alike)
        if "line" in item:
            out["line"] = [self._item(e) for e in item["line"]]
        if item.get("reply"):
            out["reply"] = {
                **item["reply"],
                "robots": [self._item(r) for r in item["reply"]["robots"]],
            }
        return out

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
    def _check(self, ev: Event) -> tuple[int, int]:
        """The operation and agent indices of ``ev``; an error naming an unknown one or an
        agent the operation does not allow (a worker ``A:human`` is agent ``A``)."""
        if ev.operation not in self._op_index:
            raise ObservationError(f"unknown operation {ev.operation!r}")
        if ev.agent not in self._agent_index:
            raise ObservationError(
                f"unknown agent {ev.agent!r} (agents: {', '.join(self._agents)})"
            )
        allowed = self._operations.get(ev.operation, {}).get("agents")
        if allowed is not None and ev.agent.split(":")[0] not in allowed:
            raise ObservationError(
                f"agent {ev.agent} may not do operation {ev.operation} "
                f"(allowed: {', '.join(allowed)})"
            )
        return self._op_index[ev.operation], self._agent_index[ev.agent]

    def _tools(self, i: int) -> dict:
        return {
            name: values[k]
            for (name, values), k in zip(
                self._policy["tools"].items(), self._policy["states"]["tools"][i], strict=False
            )
        }

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

    def _person_dict(self, op: int, agent: int) -> dict:
        """An instruction or option: :meth:`_op_dict` with the alike operations as good as
        it (``alike``, ``alike_parts``; physical ids are given by :meth:`_physical`)."""
        name = self._ops[op]
        parts = self._operations.get(name, {}).get("parts", [])
        return {**self._op_dict(op, agent), "alike": [name], "alike_parts": list(parts)}

    @classmethod
    def replay(cls, plan: dict, events: list) -> Advisor:
        """An advisor that has observed ``events`` (raises on the first it cannot explain)."""
        advisor = cls(plan)
        for ev in events:
            advisor.observe(ev)
        return advisor


# --------------------------------------------------------------------------- concurrent


@dataclass(frozen=True)
class _Branch:
    """One way the concurrent game may stand given the observations (module docstring).

    ``state`` is a human state of the policy (the robots' commitment taken) or the end
    state; ``commit`` the robots' starts and the instructions of that commitment;
    ``confirmed`` the robot starts seen; ``unreported`` the operations that finished with
    the last completion and are not reported yet.
    """

    state: int
    elapsed: float
    commit: tuple = ()
    told: tuple = ()
    confirmed: frozenset = frozenset()
    unreported: frozenset = frozenset()
    pending: tuple = ()  # (op, agent): the people's starts since the last completion
    fixed: tuple = ()  # (op, agent, duration) of the starts observed with their duration


class ConcurrentAdvisor(Advisor):
    """The runtime advisor of a concurrent plan (module docstring); ``Advisor(plan)`` returns
    one for a plan of turn model ``concurrent``."""

    TURN_MODEL = CONCURRENT

    def __init__(self, plan: dict):
        self._read(plan, self.TURN_MODEL.name)
        sides = plan.get("agents", {})
        self._robot = [_worker_side(a, sides) == "robot" for a in self._agents]
        self._events: list[Event] = []
        self._deviations = 0
        self._branches = [self._commit(self._policy["start"], 0.0)]

    # ------------------------------------------------------------------ queries
    @property
    def history(self) -> list[Event]:
        return list(self._events)

    @property
    def finished(self) -> bool:
        b = self._branches[0]
        return len(self._moves(b.state)) == 0 and not b.unreported

    def _canonical_advice(self, explain: bool = False) -> Advice:
        states = self._policy["states"]
        b = self._branches[0]
        i = b.state
        told = {a: o for o, a in b.told if a not in self._busy(b)}
        instructions = [
            {"agent": self._agents[a], "operation": None, "description": "wait"}
            if o < 0
            else self._person_dict(o, a)
            for a, o in told.items()
        ]
        instruction = next(
            (self._person_dict(o, a) for a, o in told.items() if o >= 0 and not self.finished),
            None,
        )
        running = [
            {"agent": a, "operation": op, "remaining": r} for a, op, r in states["running"][i]
        ]
        for o, a in b.pending:
            durations = [
                d
                for br in self._branches
                for m in self._consistent(br, set(br.pending))
                for so, sa, d in self._policy["moves"]["starts"][m]
                if (so, sa) == (o, a)
            ]
            running.append(
                {
                    "agent": self._agents[a],
                    "operation": self._ops[o],
                    "remaining": max(durations, default=0),
                }
            )
        total = max(br.elapsed + self._remaining(br) for br in self._branches)
        done = self._done(i)
        return Advice(
            state=i,
            turn="end" if self.finished else "human",
            done=done,
            parts=placed_parts(self._operations, done),
            tools=self._tools(i),
            running=running,
            robots=[
                {**self._op_dict(o, a), "confirmed": (o, a) in b.confirmed} for o, a in b.commit
            ],
            instruction=instruction,
            options=self._options(told, explain),
            elapsed=b.elapsed,
            bound=total - b.elapsed,
            finished=self.finished,
            deviations=self._deviations,
            turn_model=self.TURN_MODEL.name,
            instructions=instructions,
            finishes=self._finishes(explain),
            budget=states["budget"][i],
            ahead=self._ahead(b) if explain else [],
        )

    def _ahead(self, b: _Branch) -> list[dict]:
        """The plan ahead from branch ``b``: the people's starts so far, then the
        instructions (of the moves with those starts, the fewest deviations, the worst)."""
        first = None
        if b.pending:
            moves = self._consistent(b, set(b.pending))
            if moves:
                calm = min(self._policy["moves"]["deviations"][m] for m in moves)
                first = worst_move(
                    self._policy,
                    [m for m in moves if self._policy["moves"]["deviations"][m] == calm],
                )
        return self._line(line_moves(self._policy, "plan", start=b.state, first=first), b.elapsed)

    def _side(self, i: int, a: int) -> str:
        return "robot" if self._robot[a] else "human"

    def _options(self, told: dict, explain: bool = False) -> list[dict]:
        """Every operation a free person may start now, with the worst case it leads to
        (``explain``: and :meth:`Advisor._explained`)."""
        moves, states = self._policy["moves"], self._policy["states"]
        worst: dict = {}
        for br in self._branches:
            busy = self._busy(br)
            pending = set(br.pending)
            for m in self._consistent(br, pending):
                after = br.elapsed + moves["cost"][m] + states["bound"][moves["next"][m]]
                for o, a, d in moves["starts"][m]:
                    if (o, a) in pending or a in busy:
                        continue
                    w, durations, where = worst.get((o, a), (-math.inf, set(), None))
                    if after > w:
                        w, where = after, (br, m)
                    worst[(o, a)] = (w, durations | {d}, where)
        out = []
        for (o, a), (w, durations, (br, m)) in sorted(worst.items()):
            item = self._person_dict(o, a)
            item.update(
                cost=max(durations),
                durations=sorted(durations),
                worst=w,
                deviation=a in told and told[a] != o,
            )
            if explain:
                item.update(self._explained(br.state, m, br.elapsed))
            out.append(item)
        return out

    def _finishes(self, explain: bool = False) -> list[dict]:
        """The completions the plan can explain next (every branch, given the starts), each
        with the worst case after it (``explain``: and :meth:`Advisor._explained` of the move
        that leads to it: the robots' reply when it comes, the worst line from there)."""
        moves, states = self._policy["moves"], self._policy["states"]
        out: dict = {}
        for br in self._branches:
            pending = set(br.pending)
            for o, a in br.unreported:
                key, w = (o, a, br.elapsed), br.elapsed + self._bound(br.state)
                if w > out.get(key, (-math.inf, None))[0]:
                    out[key] = (w, None)
            if br.unreported:
                continue
            running = self._running(br.state) | pending
            for m in self._consistent(br, pending, exact=True):
                t = br.elapsed + moves["cost"][m]
                after = t + states["bound"][moves["next"][m]]
                for o, a in running - self._running(moves["next"][m]):
                    if after > out.get((o, a, t), (-math.inf, None))[0]:
                        out[(o, a, t)] = (after, (br, m))
        items = []
        for (o, a, t), (w, where) in sorted(out.items(), key=lambda kv: (kv[0][2], kv[0][:2])):
            item = {"operation": self._ops[o], "agent": self._agents[a]}
            item.update(side="robot" if self._robot[a] else "human", time=t, worst=w)
            if explain:
                item.update(
                    {"reply": None, "line": []}
                    if where is None
                    else self._explained(where[0].state, where[1], where[0].elapsed)
                )
            items.append(item)
        return items

    # ------------------------------------------------------------------ observing
    def _take(self, ev: Event) -> None:
        """Take one observation in canonical ids, as :meth:`Advisor.observe` (the rules:
        module docstring)."""
        o, a = self._check(ev)
        what = f"{ev.operation} {ev.kind} by {ev.agent}"
        if self.finished:
            raise ObservationError(f"{what}: the game is over")
        deviations = self._deviations
        kept, errors = [], []
        for br in self._branches:
            try:
                if ev.kind == "started":
                    kept += self._start(br, o, a, what, ev.duration)
                else:
                    kept += self._finish(br, o, a, what)
            except ObservationError as exc:
                errors.append(exc)
        if not kept:
            raise errors[0]
        if ev.kind == "started" and not self._robot[a]:
            told = dict((x, y) for y, x in self._branches[0].told)
            if a in told and told[a] != o:
                deviations += 1
        if ev.time is not None and ev.kind == "finished":
            nearest = min(abs(br.elapsed - ev.time) for br in kept)
            kept = [br for br in kept if abs(br.elapsed - ev.time) <= nearest + 1e-9]
        # The robots do what the advisor answers (the worst branch's commitment).
        kept = sorted(
            set(kept),
            key=lambda br: (-(br.elapsed + self._remaining(br)), br.state),
        )
        head = kept[0]
        self._branches = [br for br in kept if (br.commit, br.told) == (head.commit, head.told)]
        self._deviations = deviations

    def _record(self, ev: Event) -> None:
        self._events.append(ev)

    def _told(self, agent: str) -> list[str]:
        k = self._agent_index.get(agent)
        b = self._branches[0]
        return [self._ops[o] for o, a in b.told if a == k and o >= 0]

    def _pattern(self, op: str):
        """Done or not in each branch; None while it runs, is started or is committed in
        any (:data:`asp.game.alike.Pattern`)."""
        o = self._op_index[op]
        out = []
        for br in self._branches:
            busy = self._running(br.state) | set(br.pending) | set(br.unreported) | set(br.commit)
            if any(x == o for x, _ in busy):
                return None
            out.append(op in self._done(br.state))
        return tuple(out)

    def _start(
        self, br: _Branch, o: int, a: int, what: str, duration: float | None = None
    ) -> list[_Branch]:
        i = br.state
        name = self._ops[o]
        if self._robot[a]:
            if (o, a) in br.confirmed:
                raise ObservationError(f"{what}: {name} by {self._agents[a]} is already running")
            if (o, a) in br.commit:
                return [_replace(br, confirmed=br.confirmed | {(o, a)})]
            plan = ", ".join(f"{self._ops[x]} by {self._agents[y]}" for x, y in br.commit)
            raise ObservationError(
                f"{what} is not the plan's move (the robots' commitment: {plan or 'wait'})"
            )
        if name in self._done(i):
            raise ObservationError(f"{what}: operation {name} is already done")
        running = self._running(i) | set(br.pending)
        for x, y in running:
            if x == o:
                raise ObservationError(
                    f"{what}: operation {name} is already running (by {self._agents[y]})"
                )
            if y == a:
                raise ObservationError(
                    f"{what}: {self._agents[a]} is busy with operation {self._ops[x]}"
                )
        want = set(br.pending) | {(o, a)}
        fixed = br.fixed if duration is None else (*br.fixed, (o, a, duration))
        if self._consistent(br, want, fixed=fixed):
            return [_replace(br, pending=(*br.pending, (o, a)), fixed=fixed)]
        if duration is not None and self._consistent(br, want):
            took = sorted(
                {
                    d
                    for m in self._consistent(br, want)
                    for x, y, d in self._policy["moves"]["starts"][m]
                    if (x, y) == (o, a)
                }
            )
            raise ObservationError(
                f"{what}: duration {duration:g} is not one the plan knows "
                f"({', '.join(f'{d:g}' for d in took)})"
            )
        moves = self._policy["moves"]
        alone = any((o, a) in {(x, y) for x, y, _ in moves["starts"][m]} for m in self._moves(i))
        budget = self._policy["states"]["budget"][i]
        told = dict((y, x) for x, y in br.told)
        if alone:
            raise ObservationError(
                f"{what}: operation {name} cannot start together with "
                + ", ".join(f"{self._ops[x]} by {self._agents[y]}" for x, y in br.pending)
            )
        if budget == 0 and a in told and told[a] != o:
            ask = "wait" if told[a] < 0 else f"do {self._ops[told[a]]}"
            raise ObservationError(
                f"{what}: the plan's deviation budget is spent (the person was asked to {ask})"
            )
        raise ObservationError(f"{what}: operation {name} is not enabled in this state")

    def _finish(self, br: _Branch, o: int, a: int, what: str) -> list[_Branch]:
        if (o, a) in br.unreported:
            return [_replace(br, unreported=br.unreported - {(o, a)})]
        if br.unreported:
            left = ", ".join(f"{self._ops[x]} by {self._agents[y]}" for x, y in br.unreported)
            raise ObservationError(f"{what}: {left} finished at the same time; report it first")
        moves = self._policy["moves"]
        i = br.state
        pending = set(br.pending)
        running = self._running(i) | pending
        if (o, a) not in running:
            now = ", ".join(f"{self._ops[x]} by {self._agents[y]}" for x, y in sorted(running))
            raise ObservationError(f"{what}: it is not running (running: {now or 'nothing'})")
        candidates = self._consistent(br, pending, exact=True)
        if not candidates:
            raise ObservationError(
                f"{what}: the plan has no completion before a free person starts an operation "
                "(a person with something to do does not idle unless asked to wait)"
            )
        out = []
        for m in candidates:
            nxt = moves["next"][m]
            ended = running - self._running(nxt)
            if (o, a) in ended:
                b = self._commit(nxt, br.elapsed + moves["cost"][m])
                out.append(_replace(b, unreported=frozenset(ended - {(o, a)})))
        if not out:
            raise ObservationError(f"{what}: it cannot finish first in the plan (see finishes)")
        return out

    # ------------------------------------------------------------------ helpers
    def _commit(self, i: int, elapsed: float) -> _Branch:
        """The branch after the robots' commitment at robot state ``i`` (or at the end)."""
        r = self._moves(i)
        if len(r) == 0:
            return _Branch(i, elapsed)
        j = r.start
        states, moves = self._policy["states"], self._policy["moves"]
        commit = tuple((o, a) for o, a, _ in moves["starts"][j])
        told = tuple(tuple(x) for x in states["instruction"][i] or ())
        return _Branch(moves["next"][j], elapsed, commit, told)

    def _consistent(
        self, br: _Branch, starts: set, exact: bool = False, fixed: tuple | None = None
    ) -> list[int]:
        """Moves of ``br``'s state that start ``starts`` (and nothing else when ``exact``),
        with the durations observed (``fixed``, default the branch's)."""
        moves = self._policy["moves"]
        fixed = br.fixed if fixed is None else fixed
        out = []
        for m in self._moves(br.state):
            have = {(x, y) for x, y, _ in moves["starts"][m]}
            if not (have == starts if exact else starts <= have):
                continue
            took = {(x, y): d for x, y, d in moves["starts"][m]}
            if all(abs(took[(x, y)] - d) <= 1e-6 for x, y, d in fixed if (x, y) in took):
                out.append(m)
        return out

    def _remaining(self, br: _Branch) -> float:
        """The guaranteed remaining makespan of a branch given the people's starts."""
        moves, states = self._policy["moves"], self._policy["states"]
        pending = set(br.pending)
        if not pending:
            return self._bound(br.state)
        return max(
            (
                moves["cost"][m] + states["bound"][moves["next"][m]]
                for m in self._consistent(br, pending)
            ),
            default=self._bound(br.state),
        )

    def _bound(self, i: int) -> float:
        return self._policy["states"]["bound"][i]

    def _running(self, i: int) -> set:
        return {
            (self._op_index[op], self._agent_index[a])
            for a, op, _ in self._policy["states"]["running"][i]
        }

    def _busy(self, br: _Branch) -> set:
        return {a for _, a in self._running(br.state) | set(br.pending)}

    def _description(self, o: int) -> str:
        return self._operations.get(self._ops[o], {}).get("description", "")


ADVISORS: dict[str, type[Advisor]] = {c.TURN_MODEL.name: c for c in (Advisor, ConcurrentAdvisor)}
"""The advisor class of each turn model (:data:`asp.game.turns.TURNS`): ``Advisor(plan)`` is
one of the plan's."""


def _move(j: int) -> int | None:
    """A move index, or None for ``-1`` (no move)."""
    return None if j < 0 else j


def _replace(br: _Branch, **changes) -> _Branch:
    return replace(br, **changes)


def _distinct(options: list[dict]) -> list[dict]:
    """``options`` without one that is an earlier one's alike twin (the same agent and alike
    operations: a symmetry fixing the state swaps them, so their worst cases agree)."""
    seen, out = set(), []
    for o in options:
        key = (o["agent"], frozenset(o.get("alike", [o["operation"]])))
        if key not in seen:
            seen.add(key)
            out.append(o)
    return out


def _as_alike(exc: ObservationError, physical: str, canonical: str) -> ObservationError:
    """``exc`` about canonical operation ``canonical``, said of the physical one observed."""
    return ObservationError(f"{physical} (alike; the plan's {canonical} here): {exc}")


def _worker_side(worker: str, sides: dict) -> str:
    """The side of a worker of the concurrent game (``A:robot`` / ``A:human`` for side ``any``)."""
    if ":" in worker:
        return worker.rsplit(":", 1)[1]
    return sides.get(worker, "")
