"""Alternating PPO on the concurrent game played on the fly, certified by an exact best response.

The paper's learner (``../shared/DESIGN.md``, "Alternating PPO") where the exact solver
does not reach: the game is never compiled, both sides play it from its rules
(:mod:`arl.concurrent_env`), and each sees the position's features, so the policy network
generalises across states it has not visited.

The loop (:func:`train_concurrent`), per cycle:

1. the robot (sb3-contrib ``MaskablePPO``) trains ``phase_steps`` steps against the human
   model as it is (frozen for the phase, sampling its policy);
2. the human trains ``phase_steps`` steps against the robot model, frozen;
3. the robot's greedy policy is certified: the exact best response of the human side to it
   (:func:`asp.concurrent.certify.certify`) for every budget asked, in spec units; past
   the exact solver's size the budgets whose policy game is too large to walk are dropped,
   ``k = inf`` first (:func:`certify_fitting`). The policy of least certified worst case so
   far (at the largest budget certified, then the others) is the run's answer, saved as
   ``robot.zip``.

The certificate is exact whatever the network learned: it is a third candidate for the
upper bound ``U(k)`` beside the greedy and the CP-SAT schedule policies
(:mod:`asp.concurrent.search`).

Before training, when asked (``max_cycle_seconds``, ``on_estimate``), a cycle's seconds are
estimated from a sample (:func:`estimate_cycle`, said in the words of :mod:`arl.pace`, the
same rule as the alternating trainer's) and a cycle over the limit is refused before the
run folder is touched; while training, a heartbeat line says what the run is doing.

Seeds: ``seed`` fixes torch, numpy and both models; every phase reseeds its model (and so
its environment) from ``(seed, cycle, side)``. Torch runs on one thread on the CPU, so a
seed gives the same log.

The run folder: ``config.json``, ``log.json`` (a record per cycle; format
:data:`RUN_FORMAT`), ``robot.zip`` (the best robot), ``human.zip`` (the last human), each
written atomically after every cycle, the log last.
:func:`load_robot` reads the robot back; :func:`learned_policy` makes it a robot policy
for :func:`asp.concurrent.certify.certify`.
"""

from __future__ import annotations

import dataclasses
import io
import json
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback

from arl.concurrent_env import ConcurrentHumanEnv, ConcurrentRobotEnv, Encoder, robot_choose
from arl.memory import concurrent_training_room
from arl.pace import SAMPLE_STEPS, CycleEstimate, Heartbeat, phase_seconds
from asp.concurrent.certify import certify
from asp.concurrent.rules import Rules

LOG_VERSION = 1
RUN_FORMAT = "asmplan-arl-concurrent-run"
"""The ``format`` of a run folder's ``config.json`` and ``log.json`` (:func:`is_run_folder`)."""


@dataclass(frozen=True)
class ConcurrentConfig:
    """A training run on the concurrent game (the seed aside).

    Attributes
    ----------
    name : str
    net_arch : tuple of int
        Hidden layers of the policy and value networks.
    learning_rate, n_steps, batch_size, n_epochs, gamma, gae_lambda, clip_range, ent_coef
        PPO's (``MaskablePPO``); ``gamma`` 1: the robot's return is minus the makespan.
    phase_steps : int
        Steps each side trains per cycle.
    cycles : int
        Cycles of the run.
    train_budgets : tuple of int or None
        Budgets the training games start at, drawn uniformly (None: ``k = inf``).
    """

    name: str = "concurrent"
    net_arch: tuple[int, ...] = (64, 64)
    learning_rate: float = 1e-3
    n_steps: int = 256
    batch_size: int = 64
    n_epochs: int = 4
    gamma: float = 1.0
    gae_lambda: float = 0.95
    clip_range: float = 0.2
    ent_coef: float = 0.01
    phase_steps: int = 1024
    cycles: int = 9
    train_budgets: tuple = (None,)

    def __post_init__(self) -> None:
        for name in ("n_steps", "batch_size", "n_epochs", "phase_steps", "cycles"):
            if int(getattr(self, name)) < 1:
                raise ValueError(f"{name}: expected a positive integer, got {getattr(self, name)}")
        if not self.train_budgets or any(b is not None and b < 0 for b in self.train_budgets):
            raise ValueError(
                f"train_budgets: expected budgets >= 0 or None, got {self.train_budgets}"
            )

    def replace(self, **changes) -> ConcurrentConfig:
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> ConcurrentConfig:
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise ValueError(f"config: unknown fields {', '.join(unknown)}")
        values = dict(data)
        for name in ("net_arch", "train_budgets"):
            if name in values:
                values[name] = tuple(values[name])
        return cls(**values)


