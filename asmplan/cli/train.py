"""Commands ``asmplan train`` and ``asmplan evaluate`` (alternating PPO, :mod:`arl.trainer`)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from asmplan.cli.app import OutputFormat, app
from asmplan.cli.options import (
    GAMES_MAX,
    TurnModel,
    check_output,
    max_memory_option,
    seed_option,
    turn_model_option,
)
from asp.game.turns import ALTERNATE, CONCURRENT, DEFAULT_TURN, TURNS

if TYPE_CHECKING:  # pragma: no cover - types only
    from asp.game.dag import GameDAG
    from asp.graph.state_graph import StateGraph
    from asp.spec import AssemblySpec


SOURCE_HELP = (
    "Game DAG (.json asmplan-dag/1 or .graphml), or an assembly (a folder with "
    "assembly.yaml, the YAML, a .IN2 graph)."
)
TURN_MODEL_HELP = (
    "Game of an assembly: alternate (the paper's turns) or concurrent (agents at once; the "
    "robots learn against the unbounded adversary, W*(inf)). Default: the spec's."
)


def load_training_game(source: Path, turn_model: TurnModel | None = None) -> GameDAG:
    """The game DAG that ``train`` and ``evaluate`` play: a game DAG file as it is, or an
    assembly's alternating game or concurrent game (the latter compiled by
    :func:`asp.concurrent.build_game` against the unbounded adversary)."""
    from asmplan import pipeline

    if source.is_file() and source.suffix.lower() in pipeline.GRAPH_SUFFIXES:
        if turn_model is not None and not TURNS[turn_model.value].game_file:
            raise ValueError(
                f"{source}: --turn-model {turn_model.value} needs an assembly (a game DAG "
                "file is an alternating game)"
            )
        return pipeline.load_game(source).dag
    assembly = pipeline.load(source)
    graph = pipeline.state_graph(assembly)
    chosen = turn_model or TurnModel(getattr(assembly.spec, "turn_model", DEFAULT_TURN.name))
    return TRAINING_GAMES[chosen.value](assembly.spec, graph)


def _alternating_game(spec: AssemblySpec, graph: StateGraph) -> GameDAG:
    from asmplan import pipeline

    return pipeline.game(graph)


def _concurrent_game(spec: AssemblySpec, graph: StateGraph) -> GameDAG:
    """The concurrent game against the unbounded adversary (``W*(inf)``)."""
    from asp.concurrent.build import build_game
    from asp.concurrent.model import concurrent_model

    return build_game(concurrent_model(spec, graph), None).dag


TRAINING_GAMES = {ALTERNATE.name: _alternating_game, CONCURRENT.name: _concurrent_game}
"""The game DAG ``train`` and ``evaluate`` play on an assembly, by turn model
(:data:`asp.game.turns.TURNS`)."""


def _stderr_line(progress: bool):
    """A line on stderr: above the progress bar when there is one (``tqdm.write``)."""
    if not progress:
        return lambda line: typer.echo(line, err=True)
    import sys

    from tqdm.auto import tqdm

    return lambda line: tqdm.write(line, file=sys.stderr)


MAX_CYCLES = 100_000
CONCURRENT_CONFIGS = ("concurrent", "concurrent-tiny")
"""The ``--config`` names of :mod:`arl.concurrent_trainer` (checked there)."""


def _concurrent_rules(source: Path, what: str, max_memory_gb: float | None = None):
    """The concurrent game's rules of the assembly ``source`` (``what``: the option that
    needs it, for the error; ``max_memory_gb``: the state graph's memory limit, default the
    one rule)."""
    from asmplan import pipeline
    from asp.concurrent.rules import concurrent_rules

    if source.is_file() and source.suffix.lower() in pipeline.GRAPH_SUFFIXES:
        raise ValueError(f"{source}: {what} needs an assembly, not a game DAG file")
    assembly = pipeline.load(source)
    memory = None if max_memory_gb is None else int(max_memory_gb * 2**30)
    return concurrent_rules(assembly.spec, pipeline.state_graph(assembly, max_memory=memory))


def _certified_text(certified: dict) -> str:
    return ", ".join(f"k={'inf' if b is None else b}: {certified[b]:g}" for b in certified)


def _train_concurrent(
    source, turn_model, config, seed, output, max_cycles, progress, max_memory, **pace
) -> None:
    """``train --config concurrent``: alternating PPO on the assembly's concurrent game played
    from its rules (:func:`arl.concurrent_trainer.train_concurrent`; ``pace``: the cycle
    limit, the estimate's and the heartbeat's lines, as for the alternating trainer;
    ``max_memory``: ``--max-memory``, GB, for the state graph, the learners and the
    certificates' policy games)."""
    from arl.concurrent_trainer import DEFAULT_BUDGETS, train_concurrent
    from arl.concurrent_trainer import get_config as concurrent_config

    if turn_model is not None and turn_model.value != CONCURRENT.name:
        raise ValueError(
            f"--config {config} trains the concurrent game: use --turn-model concurrent"
        )
    cfg = concurrent_config(config)
    if max_cycles is not None:
        cfg = cfg.replace(cycles=max_cycles)
    rules = _concurrent_rules(source, f"--config {config}", max_memory)
    result = train_concurrent(
        rules,
        cfg,
        seed=seed,
        budgets=DEFAULT_BUDGETS,
        output=output,
        progress=progress,
        max_memory_gb=max_memory,
        **pace,
    )
    typer.echo(
        f"trained {result.steps:,} steps in {result.seconds:.1f} s; the robot of cycle "
        f"{result.best_cycle} is certified (exact best response) at "
        f"{_certified_text(result.certified)}; wrote {output}"
    )


def _evaluate_concurrent(source: Path, folder: Path, fmt) -> None:
    """``evaluate --model RUN`` of a concurrent run: its robot certified by the exact best
    response at the budgets the run was certified at (``config.json``), those whose policy
    game fits (:func:`arl.concurrent_trainer.certify_fitting`)."""
    from arl.concurrent_trainer import DEFAULT_BUDGETS, certify_fitting, learned_policy, load_robot

    rules = _concurrent_rules(source, "a concurrent run (--model)")
    robot = load_robot(folder)
    budgets = json.loads((folder / "config.json").read_text()).get("budgets", DEFAULT_BUDGETS)
    say = lambda line: typer.echo(line, err=True)  # noqa: E731
    cert, _ = certify_fitting(rules, learned_policy(rules, robot), budgets, say=say)
    if fmt is OutputFormat.json:
        doc = {"certified": cert.to_list(), "policy_game_nodes": cert.nodes}
        typer.echo(json.dumps(doc, allow_nan=False))
        return
    typer.echo(
        f"{source}, concurrent model {folder}: certified worst case (exact best response, "
        f"{cert.nodes:,} policy-game nodes) {_certified_text(cert.worst)}"
    )


EVALUATE_KEYS = (
    "nodes",
    "edges",
    "tct",
    "minimax",
    "wcpl",
    "certified_wcpl",
    "avg_random",
    "max_random",
    "rr",
    "rr_certified",
    "robust_optimal",
    "adversarial_tax",
)


@app.command("train")
def train_command(
    graph: Path = typer.Argument(..., help=SOURCE_HELP),
    turn_model: TurnModel | None = turn_model_option(TURN_MODEL_HELP),
    config: str = typer.Option(
        "paper",
        "--config",
        help="Training configuration: paper|fast (on a game DAG), or concurrent (the "
        "concurrent game played from its rules, never compiled; arl/concurrent_trainer.py).",
    ),
    seed: int = seed_option("Seed of models, environments and torch."),
    output: Path = typer.Option(..., "--output", "-o", help="Run folder (models, log, plots)."),
    resume: bool = typer.Option(False, "--resume", help="Continue the run saved in --output."),
    force: bool = typer.Option(
        False, "--force", help="Replace a training run already in --output (else refused)."
    ),
    max_cycles: int | None = typer.Option(
        None, "--max-cycles", min=1, max=MAX_CYCLES, help="Stop after N cycles."
    ),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Show a progress bar."),
    max_memory: float | None = max_memory_option(
        "Refuse a game whose training needs more GB than this, before any work "
        "(default: 3/4 of the memory available; arl/memory.py); --config concurrent: the "
        "state graph, the learners and each certificate's policy game within it."
    ),
    max_cycle_seconds: float | None = typer.Option(
        None,
        "--max-cycle-seconds",
        min=0.001,
        max=1e9,
        help="Refuse, before training, a game whose cycle is estimated to take longer "
        "(the estimate, from a short sample, is said on stderr either way).",
    ),
) -> None:
    """Train a robust robot policy by alternating PPO against a learned adversarial human."""
    from arl.config import get_config
    from arl.runfolder import refuse_existing_run
    from arl.trainer import train

    check_output(output, folder=True)
    pace = {
        "max_cycle_seconds": max_cycle_seconds,
        "on_estimate": lambda e: typer.echo(f"training: {e.text()}", err=True),
        "heartbeat": _stderr_line(progress),
    }
    if config in CONCURRENT_CONFIGS:
        if not resume:  # (train() checks its own folder)
            refuse_existing_run(output, force=force)
        _train_concurrent(
            graph, turn_model, config, seed, output, max_cycles, progress, max_memory, **pace
        )
        return
    get_config(config)  # a bad name fails before any work
    dag = load_training_game(graph, turn_model)
    cfg = get_config(config, dag.metadata.get("turn_model"))
    if max_cycles is not None:
        cfg = cfg.replace(max_cycles=max_cycles)
    result = train(
        dag,
        cfg,
        seed=seed,
        output=output,
        progress=progress,
        resume=resume,
        max_memory_gb=max_memory,
        force=force,
        **pace,
    )
    status = "converged" if result.converged else "stopped"
    typer.echo(
        f"{status} after {len(result.cycles)} cycles in {result.wall_s:.1f} s: "
        f"wcpl {result.wcpl:g}, certified wcpl {result.certified_wcpl:g}, "
        f"W* {result.minimax:g} ({'robust-optimal' if result.robust_optimal else 'not robust'})"
        f"; wrote {output}"
    )


@app.command("evaluate")
def evaluate_command(
    graph: Path = typer.Argument(..., help="Game DAG or assembly the model was trained on."),
    turn_model: TurnModel | None = turn_model_option(TURN_MODEL_HELP),
    model: Path = typer.Option(..., "--model", help="Run folder written by 'asmplan train'."),
    fmt: OutputFormat = typer.Option(OutputFormat.text, "--format", help="Output format."),
    games: int = typer.Option(
        1000, "--games", min=1, max=GAMES_MAX, help="Simulated random-human games."
    ),
    seed: int = seed_option("Seed of the simulation."),
) -> None:
    """Score a trained robot policy exactly: WCPL, certified WCPL, random-human metrics, RR."""
    from arl.concurrent_trainer import is_run_folder
    from arl.trainer import evaluate

    if is_run_folder(model):
        _evaluate_concurrent(graph, model, fmt)
        return
    dag = load_training_game(graph, turn_model)
    if not model.is_dir():
        raise ValueError(f"{model}: not a run folder")
    metrics = evaluate(dag, model, n_games=games, seed=seed)
    if fmt is OutputFormat.json:
        typer.echo(json.dumps(metrics, allow_nan=False))
        return
    typer.echo(f"{graph} ({dag.cost_model}), model {model}")
    for key in EVALUATE_KEYS:
        value = metrics[key]
        if key in ("rr", "rr_certified"):
            text = f"{100 * value:.1f}%"
        elif isinstance(value, float):
            text = f"{value:g}"
        else:
            text = str(value)
        typer.echo(f"  {key:<16} {text}")
