"""One experiment task: generate a synthetic graph, solve it, train on it, measure it.

A task is a (experiment, graph configuration, trial) triple with everything that decides
its result: the base seed, the solver(s) and the ARL configuration. Tasks are independent,
so any backend may run them in any order on any machine and get the same numbers.

Seeds
-----
Every task derives its own seeds from the base seed with numpy's ``SeedSequence``::

    SeedSequence(entropy=base_seed,
                 spawn_key=(EXPERIMENT_KEYS[experiment], layers, max_nodes, max_actions,
                            trial)).generate_state(3)  # -> graph, train, games seeds

(uint32 words). The graph seed feeds :func:`asp.game.synth.synthetic_dag`, the train seed
:func:`arl.train`, the games seed the 1,000-game random-human simulation.
"""

from __future__ import annotations

import os
import platform
import time
from contextlib import contextmanager
from dataclasses import asdict, dataclass, fields, make_dataclass
from enum import StrEnum

import numpy as np

from asp.game.metrics import PlanMetrics

EXPERIMENT_KEYS = {"table3": 3, "table4": 4}
"""Spawn-key component of each experiment (its table number in the paper)."""

TASK_FORMAT = "asmplan-experiment-task/1"
"""The ``format`` of a task file (``tasks/<task id>.json``)."""


class Solver(StrEnum):
    """Which planner(s) a task runs."""

    exact = "exact"
    arl = "arl"
    both = "both"

    @property
    def runs(self) -> tuple[str, ...]:
        """The planners to run, ARL first (the paper's method), then the exact one."""
        return {"exact": ("exact",), "arl": ("arl",), "both": ("arl", "exact")}[self.value]


@dataclass(frozen=True)
class GraphConfig:
    """Parameters of a synthetic graph (``../shared/DESIGN.md``, "Synthetic DAGs")."""

    layers: int
    max_nodes: int
    max_actions: int = 4

    @property
    def label(self) -> str:
        """The paper's row label, ``"layers/max nodes"``."""
        return f"{self.layers}/{self.max_nodes}"


TABLE3_CONFIGS: tuple[GraphConfig, ...] = tuple(
    GraphConfig(layers, max_nodes)
    for layers, max_nodes in ((4, 10), (10, 4), (10, 10), (15, 10), (20, 10), (20, 20))
)
"""The six configurations of the paper's Table 3."""

TABLE4_CONFIG = GraphConfig(20, 10)
"""The configuration of the paper's repeated experiment (Table 4)."""


@dataclass(frozen=True)
class TaskSeeds:
    """The seeds one task uses (see the module docstring for the derivation)."""

    graph: int
    train: int
    games: int


@dataclass(frozen=True)
class TaskSpec:
    """Everything that decides the result of one task.

    Attributes
    ----------
    experiment : str
        ``"table3"`` or ``"table4"``.
    graph : GraphConfig
    trial : int
        1-based trial number within the configuration.
    base_seed : int
        The sweep's seed; the task's own seeds derive from it (:attr:`seeds`).
    solver : str
        ``"exact"``, ``"arl"`` or ``"both"``.
    config : str
        The ARL configuration (``"paper"`` or ``"fast"``); unused by ``exact``.
    n_games : int
        Random-human games of the paper's seeded simulation.
    """

    experiment: str
    graph: GraphConfig
    trial: int
    base_seed: int = 0
    solver: str = "both"
    config: str = "paper"
    n_games: int = 1000

    def __post_init__(self) -> None:
        if self.experiment not in EXPERIMENT_KEYS:
            raise ValueError(
                f"experiment: expected one of {', '.join(EXPERIMENT_KEYS)}, got {self.experiment!r}"
            )
        Solver(self.solver)  # raises ValueError on an unknown solver
        if self.trial < 1:
            raise ValueError(f"trial: expected a positive integer, got {self.trial}")
        if self.base_seed < 0:
            raise ValueError(f"seed: expected a non-negative integer, got {self.base_seed}")
        if self.n_games < 1:
            raise ValueError(f"games: expected a positive integer, got {self.n_games}")

    @property
    def task_id(self) -> str:
        """File-name-safe identity within a sweep, e.g. ``table4-L20-M10-A4-t03``."""
        g = self.graph
        return f"{self.experiment}-L{g.layers}-M{g.max_nodes}-A{g.max_actions}-t{self.trial:02d}"

    @property
    def sweep(self) -> dict[str, object]:
        """What the tasks of one sweep share, by command-line flag: the results of two specs
        with different sweeps never share an output folder."""
        return {
            "experiment": self.experiment,
            "--seed": self.base_seed,
            "--solver": self.solver,
            "--config": self.config,
            "--games": self.n_games,
        }

    @property
    def seeds(self) -> TaskSeeds:
        """The task's graph, training and simulation seeds."""
        g = self.graph
        key = (EXPERIMENT_KEYS[self.experiment], g.layers, g.max_nodes, g.max_actions, self.trial)
        words = np.random.SeedSequence(entropy=self.base_seed, spawn_key=key).generate_state(3)
        return TaskSeeds(*(int(w) for w in words))

    def to_dict(self) -> dict:
        """A JSON-ready dict (the inverse of :meth:`from_dict`)."""
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> TaskSpec:
        """Rebuild a spec written by :meth:`to_dict`."""
        data = dict(data)
        data["graph"] = GraphConfig(**data["graph"])
        return cls(**data)


