"""The error policy: every bad input is one line ``asmplan: error: ...`` and exit 2."""

from __future__ import annotations

import pytest

import asmplan.errors
import asp.errors
from asmplan.cli import main
from asmplan.cli.options import MAX_STATES_HELP
from asmplan.errors import AsmplanError
from asp.game.io import save_dag
from asp.graph.state_graph import DEFAULT_MAX_STATES
from tests.asp.figures import figure4


def run(capsys, *args: str) -> tuple[int, str]:
    """Exit code and stderr of ``asmplan ARGS``."""
    with pytest.raises(SystemExit) as info:
        main(list(args))
    return info.value.code, capsys.readouterr().err


def run_out(capsys, *args: str) -> tuple[int, str]:
    """Exit code and stdout of ``asmplan ARGS``."""
    with pytest.raises(SystemExit) as info:
        main(list(args))
    return info.value.code, capsys.readouterr().out


def one_line_error(code: int, err: str) -> str:
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("asmplan: error: "), err
    return lines[0]


def test_the_max_states_help_names_the_default():
    assert f"{DEFAULT_MAX_STATES:,}" in MAX_STATES_HELP


def test_the_whole_family_is_re_exported():
    """``asmplan.errors`` lists its names again (the linter counts a re-export only in a
    literal ``__all__``): the two lists stay one."""
    assert asmplan.errors.__all__ == asp.errors.__all__


@pytest.mark.parametrize("name", asmplan.errors.__all__)
def test_one_family_of_value_errors(name):
    kind = getattr(asmplan.errors, name)
    assert issubclass(kind, AsmplanError) and issubclass(kind, ValueError)


@pytest.fixture
def graph(tmp_path):
    return str(save_dag(figure4(), tmp_path / "g.json"))


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (("synth", "--layers", "2", "--max-nodes", "2", "--seed", "-1", "-o", "x.json"), "--seed"),
        (("synth", "--layers", "2", "--max-nodes", "2", "--max-actions", "100000000000"),
         "--max-actions"),
        (("solve", "GRAPH", "--games", "1000000000"), "--games"),
        (("solve", "GRAPH", "--wcpl", "nan"), "--wcpl"),
        (("solve", "GRAPH", "--wcpl", "inf"), "--wcpl"),
        (("solve", "GRAPH", "--format", "yaml"), "--format"),
        (("solve", "GRAPH", "--bogus"), "--bogus"),
        (("solve",), "graph"),
        (("baseline", "GRAPH", "--seed", "99999999999"), "--seed"),
        (("baseline", "GRAPH", "--time-limit", "0"), "--time-limit"),
        (("baseline", "GRAPH", "--workers", "0"), "--workers"),
        (("play", "GRAPH", "--as", "referee"), "--as"),
        (("graph", "GRAPH", "--list", "-3"), "--list"),
        (("evaluate", "GRAPH", "--model", ".", "--games", "0"), "--games"),
        (("train", "GRAPH", "--output", "run", "--max-cycles", "0"), "--max-cycles"),
        (("train", "GRAPH", "--output", "run", "--max-memory", "1e7"), "--max-memory"),
        (("plan", "GRAPH", "--max-memory", "1e7"), "--max-memory"),
        (("plan", "GRAPH", "--max-memory", "0"), "--max-memory"),
        (("experiment", "table3", "--seed", "-1"), "--seed"),
        (("nosuchcommand",), "nosuchcommand"),
    ],
)  # fmt: skip
def test_usage_errors_are_one_line_naming_the_option(capsys, graph, args, needle):
    """Issue 14, item 7: Typer's error boxes and unbounded options."""
    args = [graph if a == "GRAPH" else a for a in args]
    line = one_line_error(*run(capsys, *args))
    assert needle in line


def test_output_under_a_regular_file(capsys, graph, tmp_path):
    """Issue 14, item 6: ``--output`` under a regular file was a FileExistsError traceback."""
    blocker = tmp_path / "file"
    blocker.write_text("x")
    for args in (
        ("synth", "--layers", "2", "--max-nodes", "2", "-o", str(blocker / "g.json")),
        ("plan", "examples/vacuum_pump", "--output", str(blocker / "out")),
        ("plan", "examples/vacuum_pump", "--output", str(blocker)),
        ("graph", "examples/vacuum_pump", "--output", str(tmp_path)),
        ("train", graph, "--output", str(blocker / "run"), "--max-cycles", "1"),
    ):
        line = one_line_error(*run(capsys, *args))
        assert str(tmp_path) in line
    assert blocker.read_text() == "x"


def test_deeply_nested_json_is_one_line(capsys, tmp_path):
    """Issue 14, item 6: JSON nested 200,000 deep was a RecursionError traceback."""
    path = tmp_path / "deep.json"
    path.write_text("[" * 200_000 + "]" * 200_000)
    line = one_line_error(*run(capsys, "solve", str(path)))
    assert "deep.json" in line and "nested too deeply" in line


def test_os_errors_name_the_path(capsys, tmp_path):
    folder = tmp_path / "folder.json"
    folder.mkdir()
    line = one_line_error(*run(capsys, "solve", str(folder)))
    assert "folder.json" in line


def test_help_still_works(capsys):
    code, out = run_out(capsys, "solve", "--help")
    assert code == 0 and "--games" in out


def test_library_warnings_are_one_line(capsys, graph, monkeypatch):
    import warnings

    import asp.game.io

    real = asp.game.io.load_dag

    def load_with_a_warning(path):
        warnings.warn("part X is not watertight:\nvolume may be wrong", stacklevel=2)
        return real(path)

    monkeypatch.setattr(asp.game.io, "load_dag", load_with_a_warning)
    code, err = run(capsys, "solve", graph, "--games", "10")
    assert code == 0
    assert err == "asmplan: warning: part X is not watertight: volume may be wrong\n"


def test_cli_choices_are_the_domain_names():
    from arl.config import CONFIGS
    from asmplan.cli.experiment import ConfigChoice, TableChoice
    from asmplan.cli.options import CostModel
    from asmplan.experiments.tasks import EXPERIMENT_KEYS
    from asp.game.rules import COST_MODELS

    assert tuple(ConfigChoice) == tuple(CONFIGS)
    assert tuple(TableChoice) == tuple(EXPERIMENT_KEYS)
    assert tuple(CostModel) == COST_MODELS
