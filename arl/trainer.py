"""Alternating PPO (paper, section 3.4, Figure 5), certified against the exact game.

Each cycle trains the robot against the frozen human, then the human against the frozen
robot, both with SB3 PPO; after each cycle the greedy policies are tabulated over all nodes
and scored exactly with :mod:`asp.game.solve`: the WCPL of greedy robot vs greedy human (the
paper's) and the certified WCPL of the robot against an exact best-response human.

The stop rule never looks at the exact solution: it reads the rewards (``paper``) or the
stability of the learned policies (``fast``), see :class:`arl.config.TrainConfig`.

Reproducibility: every phase reseeds numpy, torch, the model's action space and the
environments from ``(seed, cycle, side)`` and starts fresh games, so the same seed gives
the same cycle log (with deterministic torch settings), and a resumed run continues exactly
as the uninterrupted run would have.

Layout: :func:`train` reads as the loop (a :class:`_Run` holds the run's state between
cycles; :func:`_train_cycle` and :func:`_train_phase` are one cycle and one side's phase);
the stop rule is :func:`should_stop`; the run folder, whose checkpoints are committed as one
unit after every cycle, is :mod:`arl.runfolder`.
"""

from __future__ import annotations

import hashlib
import json
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.logger import Logger, TensorBoardOutputFormat
from stable_baselines3.common.vec_env import DummyVecEnv, VecEnv, VecEnvWrapper

from arl.config import TrainConfig, get_config
from arl.envs import GameVecEnv, Observer, TurnEnv
from arl.memory import check_training_size
from arl.moves import AGENTS, NO_MOVE, GameTables
from arl.pace import SAMPLE_STEPS, CycleEstimate, Heartbeat, phase_seconds
from arl.runfolder import LOG_FORMAT, RunFolder, refuse_existing_run
from arl.tabulate import action_probabilities, tabulate, tabulation_seconds
from asp.game import rules
from asp.game.dag import HUMAN, ROBOT, GameDAG
from asp.game.metrics import is_robust_optimal
from asp.game.solve import certified_worst_case, play, solve
from asp.game.turns import turn_of
from asp.numbers import plain

LOG_VERSION = 1
CycleCallback = Callable[[dict], bool | None]
"""Called after every cycle with its log record; returning ``False`` stops training."""


@dataclass(frozen=True, eq=False)
class TrainResult:
    """The outcome of :func:`train`.

    Attributes
    ----------
    robot_policy, human_policy : (n,) int64
        Greedy tabulated policies as edge indices (``NO_MOVE = -1`` where the side has no
        move).
    cycles : list of dict
        Per cycle: ``cycle``, ``robot_mean_reward``, ``human_mean_reward``, ``wcpl``,
        ``certified_wcpl``, ``wall_s`` (of the cycle), ``elapsed_s``, ``timesteps``
        (cumulative, both sides), ``robot_episodes``, ``human_episodes``, ``policy_hash``.
    episode_rewards : dict
        ``{"robot": [...], "human": [...]}``: the reward of every training game played from
        the start (Figure 11 of the paper).
    wall_s : float
        Training time, over all runs of a resumed training.
    converged : bool
        Whether the stop rule fired (else ``max_cycles`` or the callback ended it).
    wcpl : float
        Cost of greedy robot vs greedy human (:func:`asp.game.solve.play`).
    certified_wcpl : float
        Cost of the greedy robot against an exact best-response human.
    minimax : float
        The game value W* (for reference; never used in training).
    config : TrainConfig
    seed : int
    output : Path or None
    models : dict
        ``{"robot": model, "human": model}`` (SB3 models; ``None`` for a side without
        moves).
    """

    robot_policy: np.ndarray
    human_policy: np.ndarray
    cycles: list[dict]
    episode_rewards: dict[str, list[float]]
    wall_s: float
    converged: bool
    wcpl: float
    certified_wcpl: float
    minimax: float
    config: TrainConfig
    seed: int
    output: Path | None = None
    models: dict[str, Any] = field(default_factory=dict, repr=False)

    @property
    def robust_optimal(self) -> bool:
        """Whether the certified WCPL equals W*."""
        return is_robust_optimal(self.certified_wcpl, self.minimax)


