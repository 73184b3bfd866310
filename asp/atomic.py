"""Atomic file output: write to a temporary file beside the target, then rename.

A reader never sees a half-written file, and an interrupted command leaves the previous
version (or nothing) in place. A temporary file is named ``.<target>.<pid>.<random>.tmp``;
one left behind by a killed process is removed by :func:`remove_stale_temps` (which
:class:`OutputSet` calls before a run writes into a folder).

:class:`OutputSet` writes the files of one run into a folder as one unit: its manifest
(asmplan's own format only) names the files asmplan wrote, so a rerun removes its own old
files and nothing else, and a folder holding anyone else's files is refused unless forced.
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
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        if exc.filename is None and exc.errno is not None:  # a write's error names no file
            raise OSError(exc.errno, exc.strerror, str(target)) from None
        raise
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


class ForeignFilesError(FileExistsError):
    """An output folder that holds files asmplan did not write (``--force`` writes anyway)."""


class OutputSet:
    """The files of one run, written into ``folder`` as one unit (a context manager).

    The manifest (``manifest.json``: ``{"format": "asmplan-manifest/1", "files",
    "pending"}``) says which files of the folder asmplan wrote: ``files`` are one complete
    run (each exists), ``pending`` the files of an unfinished or replaced run, still to be
    removed. Only a manifest of this format counts: any other ``manifest.json`` is the
    user's file like any other.

    On entry: leftover temporary files of killed writes are removed, and a folder holding
    any file the manifest does not name is refused (:class:`ForeignFilesError`, naming
    the folder and a file) unless ``force`` (then those files are left alone, never
    deleted; a ``manifest.json`` not of asmplan's format is refused even then).

    Before this run's first file is written, the manifest switches atomically to "no
    complete run; these files pending" (the previous run's and this run's names); each
    file is written atomically; on a clean exit the stale files of the previous run are
    removed and the manifest switches atomically to this run's files. A kill at any point
    leaves a manifest whose ``files`` all exist and which names every file asmplan wrote,
    so the next run cleans up. On an exception the files this run and the previous one
    wrote are removed, so the folder holds one complete run with its manifest or no run.

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
        force: bool = False,
        manifest: str = MANIFEST,
    ):
        self.folder = Path(folder)
        self.force = force
        self.manifest = manifest
        self._names: list[str] = []
        self._owned: list[str] = []  # files of earlier runs, from the manifest
        self._claimed: set[str] = set()  # the names the manifest says are pending
        self._created = False

    def __enter__(self) -> OutputSet:
        check_output_folder(self.folder, force=self.force, manifest=self.manifest)
        self._created = not self.folder.exists()
        self.folder.mkdir(parents=True, exist_ok=True)
        remove_stale_temps(self.folder)
        self._owned = owned_files(self.folder, self.manifest)
        return self

    def path(self, name: str) -> Path:
        """The path of output ``name`` (registered as part of this run)."""
        if Path(name).name != name or name in ("", ".", "..", self.manifest):
            raise ValueError(f"output name {name!r}: expected a plain file name")
        if name not in self._names:
            self._names.append(name)
        self._claim()
        return self.folder / name

    def _claim(self) -> None:
        """Make the manifest name every file asmplan may have written here, before one is."""
        pending = list(dict.fromkeys([*self._owned, *self._names]))
        if self._claimed.issuperset(pending):
            return
        _write_manifest(self.folder / self.manifest, [], pending)
        self._claimed = set(pending)

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
            for name in {*self._owned, *self._names}:
                (self.folder / name).unlink(missing_ok=True)
            (self.folder / self.manifest).unlink(missing_ok=True)
            remove_stale_temps(self.folder)
            if self._created and not any(self.folder.iterdir()):
                self.folder.rmdir()
            return
        names = [p.name for p in self.written]
        stale = [n for n in {*self._owned, *self._names} if n not in names]
        if stale:
            self._claim()
            for name in stale:
                (self.folder / name).unlink(missing_ok=True)
        _write_manifest(self.folder / self.manifest, names, [])


