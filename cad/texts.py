"""The one bound on free text read from a file: names, ids and descriptions.

A name (an assembly, a part, an operation, an agent, a tool, a value) is drawn in figure
titles and table cells and keyed on; a description is printed beside a step. Neither has a
use at megabytes, where drawing a title alone took minutes and gigabytes (a 5 MB assembly
name). :func:`bounded` refuses a longer text in one line naming where it is, its length and
the bound; :func:`text_value` also refuses a mapping or a list where a text is read (it
would become the text of a Python dict).
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


def text_value(value, where: str, limit: int = MAX_NAME, *, strip: bool = True) -> str:
    """``value`` read as a text ("" for None; a number as written), within ``limit``
    (:func:`bounded`), stripped unless ``strip`` is False.

    Raises
    ------
    AsmplanError
        ``where: expected a text, got a mapping`` (or a list), or over the limit.
    """
    if isinstance(value, dict | list):
        kind = "a mapping" if isinstance(value, dict) else "a list"
        raise AsmplanError(f"{where}: expected a text, got {kind}")
    text = "" if value is None else str(value)
    return bounded(text.strip() if strip else text, where, limit)


__all__ = ["MAX_NAME", "MAX_TEXT", "bounded", "text_value"]
