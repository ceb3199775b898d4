"""Progress plumbing and argument checks shared by the long-running Python APIs.

``progress=`` in the public API takes ``True`` (a tqdm bar, shown only when
stderr is a terminal), ``False``/``None`` (quiet), a tqdm-like object with
``update(n)``, or a ``callable(done, total)``; :func:`progress_sink` turns
that into what ``fgf._core`` accepts.
"""

from __future__ import annotations

import contextlib
import sys
from typing import TYPE_CHECKING, Any, Callable, Iterator, Optional, Protocol, Union

import numpy as np

from . import _core

if TYPE_CHECKING:
    from tqdm import tqdm


class SupportsUpdate(Protocol):
    """A tqdm-like progress object: ``update(n)`` with the units finished
    since the last call."""

    def update(self, n: int, /) -> object: ...


#: What ``progress=`` accepts in the public API.
Progress = Union[bool, None, SupportsUpdate, Callable[[int, int], object]]
#: What ``fgf._core`` accepts (``progress_sink`` turns the former into this).
CoreProgress = Union[None, str, SupportsUpdate, Callable[[int, int], object]]


class _TqdmOnFirstCall:
    """A ``progress(done, total)`` callable that opens a tqdm bar lazily."""

    def __init__(self, desc: str) -> None:
        self.desc = desc
        self.bar: Optional[tqdm[Any]] = None
        self.last = 0

    def __call__(self, done: int, total: int) -> None:
        if self.bar is None:
            from tqdm import tqdm

            self.bar = tqdm(total=total, unit_scale=True, desc=self.desc, file=sys.stderr)
        self.bar.update(done - self.last)
        self.last = done

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


@contextlib.contextmanager
def progress_sink(progress: Progress, desc: str) -> Iterator[CoreProgress]:
    """Yield the ``progress`` object to hand to ``_core``; close any bar on exit."""
    if progress is True:
        if not sys.stderr.isatty():
            yield None
            return
        bar = _TqdmOnFirstCall(desc)
        try:
            yield bar
        finally:
            bar.close()
    else:
        yield None if progress is False else progress


def check_int(name: str, value: object, lo: int, hi: int) -> int:
    """``value`` as an int in ``[lo, hi]``, else ``fgf.ParameterError`` naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not lo <= int(value) <= hi:
        raise _core.ParameterError(f"invalid {name} = {value!r}: must be an integer in [{lo}, {hi}]")
    return int(value)


SEED_MAX = 2**64 - 1
U32_MAX = 2**32 - 1
#: Most worker threads a call may ask for.
MAX_THREADS = 4096


def check_seed(seed: object) -> int:
    """A seed is an integer in [0, 2^64 - 1]."""
    return check_int("seed", seed, 0, SEED_MAX)
