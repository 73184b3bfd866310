"""The concurrent game: the human and the robots working at once (turn model ``concurrent``).

Semantics (``../shared/DESIGN.md``, "The concurrent game"):

- Each agent (a *worker*) does one operation at a time, taking its duration. An agent of
  side ``any`` (every task of a ``.IN2`` graph) is one worker of each side, ``A:human`` and
  ``A:robot``, as in the CP-SAT schedule.
- A state is the assembly state (done operations and tool values, a node of the state
  graph), and for each busy worker its operation and the time it still needs, and the
  deviations the human side may still make (the budget ``b``; :data:`UNBOUNDED` for the
  fully adversarial human).
- Decisions are taken at events (the start and every completion). The robot side commits
  first: an operation or *wait* for each free robot and, when the budget is finite, an
  instruction (an operation or wait) for each free human. Then the human side, knowing it,
  starts operations on its free humans and picks their durations. A free human following
  its instruction is free of charge; doing anything else is one deviation (at most ``b``).
  A human that deviates or has no instruction does not idle while it has an operation it may
  start. Waiting is allowed only while something runs.
- Two operations run at the same time only if each is feasible whichever finishes first:
  with ``D`` done and the set ``A`` running, every ``D + T`` (``T`` a subset of ``A``) is a
  state of the state graph from which each operation of ``A - T`` is an edge
  (:func:`asp.graph.together.together`, the one place this rule is written: both builders and
  the schedule replay call it), and no
  operation changes a tool another one needs or changes. Every
  state entered must still be completable (the state graph's co-reachable states).
- The human's duration may be a range ``[min, max]``. The adversary picks it on the grid
  ``min, min + step, ..., max`` (``max`` always included; ``step`` defaults to the time
  unit 1). With every duration a whole number of steps this is exact: the game is then in
  discrete time, every event falls on the grid. For real-valued durations it is a lower
  bound of the adversary's supremum (a completion just before another event can be worse
  than one exactly at it). ``step=None`` uses the two end points only (a cheaper lower bound).
- The cost is the makespan. The robot side minimises it, the human side maximises it.

The rooms, in the order they build on each other: :mod:`asp.concurrent.model` (the spec
and state graph compiled), :mod:`asp.concurrent.build` (the game DAG, with its numba
builder :mod:`asp.concurrent.kernel` beside it), :mod:`asp.concurrent.robustness` (the
curve and what a policy guarantees), :mod:`asp.concurrent.describe` (the game read back)
the on-the-fly search :mod:`asp.concurrent.search` (``W*(k)`` without compiling the game,
exact or a certified interval) and :mod:`asp.concurrent.plan` (the concurrent plan of an
assembly). The CP-SAT makespan
stage it is compared with is :mod:`asp.schedule.assembly_makespan`.
"""

from asp.lazy import lazy_exports

__all__, __getattr__ = lazy_exports(
    __name__,
    {
        "build": ("build_game",),
        "describe": (
            "Bar",
            "PolicyNames",
            "commit_description",
            "move_starts",
            "policy_names",
            "state_description",
        ),
        "model": ("WAIT", "concurrent_model"),
        "plan": (
            "ConcurrentPlan",
            "exact_curve",
            "plan_concurrent",
            "plan_entries",
            "robustness_table",
            "timeline_text",
        ),
        "robustness": ("DEFAULT_MAX_K", "certified_worst_case", "policy_array", "schedule_rule"),
        "curve": ("Curve", "solve_curve"),
        "search": ("Limits",),
        "rules": (
            "NONE",
            "Position",
            "Rules",
            "commit_rows",
            "committed_row",
            "concurrent_rules",
            "lower_bound_of",
            "reply_rows",
        ),
    },
)
