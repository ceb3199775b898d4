"""Scenes shipped to workers that share no disk with the client.

The client reads the scene file and every file it references (``<include>``
files and every ``<string name="filename">``: meshes, ``.vol``, ``.vdb``),
relative to a common folder, into a :class:`ScenePayload`. A worker writes
them into a private temporary folder, loads and compiles the scene there
once (:func:`prepared`), deletes the folder, and keeps the compiled scene
for every later chunk of the same payload. Shipping the files rather than a
compiled scene keeps the wire format the scene format itself: nothing new to
version, and a worker's loader reports errors exactly as the client's does.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import tempfile
import threading
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

from .. import _core

_VAR = re.compile(r"\$([A-Za-z_][A-Za-z0-9_]*)")


def _subst(text: str, values: dict[str, str]) -> str:
    return _VAR.sub(lambda m: values.get(m.group(1), m.group(0)), text)


def scene_files(scene: Path, defines: Sequence[tuple[str, str]]) -> list[Path]:
    """The scene file and the files it references (resolved, existing, without
    repeats), found the way the loader resolves them: relative to the
    including file, after ``$name`` substitution with the ``<default>``
    values and the ``defines``."""
    out: list[Path] = []
    overrides = dict(defines)

    def visit(path: Path, inherited: dict[str, str], depth: int) -> None:
        path = path.resolve()
        if path in out or depth > 32:
            return
        out.append(path)
        try:
            root = ET.parse(path).getroot()
        except (OSError, ET.ParseError):
            return  # the loader reports it, with its line
        values = dict(inherited)
        for el in root.iter("default"):
            name, value = el.get("name"), el.get("value")
            if name is not None and value is not None:
                values.setdefault(name, value)
        values.update(overrides)
        for el in root.iter():
            ref = None
            if el.tag == "include":
                ref = el.get("filename")
            elif el.tag == "string" and el.get("name") == "filename":
                ref = el.get("value")
            if ref is None:
                continue
            target = path.parent / _subst(ref, values)
            if el.tag == "include":
                visit(target, values, depth + 1)
            elif target.is_file() and target.resolve() not in out:
                out.append(target.resolve())

    visit(scene, {}, 0)
    return out


@dataclass(frozen=True)
class ScenePayload:
    """A scene file with its referenced files, ready to ship to a worker.

    ``files`` maps paths relative to the files' common folder to contents;
    ``main`` is the scene file's relative path; ``digest`` is a SHA-256 of
    the files and the defines (what checkpoints are matched against).
    """

    main: str
    files: tuple[tuple[str, bytes], ...]
    defines: tuple[tuple[str, str], ...]
    digest: str

    @staticmethod
    def from_file(scene: str | os.PathLike[str], defines: Sequence[tuple[str, str]]) -> "ScenePayload":
        paths = scene_files(Path(scene), defines)
        root = Path(os.path.commonpath([str(p.parent) for p in paths]))
        files = []
        h = hashlib.sha256()
        for p in paths:
            rel = p.relative_to(root).as_posix()
            data = p.read_bytes()
            files.append((rel, data))
        for rel, data in sorted(files):
            h.update(f"{rel}\0{len(data)}\0".encode())
            h.update(data)
        for k, v in defines:
            h.update(f"-D{k}={v}\0".encode())
        return ScenePayload(
            main=paths[0].relative_to(root).as_posix(),
            files=tuple(files),
            defines=tuple(defines),
            digest=h.hexdigest(),
        )

    @property
    def nbytes(self) -> int:
        return sum(len(d) for _, d in self.files)


_lock = threading.Lock()
_cache: dict[str, _core.PreparedScene] = {}


def prepared(payload: ScenePayload) -> _core.PreparedScene:
    """The compiled scene of ``payload`` on this process (built once; the
    last two scenes are kept)."""
    with _lock:
        hit = _cache.get(payload.digest)
        if hit is not None:
            return hit
        folder = Path(tempfile.mkdtemp(prefix="fgf-scene-"))
        try:
            for rel, data in payload.files:
                target = folder / rel
                target.parent.mkdir(parents=True, exist_ok=True)
                target.write_bytes(data)
            scene = _core.prepare_scene(str(folder / payload.main), list(payload.defines))
        finally:
            shutil.rmtree(folder, ignore_errors=True)
        while len(_cache) >= 2:
            _cache.pop(next(iter(_cache)))
        _cache[payload.digest] = scene
        return scene