CONFIGS: dict[str, ConcurrentConfig] = {
    "concurrent": ConcurrentConfig(),
    "concurrent-tiny": ConcurrentConfig(
        name="concurrent-tiny", net_arch=(16,), n_steps=32, batch_size=32, phase_steps=64, cycles=2
    ),
}
"""``concurrent``: 9 cycles of 1,024 steps a side (18,432 steps); ``concurrent-tiny`` for
tests."""


def get_config(config: str | ConcurrentConfig) -> ConcurrentConfig:
    """The named configuration, or ``config`` itself."""
    if isinstance(config, ConcurrentConfig):
        return config
    if config not in CONFIGS:
        raise ValueError(f"config: expected one of {', '.join(CONFIGS)}, got {config!r}")
    return CONFIGS[config]


@dataclass(frozen=True, eq=False)
class ConcurrentTrainResult:
    """The outcome of :func:`train_concurrent`.

    Attributes
    ----------
    robot : sb3_contrib.MaskablePPO
        The robot model of least certified worst case (of cycle ``best_cycle``).
    certified : dict
        Budget (None: ``k = inf``) -> that robot's certified worst case (spec units).
    cycles : list of dict
        Per cycle: ``cycle``, ``steps`` (cumulative, both sides), ``seconds`` (cumulative),
        ``robot_makespan`` (mean makespan of the robot's training games), ``certified``
        (``[{"k", "bound"}]``).
    best_cycle : int
    steps : int
        Environment steps of both sides.
    seconds : float
    config : ConcurrentConfig
    """

    robot: object
    certified: dict
    cycles: list
    best_cycle: int
    steps: int
    seconds: float
    config: ConcurrentConfig


def _phase_seed(seed: int, cycle: int, side: int) -> int:
    return int(np.random.SeedSequence([seed, cycle, side]).generate_state(1)[0])


def _model(env, cfg: ConcurrentConfig, seed: int):
    from sb3_contrib import MaskablePPO

    return MaskablePPO(
        "MlpPolicy",
        env,
        learning_rate=cfg.learning_rate,
        n_steps=cfg.n_steps,
        batch_size=cfg.batch_size,
        n_epochs=cfg.n_epochs,
        gamma=cfg.gamma,
        gae_lambda=cfg.gae_lambda,
        clip_range=cfg.clip_range,
        ent_coef=cfg.ent_coef,
        policy_kwargs={"net_arch": list(cfg.net_arch)},
        seed=seed,
        device="cpu",
        verbose=0,
    )


def _key(certified: dict, budgets: list) -> tuple:
    """Order of certificates: the worst case at the last budget asked, then the others."""
    return (certified[budgets[-1]], *(certified[b] for b in budgets))


def learned_policy(rules: Rules, robot):
    """The robot model's greedy moves as a robot policy for
    :func:`asp.concurrent.certify.certify`."""
    return robot_choose(rules, robot, deterministic=True)


def _learners(rules: Rules, cfg: ConcurrentConfig, seed: int):
    """The robot and human models of a run, each playing against the other (torch on one
    thread, every random source seeded from ``seed``)."""
    import torch
    from stable_baselines3.common.utils import set_random_seed

    torch.set_num_threads(1)
    set_random_seed(seed)
    train_budgets = list(cfg.train_budgets)
    robot_env = ConcurrentRobotEnv(rules, budgets=train_budgets)
    human_env = ConcurrentHumanEnv(rules, budgets=train_budgets)
    robot = _model(robot_env, cfg, _phase_seed(seed, 0, 0))
    human = _model(human_env, cfg, _phase_seed(seed, 0, 1))
    robot_env.set_opponent(human)
    human_env.set_opponent(robot)
    return robot, human


