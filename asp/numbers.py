"""Numbers as JSON values and as text: one home for the small conversions every output uses."""

from __future__ import annotations


def plain(x):
    """A JSON-friendly scalar: numpy scalars (node ids, counts) become Python ones."""
    return x.item() if hasattr(x, "item") else x


def json_number(x, digits: int | None = None):
    """A number for JSON: an int when integral, else the float (rounded to ``digits``).

    ``None`` stays ``None``.
    """
    if x is None:
        return None
    x = float(x)
    if x.is_integer():
        return int(x)
    return x if digits is None else round(x, digits)


def cost_text(x, spec: str = "g") -> str:
    """A cost as text: ``3`` rather than ``3.0``; other values formatted with ``spec``."""
    x = float(x)
    return str(int(x)) if x.is_integer() else format(x, spec)


def cost_unit(cost_model: str) -> str:
    """The unit suffix of a cost in text: ``""`` under ``steps``, ``" s"`` under ``time``."""
    return "" if cost_model == "steps" else " s"


__all__ = [
    "cost_text",
    "cost_unit",
    "json_number",
    "plain",
]
"""What other modules may use (asmplan and arl among them)."""