def make_specs(
    experiment: str,
    *,
    trials: int,
    base_seed: int = 0,
    solver: str = "both",
    config: str = "paper",
    n_games: int = 1000,
) -> list[TaskSpec]:
    """The tasks of a sweep: every configuration of the experiment times ``trials``.

    ``table3`` runs the paper's six configurations, ``table4`` the 20/10 one; the order is
    configuration-major, as in the paper's tables.
    """
    if trials < 1:
        raise ValueError(f"trials: expected a positive integer, got {trials}")
    if experiment not in EXPERIMENT_KEYS:
        raise ValueError(f"experiment: expected table3 or table4, got {experiment!r}")
    configs = TABLE3_CONFIGS if experiment == "table3" else (TABLE4_CONFIG,)
    return [
        TaskSpec(experiment, graph, trial, base_seed, solver, config, n_games)
        for graph in configs
        for trial in range(1, trials + 1)
    ]


ROW_METRICS = (
    "nodes",
    "edges",
    "tct",
    "minimax",
    "wcpl",
    "certified_wcpl",
    "robust_optimal",
    "max_random",
    "avg_random",
    "rr",
    "rr_certified",
    "max_random_sampled",
    "avg_random_sampled",
    "rr_sampled",
    "adversarial_tax",
)
"""The :class:`asp.game.metrics.PlanMetrics` fields a row carries, in ``results.csv`` order."""


def _row_fields() -> list[tuple[str, object]]:
    metric_types = {f.name: f.type for f in fields(PlanMetrics)}
    identity = [
        ("experiment", str),
        ("config", str),
        ("layers", int),
        ("max_nodes", int),
        ("max_actions", int),
        ("trial", int),
        ("graph_seed", int),
        ("solver", str),
    ]
    training = [
        ("converged", bool | None),
        ("cycles", int | None),
        ("timesteps", int | None),
        ("train_s", float),
    ]
    return [*identity, *((name, metric_types[name]) for name in ROW_METRICS), *training]


def _comparable(self) -> dict:
    """The row without its timing fields: equal for equal specs on any backend."""
    return {k: v for k, v in asdict(self).items() if k not in self.TIMING_FIELDS}


def _field_names(cls) -> list[str]:
    """Column names, in ``results.csv`` order."""
    return [f.name for f in fields(cls)]


ResultRow = make_dataclass(
    "ResultRow",
    _row_fields(),
    frozen=True,
    namespace={
        "__module__": __name__,
        "__doc__": """The metrics of one planner on one graph: a row of ``results.csv``.

    The task's identity, then the :data:`ROW_METRICS` fields of
    :class:`asp.game.metrics.PlanMetrics` (declared there once), then the training figures.
    ``wcpl`` is the paper's WCPL: learned robot against learned human for ``arl``, the
    minimax value W* for ``exact``. ``rr`` is the exact share of random-human games with
    cost <= ``wcpl`` (the paper's RR), ``rr_certified`` the share within the certified WCPL
    (1 by construction), ``*_sampled`` the paper's seeded 1,000-game simulation.
    ``train_s`` is the training (``arl``) or solving (``exact``) wall time.
    """,
        "TIMING_FIELDS": ("train_s",),
        "comparable": _comparable,
        "field_names": classmethod(_field_names),
    },
)


