"""``asmplan experiment table3|table4``: reproduce the paper's synthetic experiments."""

from __future__ import annotations

import signal
from collections.abc import Iterator
from contextlib import contextmanager
from enum import StrEnum
from pathlib import Path

import typer

from asmplan.cli.app import app, choices, fail
from asmplan.cli.options import GAMES_MAX, WORKERS_MAX, seed_option
from asmplan.experiments.backends import BACKENDS
from asmplan.experiments.tasks import EXPERIMENT_KEYS, Solver

TRIALS_MAX = 10_000


class ConfigChoice(StrEnum):
    """ARL trainer configuration: the names of :data:`arl.config.CONFIGS` (importing it here
    would load the RL stack for every command; ``tests/asmplan/test_cli_errors.py`` checks
    that the two agree)."""

    paper = "paper"
    fast = "fast"


SolverChoice = Solver
BackendChoice = choices("BackendChoice", BACKENDS, "Where tasks run.")
TableChoice = choices("TableChoice", tuple(EXPERIMENT_KEYS), "Which of the paper's experiments.")

DEFAULT_TRIALS = {TableChoice.table3: 1, TableChoice.table4: 10}


@contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Within the block, SIGTERM interrupts like Ctrl-C (``KeyboardInterrupt``), so that a
    terminated sweep stops its workers and keeps its finished tasks the same way."""

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _run(experiment: str, output: Path, trials: int, **options) -> None:
    from asmplan.experiments.runner import TasksFailed, run_experiment

    try:
        with sigterm_as_interrupt():
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


@app.command("experiment")
def experiment_command(
    table: TableChoice = typer.Argument(
        ...,
        help="table3: the six configurations 4/10, 10/4, 10/10, 15/10, 20/10, 20/20 (4 actions); "
        "table4: the repeated experiment on 20/10 graphs.",
    ),
    output: Path | None = typer.Option(
        None, "--output", "-o", help="Output folder (default results/t3 or results/t4)."
    ),
    trials: int | None = typer.Option(
        None,
        "--trials",
        max=TRIALS_MAX,
        help="Graphs per configuration (default: 1 for table3, 10 for table4).",
    ),
    solver: SolverChoice = typer.Option(
        SolverChoice.both,
        "--solver",
        help="exact minimax, ARL, or both (ARL with exact beside it).",
    ),
    seed: int = seed_option("Base seed; each task derives its own from it."),
    config: ConfigChoice = typer.Option(ConfigChoice.paper, "--config", help="ARL configuration."),
    backend: BackendChoice = typer.Option(
        BackendChoice.local, "--backend", help="local process pool or Ray."
    ),
    address: str = typer.Option(
        "auto",
        "--address",
        help="Ray cluster: auto (started with `ray start`), host:port, or local (a private one).",
    ),
    workers: int | None = typer.Option(
        None,
        "--workers",
        min=1,
        max=WORKERS_MAX,
        help="Parallel tasks (default: all cores; 1 runs in this process).",
    ),
    games: int = typer.Option(
        1000, "--games", min=1, max=GAMES_MAX, help="Games of the random-human simulation."
    ),
    curve_trial: int = typer.Option(
        1, "--curve-trial", min=1, max=TRIALS_MAX, help="Trial whose ARL curves make Figure 11."
    ),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Show a progress bar."),
    force: bool = typer.Option(
        False,
        "--force",
        help="Replace the finished tasks of another sweep (another --solver, --config, --seed "
        "or --games) in --output (else refused).",
    ),
) -> None:
    """Reproduce the paper's synthetic experiments (Tables 3-4, Figures 11-13)."""
    _run(
        table.value,
        output or Path("results") / ("t3" if table is TableChoice.table3 else "t4"),
        DEFAULT_TRIALS[table] if trials is None else trials,
        solver=solver.value,
        seed=seed,
        config=config.value,
        backend=backend.value,
        address=address,
        workers=workers,
        n_games=games,
        curve_trial=curve_trial,
        progress=progress,
        force=force,
    )