class _ScaledRewards(VecEnvWrapper):
    """The rewards PPO learns from, divided by ``scale`` (``info["episode"]`` keeps the
    game's units)."""

    def __init__(self, venv: VecEnv, scale: float) -> None:
        super().__init__(venv)
        self.scale = scale

    def reset(self):
        return self.venv.reset()

    def step_wait(self):
        obs, rewards, dones, infos = self.venv.step_wait()
        return obs, rewards / self.scale, dones, infos


class _EpisodeRecorder(BaseCallback):
    """Collects the ``info["episode"]`` rewards of the games played during ``learn``."""

    def __init__(self) -> None:
        super().__init__()
        self.rewards: list[float] = []

    def _on_step(self) -> bool:
        for info in self.locals.get("infos", ()):
            if "episode" in info:
                self.rewards.append(float(info["episode"]["r"]))
        return True


# ---------------------------------------------------------------------------- helpers


def graph_summary(dag: GameDAG) -> dict:
    """Size, ends, cost model and a fingerprint of the arrays (checked on resume)."""
    digest = hashlib.sha256()
    # Hashed as int64 / float64 whatever the DAG stores (asp.game.dag keeps them narrow when
    # exact), so a fingerprint depends on the game only.
    arrays = ((dag.indptr, np.int64), (dag.targets, np.int64), (dag.costs, np.float64))
    for arr, dtype in (*arrays, (dag.sides, np.int8)):
        digest.update(np.ascontiguousarray(arr, dtype=dtype).tobytes())
    digest.update(f"{dag.start},{dag.end}".encode())
    return {
        "nodes": dag.n_nodes,
        "edges": dag.n_edges,
        "start": plain(dag.node_ids[dag.start]),
        "end": plain(dag.node_ids[dag.end]),
        "cost_model": dag.cost_model,
        "fingerprint": digest.hexdigest()[:16],
        "metadata": json.loads(json.dumps(dag.metadata, default=str)),
    }


def _phase_seed(seed: int, cycle: int, player: int) -> int:
    return int(np.random.SeedSequence([seed, cycle, player]).generate_state(1)[0])


def _algo_class(config: TrainConfig):
    if config.algo == "maskable_ppo":
        from sb3_contrib import MaskablePPO

        return MaskablePPO
    from stable_baselines3 import PPO

    return PPO


def _make_env(dag: GameDAG, player: int, config: TrainConfig, seed: int) -> VecEnv:
    if config.vectorized:
        return GameVecEnv(
            dag,
            AGENTS[player],
            config.n_envs,
            obs=config.obs,
            reward=config.reward,
            explore_starts=config.explore_starts,
            seed=seed,
        )

    def factory() -> TurnEnv:
        return TurnEnv(
            dag,
            AGENTS[player],
            obs=config.obs,
            reward=config.reward,
            explore_starts=config.explore_starts,
            opponent_deterministic=config.opponent_deterministic,
        )

    return DummyVecEnv([factory])


def _make_model(config: TrainConfig, env: VecEnv, seed: int):
    return _algo_class(config)(
        "MlpPolicy",
        env,
        learning_rate=config.learning_rate,
        n_steps=config.n_steps,
        batch_size=config.batch_size,
        n_epochs=config.n_epochs,
        gamma=config.gamma,
        gae_lambda=config.gae_lambda,
        clip_range=config.clip_range,
        ent_coef=config.ent_coef,
        policy_kwargs={"net_arch": list(config.net_arch)},
        seed=seed,
        device="cpu",
        verbose=0,
    )


def robot_reach(tables: GameTables, robot_policy: np.ndarray) -> np.ndarray:
    """(n,) bool: nodes where the robot is on turn, with a move, in some state reachable
    when it follows ``robot_policy`` against any human (:func:`asp.game.rules.reachable_states`)."""
    seen = rules.reachable_states(tables.dag, robot_policy)
    return seen[:, ROBOT] & tables.can_move[ROBOT]


def policy_hash(tables: GameTables, robot_policy: np.ndarray) -> str:
    """Short digest of the robot's moves at the states it can reach (the stop rule's key)."""
    reach = robot_reach(tables, robot_policy)
    data = np.where(reach, robot_policy, -2).astype(np.int64).tobytes()
    return hashlib.sha256(data).hexdigest()[:12]