@dataclass(frozen=True)
class TaskResult:
    """What one task produced: a row per planner, and the ARL training curves."""

    spec: TaskSpec
    rows: tuple[ResultRow, ...]
    episode_rewards: dict[str, tuple[float, ...]] | None = None
    """``{"robot": ..., "human": ...}`` per-episode rewards of the ARL run, else ``None``."""
    host: str = ""
    wall_s: float = 0.0

    def to_dict(self) -> dict:
        """A JSON-ready dict (the inverse of :meth:`from_dict`)."""
        return {
            "format": TASK_FORMAT,
            "spec": self.spec.to_dict(),
            "rows": [asdict(r) for r in self.rows],
            "episode_rewards": (
                None
                if self.episode_rewards is None
                else {k: list(v) for k, v in self.episode_rewards.items()}
            ),
            "host": self.host,
            "wall_s": self.wall_s,
        }

    @classmethod
    def from_dict(cls, data: dict) -> TaskResult:
        """Rebuild a result written by :meth:`to_dict`."""
        rewards = data.get("episode_rewards")
        return cls(
            spec=TaskSpec.from_dict(data["spec"]),
            rows=tuple(ResultRow(**r) for r in data["rows"]),
            episode_rewards=None
            if rewards is None
            else {k: tuple(float(x) for x in v) for k, v in rewards.items()},
            host=data.get("host", ""),
            wall_s=float(data.get("wall_s", 0.0)),
        )


def require_trainer():
    """Return :func:`arl.train`, or raise ``ValueError`` saying it is not available."""
    try:  # from the module, not ``arl.train``: works even where arl is a namespace package
        from arl.trainer import train
    except ImportError as exc:  # the trainer is a separate piece of arl
        raise ValueError(f"the ARL trainer is not available ({exc}); use --solver exact") from None
    return train


def run_task(spec: TaskSpec) -> TaskResult:
    """Run one task: build its graph, solve it exactly, train ARL on it, measure both.

    ARL trains with torch on one thread on every backend: each core runs a task of its own,
    and the same thread count keeps the floating-point results (hence the learned
    policies) the same in this process, a process pool and a Ray cluster.

    Parameters
    ----------
    spec : TaskSpec

    Returns
    -------
    TaskResult
    """
    from asp.game.metrics import plan_metrics
    from asp.game.solve import solve
    from asp.game.synth import synthetic_dag

    start = time.perf_counter()
    seeds = spec.seeds
    g = spec.graph
    dag = synthetic_dag(g.layers, g.max_nodes, g.max_actions, seed=seeds.graph)
    t0 = time.perf_counter()
    solution = solve(dag)
    solve_s = time.perf_counter() - t0

    rows: list[ResultRow] = []
    rewards = None
    for solver in Solver(spec.solver).runs:
        if solver == "exact":
            metrics = plan_metrics(dag, solution=solution, n_games=spec.n_games, seed=seeds.games)
            rows.append(_row(spec, seeds, "exact", metrics, train_s=solve_s))
            continue
        train = require_trainer()
        with one_torch_thread():
            trained = train(dag, config=spec.config, seed=seeds.train)
        policy = np.asarray(trained.robot_policy, dtype=np.int64)
        metrics = plan_metrics(
            dag,
            solution=solution,
            robot_policy=policy,
            wcpl=float(trained.wcpl),
            n_games=spec.n_games,
            seed=seeds.games,
        )
        cycles = list(trained.cycles)
        rows.append(
            _row(
                spec,
                seeds,
                "arl",
                metrics,
                train_s=float(trained.wall_s),
                converged=bool(trained.converged),
                cycles=len(cycles),
                timesteps=int(cycles[-1].get("timesteps", 0)) if cycles else 0,
            )
        )
        rewards = {
            side: tuple(float(x) for x in trained.episode_rewards.get(side, ()))
            for side in ("robot", "human")
        }
    return TaskResult(
        spec=spec,
        rows=tuple(rows),
        episode_rewards=rewards,
        host=platform.node() or str(os.getpid()),
        wall_s=time.perf_counter() - start,
    )


@contextmanager
def one_torch_thread():
    """Run the block with torch on one intra-op thread; restore the previous count after."""
    import torch

    previous = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(previous)


def _row(spec, seeds, solver, m, *, train_s, converged=None, cycles=None, timesteps=None):
    g = spec.graph
    return ResultRow(
        experiment=spec.experiment,
        config=g.label,
        layers=g.layers,
        max_nodes=g.max_nodes,
        max_actions=g.max_actions,
        trial=spec.trial,
        graph_seed=seeds.graph,
        solver=solver,
        **{name: getattr(m, name) for name in ROW_METRICS},
        converged=converged,
        cycles=cycles,
        timesteps=timesteps,
        train_s=float(train_s),
    )
