"""How a render's samples are cut into chunks: by their measured cost.

A chunk is a range of samples ``[s0, s1)`` of every pixel. Every chunk covers
the whole film, so the cost of a sample per pixel is the same from one chunk
to the next, and the time of the chunks finished predicts the time of the
next one well. :class:`Chunker` hands out the ranges not yet rendered: the
first ones short (:data:`PROBE_SAMPLES` samples, before
any time is known), then ranges sized so that each takes about ``seconds``
of rendering on its worker; near the end the rest is shared among the
workers, so that they finish together. An explicit ``chunk_spp`` fixes the
size instead. Any cut gives the same image (exact sums, ``docs/theory.md``
§7.17); the cut only trades the per-chunk overhead against progress
granularity, balance and the work a lost worker takes with it
(``docs/cluster.md``, "Cost model").
"""

from __future__ import annotations

import math
from typing import Optional

from ._film import missing

#: Seconds of rendering a chunk aims at when no ``chunk_spp`` is given: the
#: overhead of a chunk (scheduler round trip, its result of 72 bytes per
#: pixel, the merge; measured in docs/cluster.md) is then well under 5 %.
CHUNK_SECONDS = 2.0
#: Samples (pixels x samples per pixel) of the first chunks, before any
#: chunk has been timed: ~0.1 s at 2.5 M samples/s.
PROBE_SAMPLES = 1 << 18
#: Smallest chunk near the end, as a fraction of the timed chunk size.
TAIL_FRACTION = 0.25
#: Largest growth of the chunk size over the largest chunk timed so far.
MAX_GROWTH = 16


class Chunker:
    """The sample ranges of ``[0, spp)`` not in ``done``, cut by cost.

    ``pixels`` is the film's pixel count; ``chunk_spp`` (if given) fixes the
    samples per pixel of every chunk; otherwise chunks aim at ``seconds``
    (default :data:`CHUNK_SECONDS`) of rendering each, from the times passed
    to :meth:`observe`.
    """

    def __init__(
        self,
        done: list[tuple[int, int]],
        spp: int,
        pixels: int,
        chunk_spp: Optional[int] = None,
        seconds: Optional[float] = None,
    ) -> None:
        self.gaps = missing(done, spp, max(spp, 1))
        self.pixels = max(pixels, 1)
        self.fixed = chunk_spp
        self.seconds = CHUNK_SECONDS if seconds is None else seconds
        self.probe = max(1, PROBE_SAMPLES // self.pixels)
        self.timed_spp = 0
        self.timed_seconds = 0.0
        self.largest_timed = 0

    @property
    def remaining(self) -> int:
        """Samples per pixel not yet handed out."""
        return sum(b - a for a, b in self.gaps)

    def observe(self, spp: int, seconds: float) -> None:
        """A chunk of ``spp`` samples per pixel took ``seconds`` to render."""
        if spp > 0 and seconds > 0:
            self.timed_spp += spp
            self.timed_seconds += seconds
            self.largest_timed = max(self.largest_timed, spp)

    def target(self) -> int:
        """Samples per pixel of a chunk of about ``seconds``, from the chunks timed."""
        if self.fixed is not None:
            return self.fixed
        if self.timed_seconds <= 0:
            return self.probe
        k = self.seconds * self.timed_spp / self.timed_seconds
        return max(1, min(int(k), MAX_GROWTH * max(self.largest_timed, self.probe)))

    def size(self, slots: int) -> int:
        """Samples per pixel of the next chunk, with ``slots`` chunks rendering at once."""
        k = self.target()
        if self.fixed is None and slots > 1 and self.timed_seconds > 0:
            # Share the rest among the workers (two chunks in flight each),
            # down to a quarter of the target: they then finish together.
            share = math.ceil(self.remaining / (2 * slots))
            k = min(k, max(share, math.ceil(TAIL_FRACTION * k)))
        return max(1, k)

    def take(self, slots: int = 1) -> Optional[tuple[int, int]]:
        """The next range ``(s0, s1)``, or ``None`` when everything is handed out."""
        if not self.gaps:
            return None
        a, b = self.gaps[0]
        end = min(a + self.size(slots), b)
        if end == b:
            self.gaps.pop(0)
        else:
            self.gaps[0] = (end, b)
        return a, end