DEFAULT_BUDGETS = [0, 1, 2, None]
"""The budgets certified after every cycle unless told (None: ``k = inf``)."""

CERTIFICATE_NODES = 500_000
"""Nodes of a learned robot's policy game at most (:func:`certify_fitting`): past it the
largest budget is left uncertified (the walk is Python, about 5,000 nodes a second with a
network choosing)."""


def budget_order(budgets) -> list:
    """``budgets`` from the smallest to ``None`` (``k = inf``), each once."""
    return sorted(set(budgets), key=lambda b: (b is None, b or 0))


def certify_fitting(
    rules: Rules,
    choose,
    budgets: list[int | None],
    *,
    max_memory: int | None = None,
    max_nodes: int | None = None,
    say: Callable[[str], None] | None = None,
):
    """:func:`asp.concurrent.certify.certify` at the budgets whose policy game fits.

    Tried at every budget at once; while the policy game is over ``max_nodes`` nodes or
    ``max_memory`` bytes (:class:`asp.errors.GameLimit`), the largest budget left is dropped
    (``k = inf`` first: the fully adversarial human's replies are a superset of every
    bounded one's, so its walk is the largest) and the rest tried again; ``say`` is told
    each budget dropped, in one line (``max_nodes``: default :data:`CERTIFICATE_NODES`). A
    product past the exact solver's size keeps the
    budgets that can be certified instead of failing for size alone.

    Returns
    -------
    (asp.concurrent.certify.Certificate, list)
        The certificate and the budgets it holds (ordered, ``None`` last).

    Raises
    ------
    asp.errors.GameLimit
        Not even the smallest budget fits.
    """
    from asp.errors import GameLimit

    most = CERTIFICATE_NODES if max_nodes is None else int(max_nodes)
    kept = budget_order(budgets)
    while True:
        try:
            cert = certify(rules, choose, kept, max_nodes=most, max_memory=max_memory)
            return cert, kept
        except GameLimit as err:
            if len(kept) == 1:
                raise
            dropped = kept.pop()
            if say is not None:
                say(
                    f"k = {'inf' if dropped is None else dropped} not certified ({err}); "
                    f"certified at k = {', '.join(_k_name(b) for b in kept)}"
                )


def _k_name(budget) -> str:
    return "inf" if budget is None else str(budget)


CERTIFICATION = "a certification (exact best response)"
"""What a cycle's check is, in the words of :class:`arl.pace.CycleEstimate`."""


def estimate_cycle(
    rules: Rules,
    config: str | ConcurrentConfig = "concurrent",
    *,
    seed: int = 0,
    budgets: list[int | None] | None = None,
    cycles_left: int | None = None,
    max_memory: int | None = None,
) -> CycleEstimate:
    """The seconds a cycle of :func:`train_concurrent` will take, from a sample.

    The sample: throwaway models of the same configuration but rollouts of at most
    :data:`arl.pace.SAMPLE_STEPS` steps; the robot's phase is run twice (the first warms
    up) and the second timed, and the robot's greedy policy is certified once at
    ``budgets``, those whose policy game fits (:func:`certify_fitting`; ``max_memory``: the
    bytes its policy game may use, default the one rule), timed. A cycle is then both sides'
    ``phase_steps`` (rounded up to whole rollouts) at the measured seconds a step, and one
    certification. Nothing of a run folder is read or written. The untrained
    robot's policy game may be larger or smaller than a trained one's.
    """
    return _estimate(rules, config, seed, budgets, cycles_left, max_memory, None)[0]


