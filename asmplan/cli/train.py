"""Commands ``asmplan train`` and ``asmplan evaluate`` (alternating PPO, :mod:`arl.trainer`)."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from asmplan.cli.app import OutputFormat, app
from asmplan.cli.options import GAMES_MAX, SEED_MAX, check_output

MAX_CYCLES = 100_000

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
    graph: Path = typer.Argument(..., help="Game DAG (.json asmplan-dag/1 or .graphml)."),
    config: str = typer.Option("paper", "--config", help="Training configuration: paper|fast."),
    seed: int = typer.Option(
        0, "--seed", min=0, max=SEED_MAX, help="Seed of models, environments and torch."
    ),
    output: Path = typer.Option(..., "--output", "-o", help="Run folder (models, log, plots)."),
    resume: bool = typer.Option(False, "--resume", help="Continue the run saved in --output."),
    max_cycles: int | None = typer.Option(
        None, "--max-cycles", min=1, max=MAX_CYCLES, help="Stop after N cycles."
    ),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Show a progress bar."),
) -> None:
    """Train a robust robot policy by alternating PPO against a learned adversarial human."""
    from arl.config import get_config
    from arl.trainer import train
    from asp.io import load_dag

    check_output(output, folder=True)
    dag = load_dag(graph)
    cfg = get_config(config)
    if max_cycles is not None:
        cfg = cfg.replace(max_cycles=max_cycles)
    result = train(dag, cfg, seed=seed, output=output, progress=progress, resume=resume)
    status = "converged" if result.converged else "stopped"
    typer.echo(
        f"{status} after {len(result.cycles)} cycles in {result.wall_s:.1f} s: "
        f"wcpl {result.wcpl:g}, certified wcpl {result.certified_wcpl:g}, "
        f"W* {result.minimax:g} ({'robust-optimal' if result.robust_optimal else 'not robust'})"
        f"; wrote {output}"
    )


@app.command("evaluate")
def evaluate_command(
    graph: Path = typer.Argument(..., help="Game DAG the model was trained on."),
    model: Path = typer.Option(..., "--model", help="Run folder written by 'asmplan train'."),
    fmt: OutputFormat = typer.Option(OutputFormat.text, "--format", help="Output format."),
    games: int = typer.Option(
        1000, "--games", min=1, max=GAMES_MAX, help="Simulated random-human games."
    ),
    seed: int = typer.Option(0, "--seed", min=0, max=SEED_MAX, help="Seed of the simulation."),
) -> None:
    """Score a trained robot policy exactly: WCPL, certified WCPL, random-human metrics, RR."""
    from arl.trainer import evaluate
    from asp.io import load_dag

    dag = load_dag(graph)
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
