"""Atomic file output: write to a temporary file beside the target, then rename.

A reader never sees a half-written file, and an interrupted command leaves the previous
version (or nothing) in place. A temporary file is named ``.<target>.<pid>.<random>.tmp``;
one left behind by a killed process is removed by :func:`remove_stale_temps` (which
:class:`OutputSet` calls before a run writes into a folder).

:class:`OutputSet` writes the files of one run into a folder as one unit: the manifest
naming them is written last, so a folder with a manifest never mixes two runs.
"""

from __future__ import annotations

import json
import os
import re
import tempfile
from pathlib import Path


def _read_umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


_UMASK = _read_umask()
"""The process umask, read once at import: reading it means setting it, briefly."""


def write_bytes(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically, creating parent folders; return the path."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(
        prefix=f".{target.name}.{os.getpid()}.", suffix=".tmp", dir=target.parent
    )
    try:
        os.fchmod(fd, 0o666 & ~_UMASK)  # mkstemp makes 0600; give what open() would
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return target


def write_text(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; return the path."""
    return write_bytes(path, text.encode("utf-8"))


_TEMP_NAME = re.compile(r"^\..+\.(\d+)\.[^.]+\.tmp$")


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True
    return True


def remove_stale_temps(folder: str | os.PathLike[str]) -> list[Path]:
    """Remove the temporary files of :func:`write_bytes` left in ``folder`` by dead processes.

    A temporary file names the process that wrote it; one whose process still runs (a
    concurrent writer) is left alone. Returns the files removed.
    """
    folder = Path(folder)
    removed = []
    if not folder.is_dir():
        return removed
    for entry in folder.iterdir():
        match = _TEMP_NAME.match(entry.name)
        if match and entry.is_file() and not _alive(int(match.group(1))):
            entry.unlink(missing_ok=True)
            removed.append(entry)
    return removed


MANIFEST = "manifest.json"
MANIFEST_FORMAT = "asmplan-manifest/1"


class OutputSet:
    """The files of one run, written into ``folder`` as one unit (a context manager).

    On entry: leftover temporary files of killed writes are removed, then the previous
    run's manifest and the files it names (and the names in ``owns``, the files this kind
    of run always writes, for folders written before manifests existed). Each file is
    written atomically; on a clean exit the manifest (``manifest.json``: ``{"format",
    "files"}``) is written last. On an exception the files this run wrote are removed
    again, so the folder holds either one complete run with its manifest or no run at all
    (files not named by a manifest, e.g. the user's own, are never touched).

    Example
    -------
    >>> with OutputSet(folder) as out:                     # doctest: +SKIP
    ...     out.write_text("plan.json", text)
    ...     plot_dag(dag, out.path("dag.png"))             # a writer that takes a path
    """

    def __init__(
        self,
        folder: str | os.PathLike[str],
        *,
        owns: tuple[str, ...] = (),
        manifest: str = MANIFEST,
    ):
        self.folder = Path(folder)
        self.owns = owns
        self.manifest = manifest
        self._names: list[str] = []
        self._created = False

    def __enter__(self) -> OutputSet:
        if self.folder.exists() and not self.folder.is_dir():
            raise NotADirectoryError(f"{self.folder}: exists and is not a folder")
        self._created = not self.folder.exists()
        self.folder.mkdir(parents=True, exist_ok=True)
        remove_stale_temps(self.folder)
        for name in {*previous_files(self.folder, self.manifest), *self.owns}:
            (self.folder / name).unlink(missing_ok=True)
        (self.folder / self.manifest).unlink(missing_ok=True)
        return self

    def path(self, name: str) -> Path:
        """The path of output ``name`` (registered as part of this run)."""
        if Path(name).name != name or name in ("", ".", "..", self.manifest):
            raise ValueError(f"output name {name!r}: expected a plain file name")
        if name not in self._names:
            self._names.append(name)
        return self.folder / name

    def write_bytes(self, name: str, data: bytes) -> Path:
        return write_bytes(self.path(name), data)

    def write_text(self, name: str, text: str) -> Path:
        return write_text(self.path(name), text)

    @property
    def written(self) -> tuple[Path, ...]:
        """The files of this run that exist, in the order they were named."""
        return tuple(self.folder / n for n in self._names if (self.folder / n).is_file())

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is not None:
            for name in self._names:
                (self.folder / name).unlink(missing_ok=True)
            remove_stale_temps(self.folder)
            if self._created and not any(self.folder.iterdir()):
                self.folder.rmdir()
            return
        names = [p.name for p in self.written]
        doc = {"format": MANIFEST_FORMAT, "files": names}
        write_text(self.folder / self.manifest, json.dumps(doc, indent=1) + "\n")


def previous_files(folder: str | os.PathLike[str], manifest: str = MANIFEST) -> list[str]:
    """The file names the manifest in ``folder`` lists (none when it is missing or broken)."""
    try:
        doc = json.loads((Path(folder) / manifest).read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return []
    files = doc.get("files") if isinstance(doc, dict) else None
    if not isinstance(files, list):
        return []
    return [n for n in files if isinstance(n, str) and n and Path(n).name == n and n != manifest]
