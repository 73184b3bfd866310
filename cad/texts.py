"""The one bound on free text read from a file: names, ids and descriptions.

A name (an assembly, a part, an operation, an agent, a tool, a value) is drawn in figure
titles and table cells and keyed on; a description is printed beside a step. Neither has a
use at megabytes, where drawing a title alone took minutes and gigabytes (a 5 MB assembly
name). :func:`bounded` refuses a longer text in one line naming where it is, its length and
the bound.
"""

from __future__ import annotations

from cad.errors import AsmplanError

MAX_NAME = 200
"""Characters of a name or an id."""

MAX_TEXT = 2000
"""Characters of a description, a credit line or other prose."""


def bounded(text: str, where: str, limit: int = MAX_NAME) -> str:
    """``text``, when it has at most ``limit`` characters.

    Raises
    ------
    AsmplanError
        ``where: N characters, over the limit of L`` (one line; ``where`` names the file
        and key).
    """
    if len(text) > limit:
        raise AsmplanError(f"{where}: {len(text):,} characters, over the limit of {limit:,}")
    return text


__all__ = ["MAX_NAME", "MAX_TEXT", "bounded"]