def should_stop(cycles: list[dict], config: TrainConfig) -> bool:
    """The stop rule of ``config`` applied to the cycle log so far."""
    w = config.window
    if len(cycles) < max(w, config.min_cycles):
        return False
    last = cycles[-w:]
    if config.stop == "policy":
        keys = {(c["policy_hash"], c["wcpl"]) for c in last}
        return len(keys) == 1
    for key in ("robot_mean_reward", "human_mean_reward"):
        values = [c[key] for c in last]
        if any(v is None or not np.isfinite(v) for v in values):
            if key == "human_mean_reward" and all(v is None for v in values):
                continue  # the human never moves: only the robot's rewards count
            return False
        if max(values) - min(values) > config.tolerance:
            return False
    return True


def _mean(values: list[float]) -> float | None:
    return float(np.mean(values)) if values else None


# ---------------------------------------------------------------------------- training


@dataclass(eq=False)
class _Run:
    """The state of a training run between cycles (what a checkpoint saves)."""

    dag: GameDAG
    cfg: TrainConfig
    seed: int
    tables: GameTables
    observer: Observer
    summary: dict
    minimax: float
    envs: dict[int, VecEnv]
    models: dict[int, Any]
    reward_scale: float = 1.0
    cycles: list[dict] = field(default_factory=list)
    rewards: dict[str, list[float]] = field(default_factory=lambda: {"robot": [], "human": []})
    wall_before: float = 0.0
    converged: bool = False
    stopped: bool = False
    started: float = field(default_factory=time.perf_counter)
    doing: str = "starting"
    """What the run is doing now (``cycle 3 of 100: the robot's phase``), for the heartbeat."""

    def elapsed(self) -> float:
        """Training time so far, over all runs of a resumed training."""
        return self.wall_before + time.perf_counter() - self.started

    def learning_env(self, player: int) -> VecEnv:
        """The side's environment as PPO sees it (rewards scaled by ``reward_scale``)."""
        env = self.envs[player]
        return env if self.reward_scale == 1.0 else _ScaledRewards(env, self.reward_scale)

    def greedy(self, player: int) -> np.ndarray:
        """(n,) the side's greedy policy as edge indices (``NO_MOVE`` for a side without moves)."""
        if player not in self.models:
            return np.full(self.tables.n, NO_MOVE, dtype=np.int64)
        return tabulate(self.models[player], self.tables, player, self.observer)

    def log(self) -> dict:
        """The content of ``log.json``."""
        return {
            "format": LOG_FORMAT,
            "version": LOG_VERSION,
            "seed": self.seed,
            "config": self.cfg.to_dict(),
            "graph": self.summary,
            "minimax": self.minimax,
            "converged": self.converged,
            "wall_s": self.cycles[-1]["elapsed_s"] if self.cycles else self.wall_before,
            "cycles": self.cycles,
            "robot_policy": self.greedy(ROBOT).tolist(),
            "human_policy": self.greedy(HUMAN).tolist(),
            "episode_rewards": self.rewards,
        }


