"""Run a sweep: resume finished tasks, run the rest on a backend, write tables and figures.

Layout of an output folder::

    DIR/tasks/<task id>.json   one per finished task, written as it finishes (resume)
    DIR/results.csv            every row, every field
    DIR/results.md             Markdown table, the paper's columns first
    DIR/figure11_training.png  training curves of one ARL run (only when ARL ran)
    DIR/figure12_resilience.png
    DIR/figure13_path_lengths.png
    DIR/summary.md             ours next to the paper's published values

Every file is written atomically (:mod:`asp.atomic`). A task file is reused when the spec
it records equals the task's spec (same experiment, configuration, trial, base seed,
solver, ARL configuration and game count). A folder holds one sweep: a run whose experiment,
``--seed``, ``--solver``, ``--config`` or ``--games`` differs from that of a task file
already there is refused (it would overwrite finished results), unless ``force``, which
removes the other sweep's task files first. More or fewer ``--trials`` are the same sweep.
The tables, figures and summary describe the sweep just run: the figures and summary of
the previous run are removed before ``results.csv`` is written, so a figure never stands
beside results it was not drawn from (Figure 11 is absent when ARL did not run).
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path

from tqdm import tqdm

from asmplan.experiments.backends import make_backend
from asmplan.experiments.figures import (
    figure11_training,
    figure12_resilience,
    figure13_path_lengths,
)
from asmplan.experiments.summary import RunInfo, summary_markdown
from asmplan.experiments.tables import results_csv, results_markdown
from asmplan.experiments.tasks import (
    TASK_FORMAT,
    ResultRow,
    Solver,
    TaskResult,
    TaskSpec,
    make_specs,
    require_trainer,
)
from asp.atomic import write_bytes, write_text

TASKS_DIR = "tasks"
FIGURE11, FIGURE12, FIGURE13 = (
    "figure11_training.png",
    "figure12_resilience.png",
    "figure13_path_lengths.png",
)
SUMMARY = "summary.md"


class TasksFailed(RuntimeError):
    """Some tasks raised; the finished ones are saved and a rerun resumes from them."""


@dataclass(frozen=True)
class ExperimentReport:
    """What :func:`run_experiment` did and wrote."""

    output: Path
    results: tuple[TaskResult, ...]
    ran: int
    resumed: int
    wall_s: float
    files: tuple[Path, ...] = field(default=())

    @property
    def rows(self) -> list[ResultRow]:
        """All rows, in task order."""
        return [row for result in self.results for row in result.rows]


def task_path(output: Path, spec: TaskSpec) -> Path:
    """Where a task's result is saved."""
    return Path(output) / TASKS_DIR / f"{spec.task_id}.json"


def load_finished(output: Path, specs: list[TaskSpec]) -> dict[str, TaskResult]:
    """The saved results whose recorded spec equals the task's spec, by task id."""
    finished: dict[str, TaskResult] = {}
    for spec in specs:
        path = task_path(output, spec)
        if not path.is_file():
            continue
        try:
            result = TaskResult.from_dict(json.loads(path.read_text(encoding="utf-8")))
        except (ValueError, KeyError, TypeError):
            continue  # unreadable or from another format: run the task again
        if result.spec == spec:
            finished[spec.task_id] = result
    return finished


def held_tasks(output: Path) -> list[tuple[Path, TaskSpec]]:
    """The task files in ``output/tasks/`` with the specs they record (files of another
    format, or unreadable, are not this module's and are left out)."""
    held = []
    folder = Path(output) / TASKS_DIR
    for path in sorted(folder.glob("*.json")) if folder.is_dir() else ():
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
            if data.get("format") == TASK_FORMAT:
                held.append((path, TaskSpec.from_dict(data["spec"])))
        except (OSError, ValueError, KeyError, TypeError, AttributeError):
            continue
    return held


def refuse_other_sweep(output: Path, specs: list[TaskSpec], *, force: bool) -> None:
    """Refuse to run ``specs`` into a folder holding another sweep's finished tasks, unless
    ``force`` (then those task files are removed).

    Raises
    ------
    ValueError
        One line naming the folder, what differs (flag: held -> asked) and the ways on.
    """
    wanted = specs[0].sweep
    others = [(path, spec) for path, spec in held_tasks(output) if spec.sweep != wanted]
    if not others:
        return
    if force:
        for path, _ in others:
            _remove(path)
        return
    held = others[0][1].sweep
    differs = ", ".join(f"{k} {held[k]} -> {wanted[k]}" for k in wanted if held[k] != wanted[k])
    raise ValueError(
        f"{output}: holds {len(others)} finished task(s) of another sweep ({differs}); "
        "use another --output, or --force to replace them"
    )


def _remove(path: Path) -> None:
    path.unlink(missing_ok=True)


def save_result(output: Path, result: TaskResult) -> Path:
    """Write one task's result atomically under ``output/tasks/``."""
    return write_text(task_path(output, result.spec), json.dumps(result.to_dict()) + "\n")


