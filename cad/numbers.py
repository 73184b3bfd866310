"""Numbers as a person writes them in a spec or a BOM: the one rule of what text is a number.

A number is written in plain decimal: an optional sign, digits with no leading zero (``0``
itself, ``0.5``), an optional fraction and exponent (``12``, ``-3``, ``1.5``, ``2e3``,
``.5``). YAML 1.1 (PyYAML) and Python read more, and silently read it otherwise than it
looks: ``010`` is 8 in YAML (octal) and 10 in Python, ``1_000`` is 1000, ``1:30`` is 90 (base
60), ``0x10`` is 16, and ``true`` is 1 to Python. Each is refused where a number is
expected, with the value as written (the YAML loader of :mod:`cad.yamlfile` keeps such
scalars as text, so the value as written reaches the check).

The spec (:mod:`asp.spec`), the BOM (:mod:`cad.bom`), the tolerances and the build frame
call :func:`plain_number` and :func:`plain_integer`; each names its file, key or row.
"""

from __future__ import annotations

import re

PLAIN_INTEGER = r"[-+]?(?:0|[1-9][0-9]*)"
"""An integer in plain decimal (a regular expression)."""
PLAIN_NUMBER = rf"(?:{PLAIN_INTEGER}(?:\.[0-9]*)?|[-+]?\.[0-9]+)(?:[eE][-+]?[0-9]+)?"
"""A number in plain decimal, fraction and exponent optional (a regular expression)."""
WRITTEN_PLAINLY = "written in plain decimal (like 12, 0.5 or 2e3)"
"""What a message says a number must be."""

_INTEGER = re.compile(PLAIN_INTEGER)
_NUMBER = re.compile(PLAIN_NUMBER)


def plain_number(value) -> float | None:
    """``value`` as a float when it is a number written plainly, else None.

    An ``int`` or ``float`` (a YAML or JSON number, never a ``bool``) is one; text is one
    when it matches :data:`PLAIN_NUMBER` once stripped (CSV cells, YAML scalars kept as
    text). Infinities and NaN pass as numbers: the caller's range check names them.
    """
    if isinstance(value, bool):
        return None
    if isinstance(value, int | float):
        return float(value)
    if isinstance(value, str) and _NUMBER.fullmatch(value.strip()):
        return float(value.strip())
    return None


def plain_integer(value) -> int | None:
    """``value`` as an int when it is an integer written plainly (an ``int``, not a
    ``bool``, or text matching :data:`PLAIN_INTEGER`), else None."""
    if isinstance(value, bool):
        return None
    if isinstance(value, int):
        return value
    if isinstance(value, str) and _INTEGER.fullmatch(value.strip()):
        return int(value.strip())
    return None