def train(
    dag: GameDAG,
    config: str | TrainConfig = "paper",
    seed: int = 0,
    output: str | Path | None = None,
    progress: bool = False,
    resume: bool = False,
    callback: CycleCallback | None = None,
    max_memory_gb: float | None = None,
    max_cycle_seconds: float | None = None,
    on_estimate: Callable[[CycleEstimate], None] | None = None,
    heartbeat: Callable[[str], None] | None = None,
    force: bool = False,
) -> TrainResult:
    """Train a robust robot policy by alternating PPO against a learned adversarial human.

    Parameters
    ----------
    dag : GameDAG
        Any game DAG (synthetic, assembly-derived, ``steps`` or ``time`` costs).
    config : "paper", "fast" or TrainConfig
    seed : int
        Seeds models, environments, numpy and torch.
    output : path, optional
        Run folder (:mod:`arl.runfolder`): ``robot.zip``, ``human.zip``, ``log.json``
        committed as one checkpoint after every cycle, ``tb/``, ``rewards.png``.
    progress : bool
        Show a tqdm bar of cycles.
    resume : bool
        Continue the run saved in ``output`` (same graph, seed and config but for
        ``max_cycles``) from its last committed cycle.
    force : bool
        Without ``resume``: replace a run already in ``output`` (else refused,
        :func:`arl.runfolder.refuse_existing_run`).
    callback : callable, optional
        ``callback(record) -> bool | None`` after each cycle; ``False`` stops training.
    max_memory_gb : float, optional
        Refuse (before anything heavy runs) a game whose estimated training memory is over
        this (default: :func:`asp.heap.memory_budget`, 3/4 of the memory available;
        :mod:`arl.memory`).
    max_cycle_seconds : float, optional
        Refuse (:class:`asp.errors.GameError`, before the run folder is touched) a game
        whose cycle is estimated (:func:`estimate_cycle`) to take longer than this.
    on_estimate : callable, optional
        Called with the :class:`CycleEstimate` once it is within ``max_cycle_seconds``
        (``asmplan train`` says it on stderr); without it and without a limit nothing is
        estimated.
    heartbeat : callable, optional
        Called every :data:`arl.pace.HEARTBEAT_S` seconds while training with a line
        saying what the run is doing and for how long (:class:`arl.pace.Heartbeat`), so a
        long cycle is never silent.

    Returns
    -------
    TrainResult
    """
    cfg = get_config(config, dag.metadata.get("turn_model"))
    if resume and output is None:
        raise ValueError("resume: expected an output folder to resume from")
    if not resume:
        refuse_existing_run(output, force=force)
    check_training_size(dag, cfg, max_memory_gb)
    folder = None if output is None else RunFolder(output)
    if max_cycle_seconds is not None or on_estimate is not None:
        done = 0
        if resume:  # a run that cannot be resumed says so first
            folder.recover()
            done = len(_check_resume(folder, graph_summary(dag), seed, cfg)["cycles"])
        estimate = estimate_cycle(dag, cfg, seed, cycles_left=max(0, cfg.max_cycles - done))
        estimate.refuse_over(max_cycle_seconds)
        if on_estimate is not None:
            on_estimate(estimate)
    run = _start_run(dag, cfg, seed, folder, resume)
    beat = Heartbeat(heartbeat, run.elapsed, lambda: run.doing)
    try:
        bar = _progress(range(len(run.cycles), cfg.max_cycles), progress, len(run.cycles), cfg)
        beat.start()
        for cycle in bar:
            if run.converged or run.stopped:
                break
            record = _train_cycle(run, cycle, folder)
            if callback is not None and callback(record) is False:
                run.stopped = True
            if folder is not None:
                folder.commit(run.log(), {AGENTS[p]: m for p, m in run.models.items()})
            if progress:
                bar.set_postfix(wcpl=record["wcpl"], certified=record["certified_wcpl"])
        result = _result(run, folder)
        if folder is not None:
            from arl.plots import rewards_png

            folder.write_rewards_png(rewards_png(run.rewards))
    except Exception:
        if folder is not None:  # an error, not a kill: leave no half-written cycle behind
            folder.discard_uncommitted()
        raise
    finally:
        beat.stop()
        for env in run.envs.values():
            env.close()
    return result


def _start_run(
    dag: GameDAG, cfg: TrainConfig, seed: int, folder: RunFolder | None, resume: bool
) -> _Run:
    """A new run, or the run saved in ``folder`` restored from its checkpoint in force."""
    if cfg.reward == "paper" and turn_of(dag.metadata.get("turn_model")).simultaneous:
        raise ValueError(
            "reward: the paper's rewards charge the robot its own moves only, and in the "
            "concurrent game time passes on the human's replies; use the fast config "
            "(zero-sum rewards)"
        )
    tables = GameTables.from_dag(dag)
    learners = [p for p in (ROBOT, HUMAN) if tables.can_move_somewhere(p)]
    solution = solve(dag)  # W* for the log only: training never reads it
    run = _Run(
        dag=dag,
        cfg=cfg,
        seed=seed,
        tables=tables,
        observer=Observer(dag, cfg.obs),
        summary=graph_summary(dag),
        minimax=solution.minimax,
        envs={p: _make_env(dag, p, cfg, seed + p) for p in learners},
        models={},
        reward_scale=reward_scale(dag, cfg, solution.tct),
    )
    if resume:
        folder.recover()
        log = _check_resume(folder, run.summary, seed, cfg)
        run.cycles, run.rewards, run.wall_before = (
            log["cycles"],
            log["episode_rewards"],
            log["wall_s"],
        )
        for p in learners:
            path = folder.model_path(AGENTS[p])
            env = run.learning_env(p)
            run.models[p] = _algo_class(cfg).load(path, env=env, device="cpu")
    else:
        if folder is not None:
            folder.start_fresh()
        run.models = {p: _make_model(cfg, run.learning_env(p), seed + p) for p in learners}
    for model in run.models.values():
        # No logging but the run folder's TensorBoard events (else SB3 writes to stdout or
        # makes an empty /tmp/SB3-<time> folder per learn()).
        model.set_logger(Logger(folder=None, output_formats=[]))
    run.converged = should_stop(run.cycles, cfg)
    return run