def run_experiment(
    experiment: str,
    output: str | Path,
    *,
    trials: int,
    seed: int = 0,
    solver: str = "both",
    config: str = "paper",
    backend: str = "local",
    address: str = "auto",
    workers: int | None = None,
    n_games: int = 1000,
    curve_trial: int = 1,
    progress: bool = True,
    force: bool = False,
) -> ExperimentReport:
    """Run (or resume) the sweep of ``experiment`` and write its tables and figures.

    Parameters
    ----------
    experiment : str
        ``"table3"`` or ``"table4"``.
    output : path
        Output folder (created).
    trials : int
        Graphs per configuration.
    seed : int
        Base seed; every task derives its own (:attr:`TaskSpec.seeds`).
    solver : str
        ``"exact"``, ``"arl"`` or ``"both"``.
    config : str
        ARL configuration, ``"paper"`` or ``"fast"``.
    backend, address, workers
        Where tasks run (:func:`asmplan.experiments.backends.make_backend`).
    n_games : int
        Games of the paper's random-human simulation.
    curve_trial : int
        Trial whose training curves make Figure 11 (Table 3: of the 15/10 graph, the
        paper's Figure 11 graph).
    progress : bool
        Show a tqdm bar counting tasks.
    force : bool
        Replace the finished tasks of another sweep in ``output`` (else refused).

    Raises
    ------
    ValueError
        Bad parameters, the ARL trainer or Ray missing, ``output`` holding another sweep.
    TasksFailed
        Some tasks raised (the others are saved; rerun to resume).
    """
    start = time.perf_counter()
    specs = make_specs(
        experiment, trials=trials, base_seed=seed, solver=solver, config=config, n_games=n_games
    )
    if "arl" in Solver(solver).runs:
        require_trainer()
    runner = make_backend(backend, workers=workers, address=address)
    output = Path(output)
    refuse_other_sweep(output, specs, force=force)
    output.mkdir(parents=True, exist_ok=True)

    finished = load_finished(output, specs)
    todo = [s for s in specs if s.task_id not in finished]
    failures: list[tuple[TaskSpec, BaseException]] = []
    with tqdm(
        total=len(specs),
        initial=len(finished),
        desc=f"{experiment} ({runner.name})",
        unit="task",
        disable=not progress,
    ) as bar:
        for spec, outcome in runner.run(todo):
            if isinstance(outcome, BaseException):
                failures.append((spec, outcome))
            else:
                save_result(output, outcome)
                finished[spec.task_id] = outcome
            bar.update(1)
    if failures:
        listed = "; ".join(f"{s.task_id}: {_error_line(e)}" for s, e in failures)
        raise TasksFailed(
            f"{len(failures)} of {len(specs)} tasks failed ({listed}); "
            f"finished tasks are saved in {output / TASKS_DIR}, rerun to resume"
        )

    results = tuple(finished[s.task_id] for s in specs)
    wall_s = time.perf_counter() - start
    files = write_outputs(
        output,
        experiment,
        results,
        RunInfo(
            experiment=experiment,
            trials=trials,
            seed=seed,
            solver=solver,
            config=config,
            backend=runner.name,
            tasks=len(specs),
            ran=len(todo),
            resumed=len(specs) - len(todo),
            wall_s=wall_s,
            figures=(),
        ),
        curve_trial=curve_trial,
    )
    return ExperimentReport(
        output=output,
        results=results,
        ran=len(todo),
        resumed=len(specs) - len(todo),
        wall_s=time.perf_counter() - start,
        files=tuple(files),
    )


def write_outputs(
    output: Path,
    experiment: str,
    results: tuple[TaskResult, ...],
    info: RunInfo,
    curve_trial: int = 1,
) -> list[Path]:
    """Write results.csv/.md, the figures and summary.md; return the paths written.

    The previous run's figures and summary go first: a kill part way leaves files missing,
    never a figure beside results it was not drawn from.
    """
    for name in (FIGURE11, FIGURE12, FIGURE13, SUMMARY):
        _remove(output / name)
    rows = [row for result in results for row in result.rows]
    files = [
        write_text(output / "results.csv", results_csv(rows)),
        write_text(output / "results.md", results_markdown(experiment, rows)),
        write_bytes(output / FIGURE12, figure12_resilience(experiment, rows)),
        write_bytes(output / FIGURE13, figure13_path_lengths(experiment, rows)),
    ]
    curve = curve_result(experiment, results, curve_trial)
    if curve is not None:
        g = curve.spec.graph
        title = (
            f"Training reward dynamics, {g.label} graph (trial {curve.spec.trial}, "
            f"{curve.rows[0].nodes} nodes), ARL config '{curve.spec.config}'"
        )
        files.append(
            write_bytes(output / FIGURE11, figure11_training(curve.episode_rewards, title))
        )
    figures = tuple(p.name for p in files if p.suffix == ".png")
    info = RunInfo(**{**info.__dict__, "figures": figures})
    files.append(write_text(output / SUMMARY, summary_markdown(info, rows)))
    return files


def curve_result(
    experiment: str, results: tuple[TaskResult, ...], trial: int = 1
) -> TaskResult | None:
    """The task whose ARL curves make Figure 11, or ``None`` when ARL did not run.

    Table 4: the given trial. Table 3: the given trial of the 15/10 configuration (the
    paper's Figure 11 graph), else of the first configuration with curves.
    """
    with_curves = [r for r in results if r.episode_rewards and any(r.episode_rewards.values())]
    if not with_curves:
        return None
    preferred = [r for r in with_curves if r.spec.trial == trial]
    if experiment == "table3":
        paper_graph = [
            r for r in preferred if (r.spec.graph.layers, r.spec.graph.max_nodes) == (15, 10)
        ]
        preferred = paper_graph or preferred
    return (preferred or with_curves)[0]


def _error_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[-1] if text else ''}"