def _estimate(rules, config, seed, budgets, cycles_left, max_memory, say):
    """:func:`estimate_cycle` and the budgets its certificate kept (``say``: told each
    budget dropped), so that a run does not try a dropped budget again."""
    cfg = get_config(config)
    budgets = list(budgets) if budgets is not None else list(DEFAULT_BUDGETS)
    k = max(1, min(cfg.n_steps, SAMPLE_STEPS))
    robot, _ = _learners(rules, cfg.replace(n_steps=k, batch_size=min(cfg.batch_size, k)), seed)
    robot.learn(k)  # warms up
    t0 = time.perf_counter()
    robot.learn(k, reset_num_timesteps=False)
    step_s = (time.perf_counter() - t0) / k
    t0 = time.perf_counter()
    _, kept = certify_fitting(
        rules, learned_policy(rules, robot), budgets, max_memory=max_memory, say=say
    )
    check_s = time.perf_counter() - t0
    estimate = CycleEstimate(
        seconds=2 * phase_seconds(cfg.phase_steps, cfg.n_steps, step_s) + check_s,
        step_s=step_s,
        sample_steps=k,
        cycles=cfg.cycles if cycles_left is None else int(cycles_left),
        size=f"{rules.model.n_ops:,} operations, {rules.n_workers} workers",
        check_s=check_s,
        check=CERTIFICATION,
    )
    return estimate, kept


def train_concurrent(
    rules: Rules,
    config: str | ConcurrentConfig = "concurrent",
    *,
    seed: int = 0,
    budgets: list[int | None] | None = None,
    output: Path | None = None,
    progress: bool = False,
    max_cycle_seconds: float | None = None,
    on_estimate: Callable[[CycleEstimate], None] | None = None,
    heartbeat: Callable[[str], None] | None = None,
    max_memory_gb: float | None = None,
) -> ConcurrentTrainResult:
    """Alternating PPO on the concurrent game of ``rules`` (module docstring).

    Its memory is bounded before any work (:func:`arl.memory.concurrent_training_room`: the
    learners refused over ``max_memory_gb``, default :func:`asp.heap.memory_budget`), and
    each certificate's policy game gets what is left
    (:func:`asp.concurrent.certify.certify`'s ``max_memory``).

    Parameters
    ----------
    budgets : list of int or None
        The budgets certified after every cycle (default :data:`DEFAULT_BUDGETS`); the
        largest ranks the cycles' robots. A budget whose policy game is over
        :data:`CERTIFICATE_NODES` nodes or the memory left is dropped for the rest of the
        run, said on stderr (:func:`certify_fitting`).
    output : Path, optional
        The run folder (written after every cycle).
    progress : bool
        A line on stderr per cycle.
    max_cycle_seconds : float, optional
        Refuse (:class:`asp.errors.GameError`, before the run folder is touched) a game
        whose cycle is estimated (:func:`estimate_cycle`) to take longer than this.
    on_estimate : callable, optional
        Called with the :class:`arl.pace.CycleEstimate` once it is within
        ``max_cycle_seconds``; without it and without a limit nothing is estimated.
    heartbeat : callable, optional
        Called every :data:`arl.pace.HEARTBEAT_S` seconds, from the estimate on, with a
        line saying what the run is doing and for how long (:class:`arl.pace.Heartbeat`).
    max_memory_gb : float, optional
        The memory limit (``--max-memory``).

    Raises
    ------
    asp.errors.GameError
        The learners alone are over the memory limit, or a certificate's policy game is
        (:class:`asp.errors.GameLimit`), each one line naming ``--max-memory``.
    """
    cfg = get_config(config)
    budgets = budget_order(budgets if budgets is not None else DEFAULT_BUDGETS)
    room = concurrent_training_room(Encoder(rules).size, cfg, max_memory_gb)
    t0 = time.perf_counter()
    with Heartbeat(heartbeat, lambda: time.perf_counter() - t0) as beat:
        if max_cycle_seconds is not None or on_estimate is not None:
            beat.doing = "estimating a cycle's time (a sample of steps, one certification)"
            estimate, budgets = _estimate(rules, cfg, seed, budgets, None, room, _stderr)
            estimate.refuse_over(max_cycle_seconds)
            if on_estimate is not None:
                on_estimate(estimate)
        return _train(rules, cfg, seed, budgets, output, progress, beat, room)


