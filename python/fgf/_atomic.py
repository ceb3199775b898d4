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
