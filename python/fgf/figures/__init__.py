"""Reproduce the paper's figures (Guo et al. 2019; ``docs/theory.md`` §5) and
check them in numbers.

``fgf figures --out DIR [--quick]`` (or :func:`make_figures` from Python)
writes into ``DIR``:

* one PNG per figure (matplotlib, Agg; labelled axes, legends, parameters in
  the caption);
* ``index.html``: a self-contained gallery (inline style, relative image
  links) with a short caption under each figure;
* ``results.json``: every number plotted, grouped by figure group, all
  finite, plus the seconds each group took.

The figure groups (one module each):

=================  ==========================================================
``family``         1D covariance matrices (pink noise, k-fBm) and 2D
                   realizations for H = -0.4, 0.2, 0.85, 1.2, 1.8
``variance``       var[σ̄_t]: closed form, quadrature and Monte Carlo over
                   exact 1D realizations (pink against t, k-fBm against L)
``transmittance``  Tr(t) for exponential, white, pink and k-fBm media; the
                   gamma closure against the ensemble average of e^{-τ}
``renders``        one scene, exponential vs H = -0.1, 0.2, 1.2
``comparisons``    energy-conserving vs reciprocal kernel; the Bitterli
                   models (difference images, mean relative errors)
``truth``          the model under both kernels against the exact truth of
                   k-fBm media (``fgf.truth``), α = 1.14, 2, 4, 8
``ensemble``       uncorrelated vs correlated media: the model against
                   explicit 3D realizations (``fgf.ensemble``)
=================  ==========================================================

A group whose part of the fgf API is missing (for example rendering of
``fgf`` media in a partial build) is reported as *unavailable* with the
reason, in the gallery and in ``results.json``; the others still run.

Python::

    import fgf.figures
    results = fgf.figures.make_figures("figs", quick=True)
    results["groups"]["variance"]["status"]     # "ok"

Every group uses fixed seeds derived from ``seed`` (default 2019), so a run
is reproducible; ``quick=True`` uses small resolutions and few realizations
and finishes in a few minutes on two cores.
"""

from __future__ import annotations

import html
import json
import math
import os
import sys
import time
from pathlib import Path
from typing import Any, Callable, Iterable, Protocol, Union, cast

from ._common import Context, GroupResult, Unavailable, write_atomic
from . import comparisons, ensemble, family, renders, transmittance, truth, variance

__all__ = ["GROUPS", "make_figures", "Unavailable"]

#: Figure groups in gallery order: name -> module.
GROUPS = {
    "family": family,
    "variance": variance,
    "transmittance": transmittance,
    "renders": renders,
    "comparisons": comparisons,
    "truth": truth,
    "ensemble": ensemble,
}

#: Scenes used by the render groups (shipped in the repository's
#: ``scenes/figures``; found relative to this package in a source checkout).
DEFAULT_SCENE_DIR = Path(__file__).resolve().parents[3] / "scenes" / "figures"


class ProgressBar(Protocol):
    """What a figure group reports its steps to (a tqdm bar has both methods)."""

    def update(self, n: int = 1, /) -> object: ...

    def close(self) -> object: ...


#: ``progress=`` of :func:`make_figures`.
FiguresProgress = Union[bool, None, ProgressBar, Callable[[str, int, int], object]]


def _progress_bar(progress: FiguresProgress, total: int, label: str) -> ProgressBar:
    """A per-group progress sink with ``update(n)`` and ``close()``.

    ``progress`` is True (a tqdm bar, only when stderr is a terminal), a
    false value (quiet), a tqdm-like object (its ``update`` is called) or a
    callable ``progress(label, done, total)``.
    """

    class _Quiet:
        def update(self, n: int = 1, /) -> None:
            pass

        def close(self) -> None:
            pass

    if not progress:
        return _Quiet()
    if progress is True:
        if not sys.stderr.isatty():
            return _Quiet()
        from tqdm import tqdm

        return tqdm(total=total, desc=label, leave=True, file=sys.stderr)
    if hasattr(progress, "update"):
        return cast(ProgressBar, progress)
    call = progress

    class _Call:
        done = 0

        def update(self, n: int = 1, /) -> None:
            self.done += n
            call(label, self.done, total)

        def close(self) -> None:
            pass

    return _Call()


def _check_finite(obj: Any, where: str) -> None:
    """Every number in ``results.json`` must be finite: a NaN or inf is a bug
    in a group, reported with its key path."""
    if isinstance(obj, dict):
        for k, v in obj.items():
            _check_finite(v, f"{where}.{k}")
    elif isinstance(obj, (list, tuple)):
        for i, v in enumerate(obj):
            _check_finite(v, f"{where}[{i}]")
    elif isinstance(obj, bool) or obj is None or isinstance(obj, str):
        return
    elif isinstance(obj, (int, float)):
        if not math.isfinite(obj):
            raise ValueError(f"non-finite number in results: {where} = {obj}")
    else:
        raise TypeError(f"results: {where} has type {type(obj).__name__}, expected a JSON number")


