"""Schedules with OR-Tools CP-SAT: the classical baseline (``../shared/DESIGN.md``).

:mod:`~asp.schedule.cpsat` (what the models share), :mod:`~asp.schedule.path` (the
minimum-cost way through a game DAG), :mod:`~asp.schedule.makespan` (the minimum-makespan
model with its lazy-cut loop), :mod:`~asp.schedule.psplib` (PSPLIB ``.sm`` instances),
:mod:`~asp.schedule.assembly` (the scheduling problem of an assembly spec),
:mod:`~asp.schedule.cuts` (short cuts read off the state graph),
:mod:`~asp.schedule.replay` (a schedule replayed through the state graph),
:mod:`~asp.schedule.list_schedule` (a feasible schedule along a path) and
:mod:`~asp.schedule.assembly_makespan` (the makespan stage of ``asmplan plan``).
"""

from asp.lazy import lazy_exports

__all__, __getattr__ = lazy_exports(
    __name__,
    {
        "assembly_makespan": ("AUTO_PATIENCE", "AUTO_TIME_LIMIT", "assembly_makespan"),
        "cpsat": ("BaselineResult",),
        "makespan": ("min_makespan",),
        "path": ("min_cost_path",),
        "psplib": ("read_sm",),
    },
)
