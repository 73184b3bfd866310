"""The one rule of a number as written (issue 26 item 9): plain decimal only; ``010``,
``1_000``, ``1:30``, ``0x10`` and ``true`` refused with the value as written, in the YAML
loader, the BOM's quantity (CSV and YAML) and every number of a spec."""

from __future__ import annotations

import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st

from cad.bom import read_bom
from cad.errors import AsmplanError
from cad.numbers import plain_integer, plain_number
from cad.yamlfile import DecimalsAsText, PlainNumbers

NOT_PLAIN = ["010", "00", "1_000", "1:30", "0x10", "0o10", "0b1", "01.5", "1_0.5", "", "ten"]


@pytest.mark.parametrize(
    ("value", "number", "integer"),
    [
        (12, 12.0, 12),
        ("12", 12.0, 12),
        (" 7 ", 7.0, 7),
        ("-3", -3.0, -3),
        ("+10", 10.0, 10),
        ("0", 0.0, 0),
        ("0.5", 0.5, None),
        (".5", 0.5, None),
        ("2e3", 2000.0, None),
        ("1.5E-2", 0.015, None),
        (1.25, 1.25, None),
        (True, None, None),
        (False, None, None),
        (None, None, None),
        ([1], None, None),
        *[(text, None, None) for text in NOT_PLAIN],
    ],
)
def test_a_number_is_written_in_plain_decimal(value, number, integer):
    assert plain_number(value) == number
    assert plain_integer(value) == integer


@given(st.integers(min_value=-(10**12), max_value=10**12))
def test_every_integer_as_python_writes_it_is_plain(n):
    assert plain_integer(str(n)) == n and plain_number(str(n)) == n


@given(st.integers(min_value=0, max_value=10**6), st.integers(min_value=1, max_value=3))
def test_leading_zeros_are_never_a_number(n, zeros):
    text = "0" * zeros + str(n)
    assert plain_number(text) is None and plain_integer(text) is None


@pytest.mark.parametrize(
    ("scalar", "plain", "decimals"),
    [
        ("010", "010", "010"),
        ("1_000", "1_000", "1_000"),
        ("1:30", "1:30", "1:30"),
        ("0x10", "0x10", "0x10"),
        ("12", 12, 12),
        ("-3", -3, -3),
        ("1.5", 1.5, "1.5"),
        ("1.10", 1.1, "1.10"),
        ("01.5", "01.5", "01.5"),
        ("1_0.5", "1_0.5", "1_0.5"),
        ("true", True, True),
    ],
)
def test_yaml_reads_only_plain_numbers_as_numbers(scalar, plain, decimals):
    assert yaml.load(f"k: {scalar}", Loader=PlainNumbers) == {"k": plain}  # noqa: S506
    assert yaml.load(f"k: {scalar}", Loader=DecimalsAsText) == {"k": decimals}  # noqa: S506


@pytest.mark.parametrize("kind", ["csv", "yaml"])
@pytest.mark.parametrize("quantity", ["010", "1_000", "0x2", "true", "2.0", "0"])
def test_a_bom_quantity_not_written_plainly_names_file_row_and_value(tmp_path, kind, quantity):
    path = tmp_path / f"bom.{kind}"
    if kind == "csv":
        path.write_text(f"id,quantity\nA,1\nB,{quantity}\n")
    else:
        path.write_text(f"- {{id: A, quantity: 1}}\n- {{id: B, quantity: {quantity}}}\n")
    with pytest.raises(AsmplanError) as info:
        read_bom(path)
    text = str(info.value)
    assert str(path) in text and "row[1]" in text and "'B'" in text, text
    assert "quantity" in text and quantity in text.lower() and "\n" not in text, text


@pytest.mark.parametrize("kind", ["csv", "yaml"])
def test_a_bom_quantity_written_plainly_is_read(tmp_path, kind):
    path = tmp_path / f"bom.{kind}"
    if kind == "csv":
        path.write_text("id,quantity\nA, 2\nB,10\nC,\n")
    else:
        path.write_text("- {id: A, quantity: 2}\n- {id: B, quantity: '10'}\n- {id: C}\n")
    assert [r.quantity for r in read_bom(path)] == [2, 10, 1]
