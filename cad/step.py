"""STEP files (ISO 10303-21): checks of the text before OCCT reads it, OCCT's messages kept
off stdout, and a check that every solid of the file came through.

OCCT (through cascadio) tells nothing to its caller about a file it cannot read: a
truncated, garbage or header-only file leaves no converted GLB behind (trimesh then says
``FileNotFoundError ... converted.glb``), and a damaged entity silently drops the body that
needs it. It prints what went wrong (``*** ERR StepReaderData : Unresolved Reference ***``)
on the process's stdout, where a command's output goes (``relations --format json``).

So :func:`read_step` (1) checks the text first (:func:`check_step_text`: the
``ISO-10303-21;`` header, a ``DATA`` section with entities, the closing
``END-ISO-10303-21;``), naming the file and what is wrong with it; (2) runs OCCT with the
process's stdout (file descriptor 1) sent to a temporary file (:func:`captured_stdout`);
(3) counts the solids the file defines (``MANIFOLD_SOLID_BREP``, ``BREP_WITH_VOIDS``,
``FACETED_BREP``) against the meshes read: fewer meshes than solids means a body was lost,
an error naming the counts, the entity references the file leaves undefined and OCCT's
own words. OCCT's messages on a file that reads whole become one warning.
"""

from __future__ import annotations

import os
import re
import sys
import tempfile
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import trimesh

from cad.errors import GeometryError

MAGIC = b"ISO-10303-21"
"""The first token of every STEP file (Part 21 exchange structure)."""
SOLID_ENTITIES = ("MANIFOLD_SOLID_BREP", "BREP_WITH_VOIDS", "FACETED_BREP")
"""Entities of one solid body each: every one becomes at least one mesh."""
MAX_MESSAGES = 3
"""OCCT messages quoted in an error or warning (distinct ones, in order)."""

_STRING = re.compile(rb"'(?:[^']|'')*'")
_ANSI = re.compile(r"\x1b\[[0-9;]*m")


def read_step(path: Path, load: Callable[[], trimesh.Scene]) -> trimesh.Scene:
    """A STEP file read by ``load`` (trimesh through cascadio), checked before and after.

    Parameters
    ----------
    path : Path
        The STEP file.
    load : callable
        Reads ``path`` into a scene (OCCT prints to stdout while it runs).

    Raises
    ------
    GeometryError
        The file is not a STEP file, is truncated, holds no entities, OCCT reads nothing
        from it, or OCCT drops a solid of it (each naming the file and the cause).
    """
    data = path.read_bytes()
    body = _STRING.sub(b"''", data)  # string literals may hold '#', ';' or 'DATA'
    check_step_text(path, data, body)
    with captured_stdout() as said:
        try:
            scene = load()
        except FileNotFoundError:  # cascadio wrote no GLB: OCCT read nothing
            scene = None
    messages = occt_messages(said[0] if said else "")
    quoted = f"; OCCT said: {'; '.join(messages)}" if messages else ""
    if scene is None:
        raise GeometryError(f"OCCT could not read STEP file {path}{quoted}")
    solids = solid_count(body)
    read = sum(1 for g in scene.geometry.values() if len(getattr(g, "faces", ())))
    if read < solids:
        missing = undefined_references(body)
        named = (
            f"; entities refer to {', '.join(f'#{k}' for k in missing[:4])}"
            f"{' and more' if len(missing) > 4 else ''}, which the file does not define"
            if missing
            else ""
        )
        raise GeometryError(
            f"STEP file {path} is damaged: it defines {solids} solids and OCCT read "
            f"{read}{named}{quoted}; repair or re-export it"
        )
    if messages:
        warnings.warn(f"{path.name}: OCCT: {'; '.join(messages)}", stacklevel=3)
    return scene


def check_step_text(path: Path, data: bytes, body: bytes) -> None:
    """Raise a one-line GeometryError if ``data`` (the file's bytes; ``body`` the same with
    string literals emptied) is not a whole STEP file.

    Checked: the ``ISO-10303-21;`` header (else garbage, or another format under a STEP
    name), a ``DATA;`` section (else header only), at least one entity ``#n = ...`` in it,
    and the closing ``END-ISO-10303-21;`` (else truncated, with where it stops).
    """
    head = data.lstrip(b"\xef\xbb\xbf \t\r\n")
    if not head.startswith(MAGIC):
        raise GeometryError(
            f"{path} is not a STEP file: it does not begin with 'ISO-10303-21;' (it begins "
            f"{_shown(head[:24])})"
        )
    data_at = re.search(rb"\bDATA\s*(\([^;]*\))?\s*;", body)
    if data_at is None:
        raise GeometryError(f"STEP file {path} holds a header but no DATA section (no geometry)")
    if re.search(rb"#\d+\s*=", body[data_at.end() :]) is None:
        raise GeometryError(f"STEP file {path} has an empty DATA section (no entities)")
    if re.search(rb"END-ISO-10303-21\s*;\s*$", body.rstrip(b"\x00 \t\r\n\x1a")) is None:
        lines = data.count(b"\n") + 1
        raise GeometryError(
            f"STEP file {path} is truncated: it stops at line {lines} ({len(data)} bytes) "
            "without 'END-ISO-10303-21;' (copy or export it again)"
        )