def _train(rules, cfg, seed, budgets, output, progress, beat, room) -> ConcurrentTrainResult:
    """The loop of :func:`train_concurrent` (``beat``: its heartbeat, told each step)."""
    t0 = time.perf_counter()
    robot, human = _learners(rules, cfg, seed)
    records: list[dict] = []
    best, best_cycle, best_bytes = None, 0, b""
    steps = 0
    for cycle in range(1, cfg.cycles + 1):
        makespans: list[float] = []
        for side, model in ((0, robot), (1, human)):
            beat.doing = f"cycle {cycle} of {cfg.cycles}: the {('robot', 'human')[side]}'s phase"
            model.set_random_seed(_phase_seed(seed, cycle, side))
            callback = _Makespans() if side == 0 else None
            model.learn(cfg.phase_steps, callback=callback, reset_num_timesteps=False)
            if callback is not None:
                makespans = callback.makespans
        steps = int(robot.num_timesteps + human.num_timesteps)
        beat.doing = f"cycle {cycle} of {cfg.cycles}: {CERTIFICATION}"
        cert, budgets = certify_fitting(
            rules, learned_policy(rules, robot), budgets, max_memory=room, say=_stderr
        )
        record = {
            "cycle": cycle,
            "steps": steps,
            "seconds": round(time.perf_counter() - t0, 3),
            "robot_makespan": float(np.mean(makespans)) if makespans else None,
            "certified": cert.to_list(),
        }
        records.append(record)
        if best is None or _key(cert.worst, budgets) < _key(best, budgets):
            best, best_cycle, best_bytes = dict(cert.worst), cycle, _model_bytes(robot)
        if progress:
            shown = ", ".join(_k_text(r) for r in record["certified"])
            print(
                f"  cycle {cycle}/{cfg.cycles}: {steps:,} steps, {record['seconds']:.0f} s, "
                f"certified {shown}",
                file=sys.stderr,
                flush=True,
            )
        if output is not None:
            _save(Path(output), cfg, seed, budgets, records, best_cycle, best_bytes, human)
    from sb3_contrib import MaskablePPO

    best_robot = MaskablePPO.load(io.BytesIO(best_bytes), device="cpu")
    return ConcurrentTrainResult(
        robot=best_robot,
        certified=best,
        cycles=records,
        best_cycle=best_cycle,
        steps=steps,
        seconds=time.perf_counter() - t0,
        config=cfg,
    )


def _stderr(line: str) -> None:
    print(f"  {line}", file=sys.stderr, flush=True)


class _Makespans(BaseCallback):
    """Keeps the makespan of every training game the robot finished."""

    def __init__(self):
        super().__init__()
        self.makespans: list[float] = []

    def _on_step(self) -> bool:
        for info in self.locals.get("infos", []):
            if "makespan" in info:
                self.makespans.append(float(info["makespan"]))
        return True


def _k_text(row: dict) -> str:
    return f"k={_k_name(row['k'])}: {row['bound']:g}"


def _model_bytes(model) -> bytes:
    buf = io.BytesIO()
    model.save(buf)
    return buf.getvalue()


def _save(folder: Path, cfg, seed, budgets, records, best_cycle, robot_bytes, human) -> None:
    from asp.atomic import write_bytes, write_text

    folder.mkdir(parents=True, exist_ok=True)
    head = {"format": RUN_FORMAT, "version": LOG_VERSION}
    config = {**head, "seed": seed, "budgets": budgets, "config": cfg.to_dict()}
    write_text(folder / "config.json", json.dumps(config, indent=1) + "\n")
    write_bytes(folder / "robot.zip", robot_bytes)
    write_bytes(folder / "human.zip", _model_bytes(human))
    log = {**head, "best_cycle": best_cycle, "cycles": records}  # last: it names robot.zip
    write_text(folder / "log.json", json.dumps(log, indent=1) + "\n")


def is_run_folder(folder: Path) -> bool:
    """Whether ``folder`` holds a run of :func:`train_concurrent` (its ``config.json``)."""
    path = Path(folder) / "config.json"
    try:
        return json.loads(path.read_text()).get("format") == RUN_FORMAT
    except (OSError, ValueError, AttributeError):
        return False


def load_robot(folder: Path):
    """The best robot model of a run folder written by :func:`train_concurrent`.

    Raises
    ------
    ValueError
        ``folder`` is not such a run folder.
    """
    from sb3_contrib import MaskablePPO

    folder = Path(folder)
    path = folder / "robot.zip"
    if not is_run_folder(folder) or not path.is_file():
        raise ValueError(f"{folder}: not a concurrent run folder (no config.json, robot.zip)")
    return MaskablePPO.load(path, device="cpu")
