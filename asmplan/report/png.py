"""PNG pictures of matplotlib Figures: their bytes, a file written atomically, a data URI."""

from __future__ import annotations

import base64
import io
import os
from pathlib import Path

from asp.atomic import write_bytes


def png_bytes(fig, **savefig) -> bytes:
    """The matplotlib Figure ``fig`` as PNG bytes (``savefig``: more of
    :meth:`matplotlib.figure.Figure.savefig`'s options, e.g. ``dpi``)."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", **savefig)
    return buffer.getvalue()


def write_png(fig, path: str | os.PathLike[str]) -> Path:
    """Write ``fig`` as a PNG file at ``path``, atomically."""
    return write_bytes(path, png_bytes(fig))


def data_uri(png: bytes) -> str:
    """PNG bytes as a ``data:image/png;base64,...`` URI (a self-contained ``<img src>``)."""
    return "data:image/png;base64," + base64.b64encode(png).decode("ascii")