def make_figures(
    out: str | os.PathLike[str],
    quick: bool = False,
    seed: int = 2019,
    groups: Iterable[str] | None = None,
    progress: FiguresProgress = True,
    scene_dir: str | os.PathLike[str] | None = None,
) -> dict[str, Any]:
    """Make the figures, the gallery and ``results.json`` in ``out``.

    Parameters
    ----------
    out : path-like
        Output directory; created if missing. Files of earlier runs with the
        same names are replaced atomically; other files are kept.
    quick : bool
        Small resolutions and few realizations (minutes on two cores).
    seed : int
        Base seed; every group derives fixed seeds from it.
    groups : iterable of str, optional
        Subset of :data:`GROUPS` to run (default: all, in gallery order).
    progress : bool, tqdm-like or callable
        True: one tqdm bar per group when stderr is a terminal; False/None:
        quiet; an object with ``update(n)``; or ``callable(group, done,
        total)``.
    scene_dir : path-like, optional
        Directory of the figure scenes (default: ``scenes/figures`` of the
        source checkout).

    Returns
    -------
    dict
        The content of ``results.json``: ``groups[name]`` holds ``status``
        (``"ok"`` or ``"unavailable"``), ``reason``, ``figures`` and
        ``results``; ``seconds[name]`` the wall time of each group.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    names = list(GROUPS) if groups is None else list(groups)
    for n in names:
        if n not in GROUPS:
            from .. import ParameterError

            raise ParameterError(f"unknown figure group '{n}' (valid: {', '.join(GROUPS)})")
    scene_dir = Path(scene_dir) if scene_dir is not None else DEFAULT_SCENE_DIR
    report: dict[str, Any] = {
        "quick": bool(quick),
        "seed": int(seed),
        "groups": {},
        "seconds": {},
    }
    for name in names:
        mod = GROUPS[name]
        bar = _progress_bar(progress, mod.steps(quick), name)

        def tick(b: ProgressBar = bar) -> None:
            b.update(1)

        ctx = Context(out=out, quick=quick, seed=seed, tick=tick, scene_dir=scene_dir)
        start = time.perf_counter()
        try:
            res: GroupResult = mod.run(ctx)
            _check_finite(res.results, name)
            entry = {
                "status": "ok",
                "reason": "",
                "title": mod.TITLE,
                "figures": [f.__dict__ for f in res.figures],
                "results": res.results,
            }
        except Unavailable as e:
            entry = {
                "status": "unavailable",
                "reason": str(e),
                "title": mod.TITLE,
                "figures": [],
                "results": {},
            }
        finally:
            bar.close()
        report["seconds"][name] = round(time.perf_counter() - start, 3)
        report["groups"][name] = entry
        if name == "truth" and entry["status"] == "ok":
            report["truth"] = entry["results"]
        # Rewrite the outputs after each group so that an interrupted run
        # still leaves a consistent gallery of the groups that finished.
        _write_outputs(out, report)
    return report


def _write_outputs(out: Path, report: dict[str, Any]) -> None:
    text = json.dumps(report, indent=1, allow_nan=False)
    write_atomic(out / "results.json", lambda fh: fh.write(text), mode="w")
    page = gallery_html(report)
    write_atomic(out / "index.html", lambda fh: fh.write(page), mode="w")


_STYLE = """
body { font-family: sans-serif; max-width: 1100px; margin: 2em auto; padding: 0 1em; color: #222; }
h1 { font-size: 1.6em; } h2 { font-size: 1.25em; margin-top: 2em; border-bottom: 1px solid #ccc; }
figure { margin: 1.2em 0; } figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: 0.92em; color: #444; margin-top: 0.3em; }
.unavailable { background: #fff3f0; border-left: 4px solid #c33; padding: 0.6em 1em; }
.meta { color: #666; font-size: 0.9em; }
"""


def gallery_html(report: dict[str, Any]) -> str:
    """The self-contained gallery page for ``report`` (the results dict)."""
    e = html.escape
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        "<title>fgf figures</title>",
        f"<style>{_STYLE}</style></head><body>",
        "<h1>Fractional Gaussian fields: the paper's figures, regenerated</h1>",
        '<p class="meta">Made by <code>fgf figures</code>'
        + (" --quick" if report["quick"] else "")
        + f", seed {report['seed']}. Every plotted number is in "
        '<a href="results.json">results.json</a>. Formulas: docs/theory.md §1–4; '
        "figure list: docs/theory.md §5.</p>",
    ]
    for name, g in report["groups"].items():
        secs = report["seconds"].get(name, 0.0)
        parts.append(f'<h2 id="{e(name)}">{e(g["title"])}</h2>')
        parts.append(f'<p class="meta">group <code>{e(name)}</code>, {secs:.1f} s</p>')
        if g["status"] != "ok":
            parts.append(f'<p class="unavailable">Not made: {e(g["reason"])}</p>')
            continue
        for f in g["figures"]:
            parts.append(
                f'<figure><img src="{e(f["file"])}" alt="{e(f["title"])}">'
                f'<figcaption><b>{e(f["title"])}.</b> {e(f["caption"])}</figcaption></figure>'
            )
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"