def reward_scale(dag: GameDAG, cfg: TrainConfig, tct: float) -> float:
    """What PPO's rewards are divided by: the cooperative cost TCT on a graph of ``time``
    costs under ``reward_scale="tct"``, else 1 (:class:`arl.config.TrainConfig`)."""
    if cfg.reward_scale == "tct" and dag.cost_model == "time" and tct > 0:
        return float(tct)
    return 1.0


def _train_cycle(run: _Run, cycle: int, folder: RunFolder | None) -> dict:
    """One cycle (phase 1 trains the robot against the frozen human, phase 2 the reverse),
    then the check: tabulate the greedy policies and score them exactly. Returns the record
    appended to ``run.cycles``."""
    t0 = time.perf_counter()
    means: dict[int, float | None] = {ROBOT: None, HUMAN: None}
    counts = {ROBOT: 0, HUMAN: 0}
    for learner in run.models:
        run.doing = f"cycle {cycle + 1} of {run.cfg.max_cycles}: the {AGENTS[learner]}'s phase"
        episodes = _train_phase(run, learner, cycle, folder)
        run.rewards[AGENTS[learner]].extend(episodes)
        means[learner], counts[learner] = _mean(episodes), len(episodes)
    run.doing = f"cycle {cycle + 1} of {run.cfg.max_cycles}: the check (tabulations, exact scores)"
    robot_policy = run.greedy(ROBOT)
    _, wcpl = play(run.dag, robot_policy, run.greedy(HUMAN))
    record = {
        "cycle": cycle + 1,
        "robot_mean_reward": means[ROBOT],
        "human_mean_reward": means[HUMAN],
        "wcpl": float(wcpl),
        "certified_wcpl": certified_worst_case(run.dag, robot_policy),
        "wall_s": time.perf_counter() - t0,
        "elapsed_s": run.elapsed(),
        "timesteps": int(sum(m.num_timesteps for m in run.models.values())),
        "robot_episodes": counts[ROBOT],
        "human_episodes": counts[HUMAN],
        "policy_hash": policy_hash(run.tables, robot_policy),
    }
    run.cycles.append(record)
    run.converged = should_stop(run.cycles, run.cfg)
    return record


def _train_phase(
    run: _Run, learner: int, cycle: int, folder: RunFolder | None, tabulated: bool = True
) -> list[float]:
    """Train ``learner`` for ``phase_steps`` against the other side, frozen; return the
    rewards of the games it played (``tabulated``: see :func:`_freeze_opponent`).

    Every phase starts fresh games from seeds of ``(seed, cycle, learner)``, so that a
    resumed run repeats it exactly.
    """
    model = run.models[learner]
    _freeze_opponent(run, learner, tabulated)
    model.set_env(run.learning_env(learner), force_reset=True)
    model.set_random_seed(_phase_seed(run.seed, cycle, learner))
    recorder = _EpisodeRecorder()
    with writer_errors_raised():
        logger = None
        if folder is not None:
            tb = folder.staging_tb(AGENTS[learner])
            logger = Logger(folder=str(tb), output_formats=[TensorBoardOutputFormat(str(tb))])
            model.set_logger(logger)
        try:
            model.learn(run.cfg.phase_steps, callback=recorder, reset_num_timesteps=False)
        finally:
            if logger is not None:
                logger.close()
    return recorder.rewards


@contextmanager
def writer_errors_raised() -> Iterator[None]:
    """An ``OSError`` of another thread in the block (TensorBoard's log writer writes in a
    thread of its own) raised here, in the caller's thread, after the block, instead of
    printed as that thread's traceback (a full disk printed one beside the command's own
    one-line error: the reliability probe, issue 26). Other errors of threads print as
    before."""
    caught: list[BaseException] = []
    previous = threading.excepthook

    def hook(args) -> None:
        if args.exc_type is not None and issubclass(args.exc_type, OSError):
            caught.append(args.exc_value)
        else:
            previous(args)

    threading.excepthook = hook
    try:
        yield
    finally:
        threading.excepthook = previous
    if caught:
        raise caught[0]


