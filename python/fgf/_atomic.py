"""Atomic file writes for the Python side (the Rust side has ``fgf_io::atomic_write``).

The content goes into a temporary file in the target directory, which is
renamed over the target only once it is complete: an error or Ctrl-C never
leaves a half-written file and never destroys the user's previous file. The
result gets the permissions a plain ``open()`` would give (0666 minus the
umask), not ``mkstemp``'s private 0600.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Any, Callable


def write_atomic(path: str | os.PathLike[str], write: Callable[[Any], object], mode: str = "wb") -> str:
    """Write ``path`` through ``write(file_handle)``; return the file name.

    Raises ``FileNotFoundError`` naming the directory when it does not exist.
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise FileNotFoundError(f"{path}: output directory {folder} does not exist")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    except OSError as e:
        # Name the user's file, not the temporary one we failed to create.
        raise OSError(e.errno, f"{path}: cannot write ({e.strerror})") from None
    try:
        with os.fdopen(fd, mode) as fh:
            write(fh)
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    return path.name


def _umask() -> int:
    """The process umask (read by setting and restoring it)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


class StagedOutputs:
    """Every output file of one run: checked before the work, committed together.

    :meth:`add` checks an output (its directory exists and is writable, it
    is not a directory, no two outputs of the run are the same file) and
    reserves a temporary file next to it, whose name the writers get.
    :meth:`commit` renames every temporary file over its target at the end;
    if one rename fails, the targets already replaced are restored from
    hard-link backups, so the user ends with all of the new files or with
    all of the old ones. Leaving the ``with`` block without committing (an
    error, Ctrl-C) removes the temporary files and touches no target.
    """

    def __init__(self) -> None:
        self._items: list[tuple[str, Path, str]] = []

    def __enter__(self) -> StagedOutputs:
        return self

    def __exit__(self, *exc: object) -> None:
        self.discard()

    def add(self, option: str, target: str | os.PathLike[str]) -> str:
        """Check ``target`` (given as ``option``) and return the temporary name to write."""
        path = Path(target)
        if not str(target):
            raise OSError(f"{option}: empty file name")
        folder = path.parent if str(path.parent) else Path(".")
        if not folder.is_dir():
            raise FileNotFoundError(f"{option} {path}: output directory {folder} does not exist")
        if path.is_dir():
            raise IsADirectoryError(f"{option} {path}: is a directory")
        real = os.path.realpath(path)
        for other_option, other, _ in self._items:
            same = os.path.realpath(other) == real
            if not same and path.exists() and other.exists():
                same = os.path.samefile(path, other)
            if same:
                raise OSError(f"{option} {path}: the same file as {other_option} {other}; give each output its own file")
        try:
            fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=f".tmp{path.suffix}", dir=folder)
        except OSError as e:
            raise OSError(e.errno, f"{option} {path}: cannot write ({e.strerror})") from None
        os.close(fd)
        self._items.append((option, path, tmp))
        return tmp

    def __getitem__(self, option: str) -> str:
        """The temporary file reserved for ``option``."""
        return next(tmp for o, _, tmp in self._items if o == option)

    def commit(self) -> None:
        """Rename every temporary file over its target: all of them, or none."""
        backups: list[tuple[Path, str | None]] = []
        try:
            for _, path, tmp in self._items:
                backup = None
                if path.exists():
                    backup = f"{tmp}.old"
                    try:
                        os.link(path, backup)
                    except OSError:
                        backup = None
                backups.append((path, backup))
                os.replace(tmp, path)
        except BaseException:
            for path, backup in reversed(backups):
                try:
                    if backup is not None:
                        os.replace(backup, path)
                    else:
                        os.unlink(path)
                except OSError:
                    pass
            raise
        finally:
            for _, backup in backups:
                if backup is not None:
                    try:
                        os.unlink(backup)
                    except FileNotFoundError:
                        pass
        self._items = []

    def discard(self) -> None:
        """Remove the temporary files not committed."""
        for _, _, tmp in self._items:
            try:
                os.unlink(tmp)
            except FileNotFoundError:
                pass
        self._items = []
