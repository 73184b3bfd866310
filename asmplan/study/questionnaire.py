"""The study's questionnaire: scales, items, and the check of a participant's answers.

An item is the researcher's text with a scale: a rating scale of whole numbers
``min..max`` (each point may have a label: ``1: Strongly disagree``), or free text. An
answer is checked against its item (a rating a whole number on the scale, a text at most
:data:`MAX_TEXT` characters) and an item left unanswered is missing: it is absent from the
stored answers, never a default value. ``required: true`` items must be answered.

The API shape of an item (``GET /api/questionnaire``) keeps the earlier one: ``{"id",
"text", "scale": [min, max] | null}``, with ``labels`` (point -> text), ``required`` and
``scale_name``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

MAX_TEXT = 2000
"""Longest free-text answer, characters."""
MAX_ITEMS = 200


@dataclass(frozen=True)
class Scale:
    """A rating scale of whole numbers ``low..high`` with optional labels per point."""

    name: str
    low: int
    high: int
    labels: dict[int, str] = field(default_factory=dict)


@dataclass(frozen=True)
class Item:
    """One question: ``scale`` None for free text."""

    id: str
    text: str
    scale: Scale | None
    required: bool = False

    def to_dict(self) -> dict:
        s = self.scale
        return {
            "id": self.id,
            "text": self.text,
            "scale": None if s is None else [s.low, s.high],
            "scale_name": None if s is None else s.name,
            "labels": {} if s is None else {str(k): v for k, v in sorted(s.labels.items())},
            "required": self.required,
        }


class AnswerError(ValueError):
    """An answer the questionnaire does not accept (HTTP 422), naming the item."""


def check_answers(items: list[Item], answers: dict) -> dict:
    """The answers as stored: each checked against its item; unanswered items absent.

    Raises
    ------
    AnswerError
        An unknown item, a rating off its scale or not a whole number, a text too long or
        not text, a required item missing.
    """
    by_id = {item.id: item for item in items}
    out = {}
    for key, value in answers.items():
        item = by_id.get(key)
        if item is None:
            raise AnswerError(f"unknown questionnaire item {key!r}")
        if value is None:
            continue  # explicitly unanswered: missing
        if item.scale is None:
            if not isinstance(value, str):
                raise AnswerError(f"item {key!r}: expected text, got {value!r}")
            if len(value) > MAX_TEXT:
                raise AnswerError(f"item {key!r}: text over {MAX_TEXT} characters")
            if value.strip():
                out[key] = value
            continue
        s = item.scale
        ok = isinstance(value, int | float) and not isinstance(value, bool)
        if ok and isinstance(value, float):
            ok = math.isfinite(value) and value == int(value)
        if not ok or not s.low <= value <= s.high:
            raise AnswerError(
                f"item {key!r}: expected a whole number from {s.low} to {s.high} "
                f"(scale {s.name}), got {value!r}"
            )
        out[key] = int(value)
    missing = [i.id for i in items if i.required and i.id not in out]
    if missing:
        raise AnswerError(f"item {missing[0]!r} must be answered")
    return out


def items_from_data(data, where: str, scales: dict[str, Scale] | None = None) -> list[Item]:
    """Items from parsed YAML/JSON: ``[{"id", "text", "scale", "required"?}]``.

    ``scale`` is a scale's name (of ``scales``), ``[low, high]``, ``{"min", "max",
    "labels"?}``, ``text`` or null (free text). Raises ``ValueError`` naming ``where``."""
    scales = scales or {}
    if not isinstance(data, list) or not data:
        raise ValueError(f"{where}: expected a list of questionnaire items")
    if len(data) > MAX_ITEMS:
        raise ValueError(f"{where}: {len(data)} items, at most {MAX_ITEMS}")
    items, seen = [], set()
    for n, raw in enumerate(data):
        at = f"{where}[{n}]"
        if not isinstance(raw, dict):
            raise ValueError(f"{at}: expected an item {{id, text, scale}}")
        unknown = sorted(set(raw) - {"id", "text", "scale", "required"})
        if unknown:
            raise ValueError(f"{at}: unknown key {unknown[0]!r}")
        iid, text = raw.get("id"), raw.get("text")
        if not isinstance(iid, str) or not iid or len(iid) > 64:
            raise ValueError(f"{at}: expected an id (text, at most 64 characters)")
        if iid in seen:
            raise ValueError(f"{at}: item id {iid!r} given twice")
        seen.add(iid)
        if not isinstance(text, str) or not text.strip() or len(text) > MAX_TEXT:
            raise ValueError(f"{at} ({iid}): expected the item's text")
        required = raw.get("required", False)
        if not isinstance(required, bool):
            raise ValueError(f"{at} ({iid}): required: expected true or false")
        items.append(Item(iid, text.strip(), _item_scale(raw.get("scale"), at, scales), required))
    return items


def _item_scale(value, at: str, scales: dict[str, Scale]) -> Scale | None:
    if value is None or value == "text":
        return None
    if isinstance(value, str):
        if value not in scales:
            known = ", ".join(sorted(scales)) or "none defined"
            raise ValueError(f"{at}: unknown scale {value!r} (scales: {known}, or text)")
        return scales[value]
    if isinstance(value, list):
        return scale_from_data("", {"min": value[0], "max": value[-1]} if value else {}, at)
    if isinstance(value, dict):
        return scale_from_data("", value, at)
    raise ValueError(f"{at}: scale: expected a scale name, [min, max], or text")


def scale_from_data(name: str, data, where: str) -> Scale:
    """A :class:`Scale` from ``{"min", "max", "labels"?}``."""
    if not isinstance(data, dict):
        raise ValueError(f"{where}: expected a scale {{min, max, labels}}")
    unknown = sorted(set(data) - {"min", "max", "labels"})
    if unknown:
        raise ValueError(f"{where}: unknown key {unknown[0]!r}")
    low, high = data.get("min"), data.get("max")
    for key, x in (("min", low), ("max", high)):
        if not isinstance(x, int) or isinstance(x, bool):
            raise ValueError(f"{where}: {key}: expected a whole number, got {x!r}")
    if not low < high or high - low > 100:
        raise ValueError(f"{where}: expected min < max (at most 100 points), got {low}..{high}")
    labels = data.get("labels") or {}
    if not isinstance(labels, dict):
        raise ValueError(f"{where}: labels: expected point -> text")
    out = {}
    for k, v in labels.items():
        try:
            point = int(k)
        except (TypeError, ValueError):
            raise ValueError(f"{where}: label {k!r}: expected a point of the scale") from None
        if not low <= point <= high or not isinstance(v, str):
            raise ValueError(f"{where}: label {k!r}: expected a point {low}..{high} with text")
        out[point] = v
    return Scale(name or f"{low}-{high}", low, high, out)
