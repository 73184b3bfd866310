"""Read YAML safely: no code, bounded alias expansion, numbers only in plain decimal
(:class:`PlainNumbers`), optionally decimals kept as text.

YAML aliases share one node, so a 1 KB file of nested aliases ("billion laughs") loads in
microseconds but expands to gigabytes once written out (a plan echoes its input). The
loaded document is therefore measured as if every alias were expanded, and refused past
:data:`MAX_EXPANDED_VALUES`.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import yaml

from cad.errors import AsmplanError
from cad.numbers import PLAIN_INTEGER

MAX_EXPANDED_VALUES = 1_000_000
"""Most values (scalars, lists, mappings, counted with aliases expanded) a file may hold."""


_INT, _FLOAT = "tag:yaml.org,2002:int", "tag:yaml.org,2002:float"
_MERGE = "tag:yaml.org,2002:merge"


class PlainNumbers(yaml.SafeLoader):
    """SafeLoader that reads only numbers written in plain decimal as numbers
    (:mod:`cad.numbers`): ``010``, ``0x10``, ``1_000``, ``1:30`` stay text, as written,
    for the check that names them (``.inf`` and ``.nan`` are still floats); and a mapping
    that repeats a key is refused (YAML's keys are unique; PyYAML would keep the last)."""

    def construct_mapping(self, node, deep=False):
        first: dict[str, int] = {}
        for key_node, _ in node.value:
            if not isinstance(key_node, yaml.ScalarNode) or key_node.tag == _MERGE:
                continue
            line = key_node.start_mark.line + 1
            if key_node.value in first:
                raise yaml.constructor.ConstructorError(
                    None,
                    None,
                    f"duplicate key {key_node.value!r} at line {line} (first at line "
                    f"{first[key_node.value]}): give each key once",
                    None,
                )
            first[key_node.value] = line
        return super().construct_mapping(node, deep=deep)


class DecimalsAsText(PlainNumbers):
    """:class:`PlainNumbers` that keeps decimal-looking scalars as strings too (``1.10``
    stays ``"1.10"``)."""


def _resolvers(keep_floats: bool) -> dict:
    """The implicit resolvers of SafeLoader with ints (and floats) in plain decimal only."""
    plain_float = re.compile(
        rf"^(?:{PLAIN_INTEGER}\.[0-9]*(?:[eE][-+]?[0-9]+)?|[-+]?\.[0-9]+(?:[eE][-+]?[0-9]+)?"
        r"|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$"
    )
    plain = {_INT: re.compile(rf"^{PLAIN_INTEGER}$"), _FLOAT: plain_float}
    out = {}
    for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items():
        kept = [
            (tag, plain.get(tag, regexp))
            for tag, regexp in resolvers
            if keep_floats or tag != _FLOAT
        ]
        if kept:
            out[first] = kept
    return out


PlainNumbers.yaml_implicit_resolvers = _resolvers(keep_floats=True)
DecimalsAsText.yaml_implicit_resolvers = _resolvers(keep_floats=False)


def read_yaml(path: str | Path, *, what: str, decimals_as_text: bool = False) -> Any:
    """The parsed YAML document of ``path``.

    Parameters
    ----------
    path : str or Path
        The file.
    what : str
        What the file is, for messages (``"assembly spec"``, ``"BOM"``).
    decimals_as_text : bool
        Keep ``1.10`` as the string ``"1.10"`` (operation ids) instead of a float. Either
        way ``010``, ``0x10``, ``1_000`` and ``1:30`` stay text (:class:`PlainNumbers`).

    Raises
    ------
    AsmplanError
        One line naming the file: malformed YAML, not UTF-8 text, or aliases that expand
        past :data:`MAX_EXPANDED_VALUES` values.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise AsmplanError(f"{path}: not a UTF-8 text file ({exc.reason})") from None
    loader = DecimalsAsText if decimals_as_text else PlainNumbers
    try:
        data = yaml.load(text, Loader=loader)  # noqa: S506 - a SafeLoader subclass
    except yaml.YAMLError as exc:
        first = " ".join(str(exc).split())
        raise AsmplanError(f"{path}: malformed YAML in {what} ({first})") from None
    except RecursionError:
        raise AsmplanError(f"{path}: {what} is nested too deeply") from None
    if expanded_size(data) > MAX_EXPANDED_VALUES:
        raise AsmplanError(
            f"{path}: {what} expands to more than {MAX_EXPANDED_VALUES:,} values through "
            "YAML aliases (refused: an alias bomb or a runaway file)"
        )
    return data


def expanded_size(data: Any) -> int:
    """Number of values in ``data`` with every shared (aliased) node counted each time.

    Linear in the number of distinct nodes (sizes are memoised by identity); a
    self-referencing document counts as infinitely large.
    """
    sizes: dict[int, float] = {}
    open_nodes: set[int] = set()

    def size(node: Any) -> float:
        if not isinstance(node, dict | list):
            return 1
        key = id(node)
        if key in sizes:
            return sizes[key]
        if key in open_nodes:
            return float("inf")
        open_nodes.add(key)
        children = [*node.keys(), *node.values()] if isinstance(node, dict) else node
        total = 1.0
        for child in children:
            total += size(child)
            if total > MAX_EXPANDED_VALUES:
                break
        open_nodes.discard(key)
        sizes[key] = total
        return total

    try:
        total = size(data)
    except RecursionError:
        return MAX_EXPANDED_VALUES + 1
    return int(min(total, MAX_EXPANDED_VALUES + 1))
