"""``asmplan experiment table3|table4``: reproduce the paper's synthetic experiments."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path

import typer

from arl.cli.app import app, fail


class SolverChoice(StrEnum):
    """Planner(s) each task runs."""

    exact = "exact"
    arl = "arl"
    both = "both"


class ConfigChoice(StrEnum):
    """ARL trainer configuration."""

    paper = "paper"
    fast = "fast"


class BackendChoice(StrEnum):
    """Where tasks run."""

    local = "local"
    ray = "ray"


experiment_app = typer.Typer(
    help="Reproduce the paper's synthetic experiments (Tables 3-4, Figures 11-13).",
    no_args_is_help=True,
)
app.add_typer(experiment_app, name="experiment")


def _run(experiment: str, output: Path, trials: int, **options) -> None:
    from arl.experiments.runner import TasksFailed, run_experiment

    try:
        report = run_experiment(experiment, output, trials=trials, **options)
    except ValueError as exc:
        fail(str(exc).splitlines()[0] if str(exc) else type(exc).__name__)
    except TasksFailed as exc:
        typer.echo(f"asmplan: error: {exc}", err=True)
        raise typer.Exit(code=1) from None
    typer.echo(
        f"{experiment}: {len(report.results)} tasks ({report.ran} run, {report.resumed} resumed) "
        f"in {report.wall_s:.1f} s; wrote {', '.join(p.name for p in report.files)} to {output}"
    )


SOLVER = typer.Option(
    SolverChoice.both, "--solver", help="exact minimax, ARL, or both (ARL with exact beside it)."
)
SEED = typer.Option(0, "--seed", help="Base seed; each task derives its own from it.")
CONFIG = typer.Option(ConfigChoice.paper, "--config", help="ARL configuration.")
BACKEND = typer.Option(BackendChoice.local, "--backend", help="local process pool or Ray.")
ADDRESS = typer.Option(
    "auto",
    "--address",
    help="Ray cluster: auto (started with `ray start`), host:port, or local (private instance).",
)
WORKERS = typer.Option(
    None, "--workers", help="Parallel tasks (default: all cores; 1 runs in this process)."
)
GAMES = typer.Option(1000, "--games", help="Games of the random-human simulation.")
CURVE_TRIAL = typer.Option(1, "--curve-trial", help="Trial whose ARL curves make Figure 11.")
PROGRESS = typer.Option(True, "--progress/--no-progress", help="Show a progress bar.")


@experiment_app.command("table3")
def table3_command(
    output: Path = typer.Option(Path("results/t3"), "--output", "-o", help="Output folder."),
    trials: int = typer.Option(1, "--trials", help="Graphs per configuration."),
    solver: SolverChoice = SOLVER,
    seed: int = SEED,
    config: ConfigChoice = CONFIG,
    backend: BackendChoice = BACKEND,
    address: str = ADDRESS,
    workers: int | None = WORKERS,
    games: int = GAMES,
    curve_trial: int = CURVE_TRIAL,
    progress: bool = PROGRESS,
) -> None:
    """Table 3: the six configurations 4/10, 10/4, 10/10, 15/10, 20/10, 20/20 (4 actions)."""
    _run(
        "table3",
        output,
        trials,
        solver=solver.value,
        seed=seed,
        config=config.value,
        backend=backend.value,
        address=address,
        workers=workers,
        n_games=games,
        curve_trial=curve_trial,
        progress=progress,
    )


@experiment_app.command("table4")
def table4_command(
    output: Path = typer.Option(Path("results/t4"), "--output", "-o", help="Output folder."),
    trials: int = typer.Option(10, "--trials", help="Number of 20/10 graphs."),
    solver: SolverChoice = SOLVER,
    seed: int = SEED,
    config: ConfigChoice = CONFIG,
    backend: BackendChoice = BACKEND,
    address: str = ADDRESS,
    workers: int | None = WORKERS,
    games: int = GAMES,
    curve_trial: int = CURVE_TRIAL,
    progress: bool = PROGRESS,
) -> None:
    """Table 4: the repeated experiment on 20/10 graphs (ten by default, see --trials)."""
    _run(
        "table4",
        output,
        trials,
        solver=solver.value,
        seed=seed,
        config=config.value,
        backend=backend.value,
        address=address,
        workers=workers,
        n_games=games,
        curve_trial=curve_trial,
        progress=progress,
    )