def _freeze_opponent(run: _Run, learner: int, tabulated: bool = True) -> None:
    """Set the other side's current policy as the learner's frozen opponent (not
    ``tabulated``: a vectorised environment's opponent plays uniformly at random, as
    before its first tabulation; :func:`estimate_cycle` times the tabulation apart)."""
    other, env = run.models.get(1 - learner), run.envs[learner]
    if not isinstance(env, GameVecEnv):  # the paper's: the frozen model plays every move
        env.env_method("set_opponent", other)
        return
    table = None  # tabulated once: one forward pass over all nodes
    if other is not None and tabulated:
        tab = tabulate if run.cfg.opponent_deterministic else action_probabilities
        table = tab(other, run.tables, 1 - learner, run.observer)
    env.set_opponent(table, run.cfg.opponent_epsilon)


def _result(run: _Run, folder: RunFolder | None) -> TrainResult:
    robot_policy, human_policy = run.greedy(ROBOT), run.greedy(HUMAN)
    _, wcpl = play(run.dag, robot_policy, human_policy)
    return TrainResult(
        robot_policy=robot_policy,
        human_policy=human_policy,
        cycles=run.cycles,
        episode_rewards=run.rewards,
        wall_s=run.elapsed(),
        converged=run.converged,
        wcpl=float(wcpl),
        certified_wcpl=certified_worst_case(run.dag, robot_policy),
        minimax=run.minimax,
        config=run.cfg,
        seed=run.seed,
        output=None if folder is None else folder.path,
        models={AGENTS[p]: m for p, m in run.models.items()},
    )


def _progress(iterable, enabled: bool, initial: int, cfg: TrainConfig):
    if not enabled:
        return iterable
    from tqdm.auto import tqdm

    return tqdm(iterable, initial=initial, total=cfg.max_cycles, desc="cycles", unit="cycle")


# ------------------------------------------------------------- the size check: time