def document_files(path: Path) -> tuple[str, ...]:
    """The files a STEP file's ``DOCUMENT_FILE`` entities name, in order, without repeats."""
    try:
        text = path.read_text(encoding="latin-1")
    except OSError:
        return ()
    found = re.findall(r"DOCUMENT_FILE\s*\(\s*'([^']+)'", text, flags=re.IGNORECASE)
    return tuple(dict.fromkeys(found))


def solid_count(body: bytes) -> int:
    """The number of solid-body entities (:data:`SOLID_ENTITIES`) a file's text (string
    literals emptied) defines."""
    names = b"|".join(name.encode() for name in SOLID_ENTITIES)
    return len(re.findall(rb"#\d+\s*=\s*(?:" + names + rb")\s*\(", body))


def solid_shells(path: Path) -> tuple[int, ...] | None:
    """The face count of each closed shell of a STEP file's one solid, outer shell first,
    when that solid is a ``BREP_WITH_VOIDS`` (FreeCAD writes a product fused into one solid
    so, each body a shell: the APLAN toy truck's 61); None for any other file (several
    solids, no voids, unreadable text). :func:`cad.bodies.closed_bodies` cuts the mesh by
    these counts."""
    try:
        body = _STRING.sub(b"''", path.read_bytes())
    except OSError:
        return None
    if solid_count(body) != 1:
        return None
    solid = re.search(rb"#\d+\s*=\s*BREP_WITH_VOIDS\s*\((.*?)\)\s*;", body, flags=re.S)
    if solid is None:
        return None
    shells = {
        int(k): (kind, args)
        for k, kind, args in re.findall(
            rb"#(\d+)\s*=\s*((?:ORIENTED_)?CLOSED_SHELL)\s*\((.*?)\)\s*;", body, flags=re.S
        )
    }
    counts = []
    for ref in (int(k) for k in re.findall(rb"#(\d+)", solid.group(1))):
        kind, args = shells.get(ref, (b"", b""))
        if kind == b"ORIENTED_CLOSED_SHELL":
            inner = re.findall(rb"#(\d+)", args)
            kind, args = shells.get(int(inner[0]), (b"", b"")) if inner else (b"", b"")
        if kind != b"CLOSED_SHELL":
            return None
        counts.append(len(re.findall(rb"#\d+", args)))
    return tuple(counts) if len(counts) > 1 else None


def undefined_references(body: bytes) -> list[int]:
    """Entity ids a file's text (string literals emptied) refers to (``#n`` in an entity)
    but never defines, ascending."""
    defined = {int(k) for k in re.findall(rb"#(\d+)\s*=", body)}
    used = {int(k) for k in re.findall(rb"#(\d+)(?!\d|\s*=)", body)}
    return sorted(used - defined)


@contextmanager
def captured_stdout() -> Iterator[list[str]]:
    """Send the process's stdout (file descriptor 1, where C++ libraries print) to a
    temporary file while the block runs; the list yielded holds its text afterwards."""
    said: list[str] = []
    sys.stdout.flush()
    saved = os.dup(1)
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), 1)
        try:
            yield said
        finally:
            sys.stdout.flush()
            os.dup2(saved, 1)
            os.close(saved)
            sink.seek(0)
            said.append(sink.read().decode("utf-8", errors="replace"))


def occt_messages(text: str) -> list[str]:
    """OCCT's distinct messages in ``text`` (colour codes and ``***`` frames removed),
    at most :data:`MAX_MESSAGES`."""
    out: list[str] = []
    for line in _ANSI.sub("", text).splitlines():
        line = line.strip().strip("*").strip()
        if line and line not in out:
            out.append(line)
    return out[:MAX_MESSAGES]


def _shown(head: bytes) -> str:
    """The first bytes of a file (up to its first line end), as text when printable, else
    in hex."""
    line = head.splitlines()[0] if head.strip() else head
    text = line.decode("latin-1")
    if text and text.isprintable():
        return repr(text)
    return "with bytes " + head[:12].hex(" ")
