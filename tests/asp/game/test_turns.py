"""The turn models' registry: each entry's fields, and the lookups that read them."""

from __future__ import annotations

import pytest

from asp.game.turns import ALTERNATE, CONCURRENT, DEFAULT_TURN, TURNS, expected_names, turn_of


def test_the_registry_names_each_model_once_the_default_first():
    assert list(TURNS) == ["alternate", "concurrent"]
    assert next(iter(TURNS.values())) is DEFAULT_TURN is ALTERNATE
    assert all(TURNS[name].name == name for name in TURNS)


@pytest.mark.parametrize(
    ("name", "model"),
    [
        ("alternate", ALTERNATE),
        ("concurrent", CONCURRENT),
        (None, ALTERNATE),  # a document that names none
        ("sequential", ALTERNATE),  # a name of no model: the default's behaviour
        (["concurrent"], ALTERNATE),  # not a name
    ],
)
def test_turn_of(name, model):
    assert turn_of(name) is model


@pytest.mark.parametrize(
    ("model", "game_file", "simultaneous", "columns", "curve", "suffix"),
    [
        (ALTERNATE, True, False, ("operation", "agent"), False, ""),
        (CONCURRENT, False, True, ("starts", "deviations"), True, "-concurrent"),
    ],
)
def test_what_differs(model, game_file, simultaneous, columns, curve, suffix):
    assert model.game_file is game_file
    assert model.simultaneous is simultaneous
    assert model.move_columns == columns
    assert model.plan_curve is curve
    assert model.plan_id_suffix == suffix


def test_expected_names_as_the_errors_wrote_them():
    assert expected_names() == "alternate or concurrent"
    assert expected_names(quote=True) == "'alternate' or 'concurrent'"
