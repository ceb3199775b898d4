"""Exact film sums of sample ranges, their merge, and checkpoint files.

A :class:`FilmSums` holds the exact fixed-point sums (``docs/theory.md``
§7.17) of the samples in ``ranges`` of every pixel. Merging is integer
addition, so the merged sums, and the image :meth:`FilmSums.finish` makes
of them, have the same bits for any split into chunks and any merge order.
"""

from __future__ import annotations

import io
import json
import os
from dataclasses import dataclass, field
from typing import Any, Callable, Optional, TypeVar

import numpy as np
import numpy.typing as npt

from .. import _atomic, _core

U64 = npt.NDArray[np.uint64]
F32 = npt.NDArray[np.float32]
CHECKPOINT_FORMAT = "fgf-checkpoint-1"
T = TypeVar("T")


def _union(ranges: list[tuple[int, int]]) -> list[tuple[int, int]]:
    out: list[tuple[int, int]] = []
    for a, b in sorted(ranges):
        if out and a <= out[-1][1]:
            out[-1] = (out[-1][0], max(out[-1][1], b))
        else:
            out.append((a, b))
    return out


def missing(done: list[tuple[int, int]], spp: int, chunk_spp: int) -> list[tuple[int, int]]:
    """The chunks (of at most ``chunk_spp`` samples) of ``[0, spp)`` not in ``done``."""
    out: list[tuple[int, int]] = []
    cursor = 0
    for a, b in _union(done) + [(spp, spp)]:
        while cursor < min(a, spp):
            end = min(cursor + chunk_spp, a, spp)
            out.append((cursor, end))
            cursor = end
        cursor = max(cursor, b)
    return out


@dataclass
class FilmSums:
    """Exact per-pixel sums of the samples in ``ranges`` (``[s0, s1)`` pairs)."""

    sum: U64
    sum_sq: Optional[U64]
    ranges: list[tuple[int, int]] = field(default_factory=list)

    @staticmethod
    def empty(height: int, width: int, variance: bool) -> "FilmSums":
        z = np.zeros((height, width, 3, 3), dtype=np.uint64)
        return FilmSums(z, z.copy() if variance else None, [])

    @property
    def samples(self) -> int:
        return sum(b - a for a, b in self.ranges)

    def merge(self, other: "FilmSums") -> None:
        """Add ``other``'s sums (disjoint sample ranges) to these, in place."""
        for a, b in other.ranges:
            for c, d in self.ranges:
                if a < d and c < b:
                    raise _core.ParameterError(f"sample range [{a}, {b}) merged twice (overlaps [{c}, {d}))")
        _core.film_merge(self.sum, other.sum)
        if self.sum_sq is not None and other.sum_sq is not None:
            _core.film_merge(self.sum_sq, other.sum_sq)
        self.ranges = _union(self.ranges + other.ranges)

    def finish(self, spp_requested: int) -> tuple[F32, Optional[F32]]:
        """``(image, variance of the mean or None)`` over the samples held."""
        return _core.film_finish(self.sum, self.sum_sq, self.samples, spp_requested)


def save(path: str | os.PathLike[str], meta: dict[str, Any], arrays: dict[str, npt.NDArray[Any]]) -> None:
    """Write a checkpoint atomically: ``meta`` (JSON) and named arrays, as an ``.npz``."""
    header = np.frombuffer(json.dumps({"format": CHECKPOINT_FORMAT, **meta}, sort_keys=True).encode(), dtype=np.uint8)

    def write(fh: Any) -> None:
        buf = io.BytesIO()
        np.savez(buf, **{"__meta__": header, **arrays})  # type: ignore[arg-type]
        fh.write(buf.getvalue())

    _atomic.write_atomic(path, write)


def load(path: str | os.PathLike[str]) -> tuple[dict[str, Any], dict[str, npt.NDArray[Any]]]:
    """Read a checkpoint written by :func:`save`; ``fgf.ParameterError`` if it is not one."""
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
        meta = json.loads(arrays.pop("__meta__").tobytes().decode())
    except (ValueError, KeyError, OSError, json.JSONDecodeError) as e:
        if isinstance(e, FileNotFoundError):
            raise
        raise _core.ParameterError(f"{path}: not an fgf checkpoint ({e})") from None
    if not isinstance(meta, dict) or meta.get("format") != CHECKPOINT_FORMAT:
        raise _core.ParameterError(f"{path}: not an fgf checkpoint (format {CHECKPOINT_FORMAT} expected)")
    return meta, arrays


def check_meta(path: str | os.PathLike[str], found: dict[str, Any], expected: dict[str, Any]) -> None:
    """Refuse a checkpoint whose settings differ from this run's, naming the first difference."""
    names = {
        "kind": "command",
        "scene_digest": "scene (its files or -D defines)",
        "seed": "--seed",
        "variance": "--variance",
        "width": "film width",
        "height": "film height",
        "resolution": "--resolution",
        "spp": "--spp",
        "padding": "--padding",
        "marginal": "--marginal",
        "nodes": "--nodes",
    }
    for key, want in expected.items():
        got = found.get(key)
        if got != want:
            what = names.get(key, key)
            raise _core.ParameterError(
                f"{path}: checkpoint made with a different {what} ({got!r}, this run has {want!r}); "
                "refusing to mix them: rerun with the original arguments, or remove the checkpoint"
            )


def resume(path: Optional[str], meta: dict[str, Any]) -> Optional[tuple[dict[str, Any], dict[str, npt.NDArray[Any]]]]:
    """The checkpoint at ``path`` (its meta and arrays), or ``None`` if there is
    none yet; ``fgf.ParameterError`` if it was made with other settings than
    ``meta``'s (:func:`check_meta`)."""
    if path is None or not os.path.exists(path):
        return None
    found, arrays = load(path)
    check_meta(path, found, meta)
    return found, arrays


def resume_items(
    path: Optional[str],
    meta: dict[str, Any],
    restore: Callable[[int, dict[str, Any], dict[str, npt.NDArray[Any]]], T],
) -> dict[int, T]:
    """The finished items (ensemble realizations, truth nodes) of the checkpoint
    at ``path``, by index; empty without one. A checkpoint lists its finished
    indices under ``"done"`` (:func:`items_meta`); ``restore(index, meta,
    arrays)`` rebuilds one item from the file."""
    found = resume(path, meta)
    if found is None:
        return {}
    meta_found, arrays = found
    return {int(i): restore(int(i), meta_found, arrays) for i in meta_found.get("done", [])}


def items_meta(meta: dict[str, Any], done: dict[int, Any]) -> dict[str, Any]:
    """``meta`` with the sorted indices of the finished items, as
    :func:`resume_items` reads them."""
    return dict(meta, done=sorted(done))