def _write_manifest(path: Path, files: list[str], pending: list[str]) -> None:
    doc: dict = {"format": MANIFEST_FORMAT, "files": files}
    if pending:
        doc["pending"] = pending
    write_text(path, json.dumps(doc, indent=1) + "\n")


def _manifest_names(folder: Path, manifest: str, keys: tuple[str, ...]) -> list[str]:
    try:
        doc = json.loads((folder / manifest).read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return []
    if not isinstance(doc, dict) or doc.get("format") != MANIFEST_FORMAT:
        return []
    names: list[str] = []
    for key in keys:
        listed = doc.get(key, [])
        if isinstance(listed, list):
            names += [n for n in listed if _plain_name(n, manifest) and n not in names]
    return names


def _plain_name(name: object, manifest: str) -> bool:
    return isinstance(name, str) and bool(name) and Path(name).name == name and name != manifest


def is_own_manifest(folder: str | os.PathLike[str], manifest: str = MANIFEST) -> bool:
    """Whether ``folder/manifest`` is a manifest of asmplan's own format and version."""
    try:
        doc = json.loads((Path(folder) / manifest).read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return False
    return isinstance(doc, dict) and doc.get("format") == MANIFEST_FORMAT


def previous_files(folder: str | os.PathLike[str], manifest: str = MANIFEST) -> list[str]:
    """The complete run the manifest in ``folder`` lists (none when it is missing, broken
    or not asmplan's own format)."""
    return _manifest_names(Path(folder), manifest, ("files",))


def owned_files(folder: str | os.PathLike[str], manifest: str = MANIFEST) -> list[str]:
    """Every file asmplan's manifest in ``folder`` names: the complete run and the pending."""
    return _manifest_names(Path(folder), manifest, ("files", "pending"))


def foreign_files(folder: str | os.PathLike[str], manifest: str = MANIFEST) -> list[str]:
    """The entries of ``folder`` asmplan did not write, sorted: neither named by its
    manifest, nor the manifest itself (when of asmplan's format), nor a temporary file."""
    folder = Path(folder)
    if not folder.is_dir():
        return []
    ours = set(owned_files(folder, manifest))
    if is_own_manifest(folder, manifest):
        ours.add(manifest)
    return sorted(
        entry.name
        for entry in folder.iterdir()
        if entry.name not in ours and not _TEMP_NAME.match(entry.name)
    )


def check_output_folder(
    folder: str | os.PathLike[str], *, force: bool = False, manifest: str = MANIFEST
) -> None:
    """Refuse an output folder holding files asmplan did not write, unless ``force``.

    Raises :class:`ForeignFilesError` (a ``FileExistsError``) naming the folder and one
    such file (and, even with ``force``, a folder whose ``manifest`` is someone else's:
    writing ours would overwrite it); a folder that does not exist, is empty, or holds only
    asmplan's own files passes. Commands call it before any work so a refusal costs nothing.
    """
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise NotADirectoryError(f"{folder}: exists and is not a folder")
    if (folder / manifest).exists() and not is_own_manifest(folder, manifest):
        raise ForeignFilesError(
            f"{folder}: holds a {manifest!r} that is not asmplan's (format "
            f"{MANIFEST_FORMAT!r}); choose another folder (even --force would overwrite it)"
        )
    others = [] if force else foreign_files(folder, manifest)
    if others:
        more = f" and {len(others) - 1} more" if len(others) > 1 else ""
        raise ForeignFilesError(
            f"{folder}: holds {others[0]!r}{more}, not written by asmplan; choose an empty "
            "or new folder, or pass --force to write beside them (they are never deleted)"
        )


__all__ = [
    "ForeignFilesError",
    "OutputSet",
    "check_output_folder",
    "remove_stale_temps",
    "write_bytes",
    "write_text",
]
"""What other modules may use (asmplan and arl among them)."""