def estimate_cycle(
    dag: GameDAG, cfg: TrainConfig, seed: int = 0, cycles_left: int | None = None
) -> CycleEstimate:
    """The seconds a cycle of training ``dag`` with ``cfg`` will take, from a sample.

    The sample: throwaway models and games of the same configuration but rollouts of
    :data:`SAMPLE_STEPS` game steps; one learner's phase is run twice (the first warms
    up) and the second timed, and one chunk of a tabulation is timed
    (:func:`arl.tabulate.tabulation_seconds`). A cycle is then every learner's
    ``phase_steps`` (rounded up to whole rollouts, as PPO does) at the measured seconds
    a step, a tabulation of the frozen opponent per phase (vectorised games), and one
    tabulation per learner for the check. Nothing of the run folder is read or written.
    A sample on a busy machine is slower, and a small game's phase, one long rollout in
    the real configuration, pays PPO's overhead per rollout fewer times: the estimate
    errs on the long side.
    """
    n_envs = cfg.n_envs
    k = max(1, min(cfg.n_steps, SAMPLE_STEPS // n_envs))
    sample = cfg.replace(n_steps=k, batch_size=min(cfg.batch_size, k * n_envs))
    sample = sample.replace(phase_steps=k * n_envs)
    run = _start_run(dag, sample, seed, None, False)
    try:
        step_s = tabulation_s = 0.0
        if run.models:
            learner = next(iter(run.models))
            _train_phase(run, learner, 0, None, tabulated=False)  # warms up
            t0 = time.perf_counter()
            _train_phase(run, learner, 1, None, tabulated=False)
            step_s = (time.perf_counter() - t0) / (k * n_envs)
            tabulation_s = tabulation_seconds(run.models[learner], run.tables, run.observer)
    finally:
        for env in run.envs.values():
            env.close()
    phase = phase_seconds(cfg.phase_steps, cfg.n_steps * n_envs, step_s)
    opponent = tabulation_s if cfg.vectorized and len(run.models) > 1 else 0.0
    learners = len(run.models)
    return CycleEstimate(
        seconds=learners * (phase + opponent + tabulation_s),
        step_s=step_s,
        sample_steps=k * n_envs,
        cycles=cfg.max_cycles if cycles_left is None else int(cycles_left),
        size=f"{dag.n_nodes:,} nodes, {dag.n_edges:,} edges",
        check_s=tabulation_s,
        check="a tabulation of every node",
    )


def read_log(output: str | Path) -> dict:
    """The ``log.json`` in force in a run folder (``ValueError`` if missing or malformed)."""
    return RunFolder(output).read_log()


def _saved_config(folder: RunFolder, log: dict) -> TrainConfig:
    try:
        return TrainConfig.from_dict(log["config"])
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{folder.log_path()}: malformed run log (config: {exc})") from None


def _check_resume(folder: RunFolder, summary: dict, seed: int, cfg: TrainConfig) -> dict:
    """The saved log, checked to belong to the same graph (``summary``, of
    :func:`graph_summary`), seed and config."""
    out = folder.path
    log = folder.read_log()
    if log["graph"]["fingerprint"] != summary["fingerprint"]:
        raise ValueError(f"resume: {out} was trained on a different graph")
    if log["seed"] != seed:
        raise ValueError(f"resume: {out} was trained with seed {log['seed']}, not {seed}")
    saved = _saved_config(folder, log)
    if saved.replace(max_cycles=cfg.max_cycles) != cfg:
        diff = [k for k, v in cfg.to_dict().items() if saved.to_dict()[k] != v]
        raise ValueError(f"resume: config differs from the saved run in {', '.join(diff)}")
    return log


# ---------------------------------------------------------------------------- evaluation


def load_policies(dag: GameDAG, model_dir: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Greedy robot and human policies of a run folder, tabulated from its saved models.

    Raises ``ValueError`` if the folder is not a run or was trained on another graph.
    """
    folder = RunFolder(model_dir)
    log = folder.read_log()
    if log["graph"]["fingerprint"] != graph_summary(dag)["fingerprint"]:
        raise ValueError(f"{model_dir} was trained on a different graph")
    cfg = _saved_config(folder, log)
    tables = GameTables.from_dag(dag)
    observer = Observer(dag, cfg.obs)
    policies = []
    for p in (ROBOT, HUMAN):
        path = folder.model_path(AGENTS[p])
        if not tables.can_move_somewhere(p):
            policies.append(np.full(tables.n, NO_MOVE, dtype=np.int64))
            continue
        if not path.is_file():
            raise ValueError(f"{model_dir}: missing {path.name}")
        model = _algo_class(cfg).load(path, device="cpu")
        policies.append(tabulate(model, tables, p, observer))
    return policies[0], policies[1]


def evaluate(
    dag: GameDAG,
    robot_policy_or_model_dir: np.ndarray | str | Path,
    *,
    human_policy: np.ndarray | None = None,
    n_games: int = 1000,
    seed: int = 0,
) -> dict:
    """All metrics of a learned robot policy (``asp.game.metrics.plan_metrics``) as a dict.

    Parameters
    ----------
    dag : GameDAG
    robot_policy_or_model_dir : (n,) edge indices, or a run folder of :func:`train`
        For a run folder the greedy policies are tabulated from ``robot.zip`` and
        ``human.zip``.
    human_policy : (n,) edge indices, optional
        The learned human (a run folder supplies its own); with it ``wcpl`` is the paper's
        greedy-vs-greedy cost, without it the certified one.

    Returns
    -------
    dict
        ``tct, minimax, wcpl, certified_wcpl, avg_random, max_random, rr, rr_certified,
        robust_optimal, ...`` (every :class:`asp.game.metrics.PlanMetrics` field) plus
        ``robot_policy`` (edge indices).
    """
    from asp.game.metrics import plan_metrics

    target = robot_policy_or_model_dir
    if isinstance(target, str | Path):
        robot_policy, human_policy = load_policies(dag, target)
    else:
        robot_policy = np.asarray(target, dtype=np.int64)
    wcpl = None
    if human_policy is not None:
        _, wcpl = play(dag, robot_policy, np.asarray(human_policy, dtype=np.int64))
    metrics = plan_metrics(dag, robot_policy=robot_policy, wcpl=wcpl, n_games=n_games, seed=seed)
    out = metrics.to_dict()
    out["robot_policy"] = robot_policy.tolist()
    return out
