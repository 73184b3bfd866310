"""Part records: the one model of a bill-of-materials row, for BOM files and assembly specs.

A part record names a part and where its mesh is; it holds no geometry. The same record
and the same validation serve a BOM file (CSV or YAML, :func:`read_bom`) and the
``parts:`` list of an ``assembly.yaml`` (``asp.spec``), so both accept the same things.

Keys: ``id`` (required), ``name``, ``file``, ``quantity``, ``type``, ``shape``. ``file`` is
a mesh file relative to the spec or BOM, or ``scene.step#node`` for one part of a scene
file (the node's cleaned id or its name in the file). ``shape`` is the shape class: parts
with the same shape up to a rigid motion share it (``asmplan init`` fills it in). A bare
string in a ``parts:`` list is a record with that id.
"""

from __future__ import annotations

import csv
import difflib
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cad.errors import AsmplanError
from cad.numbers import WRITTEN_PLAINLY, plain_integer
from cad.texts import MAX_TEXT, text_value
from cad.yamlfile import read_yaml

PART_KEYS = ("id", "name", "file", "quantity", "type", "shape")


@dataclass(frozen=True)
class PartRecord:
    """One part of the bill of materials.

    Attributes
    ----------
    id : str
        Unique identifier, used in operations and relation tables.
    name : str
        Human-readable name (the id if not given).
    file : str or None
        Mesh file relative to the BOM/spec, ``file#node`` for one node of a scene file, or
        None (a part without geometry).
    quantity : int
        BOM quantity (informative; each record is one part in the relations).
    type : str
        Free part type from the BOM, e.g. ``"screw"``.
    shape : str
        Shape class: parts with equal shapes up to a rigid motion share it (empty: unknown).
    """

    id: str
    name: str = ""
    file: str | None = None
    quantity: int = 1
    type: str = ""
    shape: str = ""


def unknown_key_message(key: object, known: Iterable[str], word: str = "key") -> str:
    """``unknown key 'gravty' (did you mean 'gravity'?)``, the nearest known key suggested."""
    known = list(known)
    near = difflib.get_close_matches(str(key), known, n=1, cutoff=0.6)
    hint = f" (did you mean {near[0]!r}?)" if near else f" (known: {', '.join(known)})"
    return f"unknown {word} {str(key)!r}{hint}"


def refuse_unknown_keys(mapping: dict, known: Iterable[str], where: str, word="key") -> None:
    """Raise ``AsmplanError`` ``where: unknown key ...`` for the first key not in ``known``."""
    known = tuple(known)
    for key in mapping:
        if key not in known:
            raise AsmplanError(f"{where}: {unknown_key_message(key, known, word)}")


def part_record(row: Any, where: str) -> PartRecord:
    """Validate one BOM row or ``parts:`` entry.

    Parameters
    ----------
    row : str or dict
        A bare id, or a mapping with the keys of :data:`PART_KEYS` (only ``id`` required).
    where : str
        Location for messages, e.g. ``"assembly.yaml: parts[3]"``.

    Raises
    ------
    AsmplanError
        ``where: ...`` naming the problem: not a mapping, no id, an unknown key (the nearest
        known one suggested), a mapping or list where a text goes (the key and the part
        named), a quantity that is not a positive integer.
    """
    if isinstance(row, str | int) and not isinstance(row, bool):
        row = {"id": row}
    if not isinstance(row, dict):
        raise AsmplanError(f"{where}: expected a mapping with an 'id' or a part id")
    refuse_unknown_keys(row, PART_KEYS, where)
    pid = text_value(row.get("id"), f"{where}: id")
    if not pid:
        raise AsmplanError(f"{where}: part has no id")
    at = f"{where} (part {pid!r})"
    return PartRecord(
        id=pid,
        name=text_value(row.get("name"), f"{at}: name") or pid,
        file=text_value(row.get("file"), f"{at}: file", MAX_TEXT) or None,
        quantity=_quantity(row.get("quantity"), at),
        type=text_value(row.get("type"), f"{at}: type"),
        shape=text_value(row.get("shape"), f"{at}: shape"),
    )


def part_records(rows: Any, where: str) -> tuple[PartRecord, ...]:
    """Validate a list of rows (:func:`part_record`); duplicate ids are an error."""
    if not isinstance(rows, list):
        raise AsmplanError(f"{where}: expected a list of parts {{id, name, file, quantity, type}}")
    out, seen = [], set()
    for k, row in enumerate(rows):
        record = part_record(row, f"{where}[{k}]")
        if record.id in seen:
            raise AsmplanError(f"{where}: duplicate part id {record.id!r}")
        seen.add(record.id)
        out.append(record)
    return tuple(out)


def read_bom(path: str | Path) -> tuple[PartRecord, ...]:
    """Records of a BOM file: CSV with a header row, or YAML list / ``{parts: [...]}``.

    Raises
    ------
    FileNotFoundError
        No such file.
    AsmplanError
        Unreadable file or an invalid row (:func:`part_record`), naming the file and row.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"BOM not found: {path}")
    if path.suffix.lower() == ".csv":
        try:
            with path.open(newline="", encoding="utf-8-sig") as handle:
                rows: Any = [
                    {str(k).strip().lower(): v for k, v in row.items() if k and v not in (None, "")}
                    for row in csv.DictReader(handle)
                ]
        except (OSError, UnicodeDecodeError, csv.Error) as exc:
            raise AsmplanError(f"unreadable BOM {path}: {exc}") from None
    else:
        data = read_yaml(path, what="BOM")
        rows = data.get("parts", []) if isinstance(data, dict) else data
    if not isinstance(rows, list):
        raise AsmplanError(f"BOM {path} must be a list of parts")
    return part_records(rows, f"BOM {path}: row")


def _quantity(value: Any, where: str) -> int:
    """A positive integer written plainly (:func:`cad.numbers.plain_integer`: text such as
    ``"2"``, as CSV gives, is accepted; ``010``, ``1_000`` or ``true`` are not)."""
    if value is None or value == "":
        return 1
    number = plain_integer(value)
    if number is None or number < 1:
        raise AsmplanError(
            f"{where}: quantity {value!r} is not a positive integer {WRITTEN_PLAINLY}"
        )
    return number
