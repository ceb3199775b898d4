"""Exact ground truth for constant-α media (``docs/theory.md`` §6.1, §6.3).

A k-fBm ``fgf`` medium or a ``nonexponential`` Davis medium has one gamma
shape α for every segment length, and the random medium behind it is, in
each realization, ``sigma(x) = X sigma_m rho(x)`` with ``X ~ Gamma(alpha,
mean 1)`` and ``rho`` the macro density (1 without one). The truth is the
average of *classical* renders over ``X``, computed with the generalised
Gauss–Laguerre rule of ``Gamma(alpha, mean 1)``::

    truth = sum_i w_i render(scene with sigma_t -> x_i sigma_t)

deterministic in the nodes, Monte Carlo only within each node's render; no
non-exponential kernel is involved (the scene's ``kernel`` is ignored). The
default node count is the smallest that reproduces the closed form
``(1 + tau/alpha)^-alpha`` to 1e-4 relative at the scene's largest optical
depth (``docs/theory.md`` §6.3); the Rust module ``fgf_render::truth`` has
the details.

The computation is split in two public steps so that the node renders can
run anywhere (one process, or a cluster) and still give the same image:

* :func:`truth_plan` — ``alpha`` and the ``(x_i, w_i)`` of the scene;
* :func:`render_node` — the classical render of node ``i``, which depends
  only on the scene, the node count, ``i``, ``spp`` and ``seed``;

:func:`truth` renders every node and sums them in node order.

>>> import fgf                                                        # doctest: +SKIP
>>> t = fgf.truth("scenes/fgf-cube-2fbm.xml", spp=64, seed=0)         # doctest: +SKIP
>>> model = fgf.render("scenes/fgf-cube-2fbm.xml", spp=64)           # doctest: +SKIP
>>> (model.mean() / t.mean()) - 1    # the kernel's departure from the truth  # doctest: +SKIP
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal, Optional, overload

import numpy as np
import numpy.typing as npt

from . import _core

if TYPE_CHECKING:
    from ._progress import Progress
    from .render import Defines

#: An image: ``(H, W, 3)`` float32.
Image = npt.NDArray[np.float32]

__all__ = ["truth", "truth_plan", "truth_render_node", "TruthPlan"]


@dataclass(frozen=True)
class TruthPlan:
    """The quadrature of a scene's truth.

    Attributes
    ----------
    alpha : float
        Gamma shape of the scene's constant-α media.
    x, weights : tuple of float
        Nodes ``x_i`` (levels of ``X``, mean 1) and weights ``w_i`` (sum 1),
        in node order.
    tau_max : float
        The largest optical depth the node rule was chosen for (bounding-box
        diagonal of the media times their largest mean extinction).
    auto_nodes : bool
        Whether the node count came from the default rule.
    closed_form_error : float
        The rule's worst relative error for ``(1 + tau/alpha)^-alpha`` at
        ``tau_max`` and ``tau_max/2, /4, /8``.
    media : tuple of int
        Indices of the media scaled by ``X``.
    width, height, spp : int
        The scene's image size and samples per pixel.
    """

    alpha: float
    x: tuple[float, ...]
    weights: tuple[float, ...]
    tau_max: float
    auto_nodes: bool
    closed_form_error: float
    media: tuple[int, ...]
    width: int
    height: int
    spp: int

    @property
    def nodes(self) -> int:
        """Number of nodes."""
        return len(self.x)


def _check_nodes(nodes: int | None) -> int | None:
    from ._progress import check_int

    return None if nodes is None else check_int("nodes", nodes, 1, 4096)


def truth_plan(scene: str | os.PathLike[str], nodes: int | None = None, defines: Defines = None) -> TruthPlan:
    """The quadrature of ``scene``'s truth: its ``alpha`` and ``(x_i, w_i)``.

    Parameters
    ----------
    scene : path
        A Mitsuba 3 XML scene whose non-exponential media are k-fBm ``fgf``
        or ``nonexponential`` ``davis`` media (with or without a density
        grid), all with the same ``alpha``.
    nodes : int, optional
        Number of nodes (1–4096; default: the adaptive rule).
    defines : dict or list of "name=value", optional
        Overrides of the scene's ``<default>`` values.

    Raises
    ------
    fgf.SceneError
        One line when the scene has no such medium, media with different
        ``alpha``, RGB ``sigma_t`` whose channels have different ``alpha``,
        or a medium without a constant ``alpha`` (pink or white noise,
        Davis–Weinstein with ``h < 1``).
    fgf.ParameterError
        A bad ``nodes``.
    """
    from .render import _defines_list

    p = _core.truth_plan(os.fspath(scene), nodes=_check_nodes(nodes), defines=_defines_list(defines))
    return TruthPlan(
        alpha=float(p["alpha"]),
        x=tuple(float(v) for v in p["x"]),
        weights=tuple(float(v) for v in p["weights"]),
        tau_max=float(p["tau_max"]),
        auto_nodes=bool(p["auto_nodes"]),
        closed_form_error=float(p["closed_form_error"]),
        media=tuple(int(v) for v in p["media"]),
        width=int(p["width"]),
        height=int(p["height"]),
        spp=int(p["spp"]),
    )


def render_node(
    scene: str | os.PathLike[str],
    node: int,
    nodes: int | None = None,
    spp: int | None = None,
    seed: int = 0,
    threads: int | None = None,
    defines: Defines = None,
    progress: Any = None,
    return_variance: bool = False,
) -> tuple[Image, Optional[Image]]:
    """Render node ``node`` of the truth of ``scene`` classically.

    The image depends only on ``scene`` (and ``defines``), ``nodes``,
    ``node``, ``spp`` and ``seed``; the node's render seed is derived from
    ``(seed, node)``. ``progress`` is what ``fgf._core`` accepts (None, a
    tqdm-like object with ``update(n)``, or ``callable(done, total)``).
    Returns ``(image, variance or None)``, unweighted.

    Raises
    ------
    KeyboardInterrupt
        On Ctrl-C (a partial node is discarded).
    """
    from ._progress import check_int, check_seed
    from .render import _defines_list

    img, var, interrupted = _core.render_truth_node(
        os.fspath(scene),
        check_int("node", node, 0, 4095),
        nodes=_check_nodes(nodes),
        spp=spp,
        seed=check_seed(seed),
        threads=threads,
        defines=_defines_list(defines),
        progress=progress,
        return_variance=return_variance,
    )
    if interrupted or img is None:
        raise KeyboardInterrupt(f"truth interrupted during node {node}")
    return img, var


#: :func:`render_node` under its package-level name (``fgf.truth`` is the function).
truth_render_node = render_node


class _Offset:
    """Turns one node's ``(done, total)`` callbacks into ``update(n)`` of a
    bar over all the nodes."""

    def __init__(self, bar: Any) -> None:
        self.bar = bar
        self.last = 0

    def __call__(self, done: int, total: int) -> None:
        if done > self.last:
            self.bar.update(done - self.last)
            self.last = done


class _CallTotal:
    """A ``progress(done, total)`` callable of the whole truth, as a bar."""

    def __init__(self, call: Any, offset: int, total: int) -> None:
        self.call, self.offset, self.total = call, offset, total

    def update(self, n: int) -> None:
        self.offset += n
        self.call(self.offset, self.total)


@overload
def truth(
    scene: str | os.PathLike[str],
    spp: int | None = None,
    nodes: int | None = None,
    seed: int = 0,
    defines: Defines = None,
    progress: Progress = True,
    threads: int | None = None,
    return_stderr: Literal[False] = False,
    *,
    client: Any = None,
    checkpoint: str | os.PathLike[str] | None = None,
) -> Image: ...
@overload
def truth(
    scene: str | os.PathLike[str],
    spp: int | None = None,
    nodes: int | None = None,
    seed: int = 0,
    defines: Defines = None,
    progress: Progress = True,
    threads: int | None = None,
    *,
    return_stderr: Literal[True],
    client: Any = None,
    checkpoint: str | os.PathLike[str] | None = None,
) -> tuple[Image, Image]: ...
def truth(
    scene: str | os.PathLike[str],
    spp: int | None = None,
    nodes: int | None = None,
    seed: int = 0,
    defines: Defines = None,
    progress: Progress = True,
    threads: int | None = None,
    return_stderr: bool = False,
    *,
    client: Any = None,
    checkpoint: str | os.PathLike[str] | None = None,
) -> Image | tuple[Image, Image]:
    """The exact ensemble average of ``scene`` over constant-α realizations.

    Parameters
    ----------
    scene : path
        A Mitsuba 3 XML scene (see :func:`truth_plan` for what it may hold).
    spp : int, optional
        Samples per pixel of *each* node's render (default: the scene's).
    nodes : int, optional
        Number of quadrature nodes (default: the adaptive rule of
        ``docs/theory.md`` §6.3).
    seed : int
        Master seed; node ``i`` renders with a seed derived from
        ``(seed, i)``. The image never depends on ``threads``.
    defines : dict or list of "name=value", optional
        Overrides of the scene's ``<default>`` values.
    progress : bool, tqdm-like object or callable, optional
        As for :func:`fgf.render`, counted in samples over all nodes
        (``nodes × pixels × spp``).
    threads : int, optional
        Worker threads (default: all cores).
    return_stderr : bool
        Also return the per-pixel standard error ``sqrt(sum_i w_i² var_i)``
        of the Monte Carlo noise of the node renders.
    client : dask.distributed.Client, optional
        Render one node per Dask task on the client's workers; the nodes are
        still summed here in node order, so the image has the same bits
        (``fgf.cluster``, ``docs/cluster.md``).
    checkpoint : path, optional
        Save the finished node renders there as they arrive (with or without
        a client); a rerun with the same arguments resumes from them.

    Returns
    -------
    numpy.ndarray
        ``(H, W, 3)`` float32 linear RGB; with ``return_stderr``,
        ``(image, stderr)``.

    Raises
    ------
    fgf.SceneError
        The scene is outside what the truth covers (one line saying why).
    KeyboardInterrupt
        On Ctrl-C; nothing is returned (a partial quadrature sum is no truth).
    """
    from ._progress import progress_sink

    plan = truth_plan(scene, nodes=nodes, defines=defines)
    n_spp = plan.spp if spp is None else int(spp)
    per_node = plan.width * plan.height * n_spp
    total = per_node * plan.nodes
    acc = np.zeros((plan.height, plan.width, 3), dtype=np.float64)
    var_acc = np.zeros_like(acc) if return_stderr else None
    if client is not None or checkpoint is not None:
        from . import cluster
        from ._progress import check_seed
        from .render import _defines_list

        run = cluster.truth_nodes(
            scene, plan.nodes, spp=spp, seed=check_seed(seed), threads=threads, defines=_defines_list(defines),
            progress=progress, return_variance=return_stderr, client=client, checkpoint=checkpoint,
        )
        if run.lost is not None:
            raise cluster.ClusterError(run.lost)
        if run.interrupted:
            raise KeyboardInterrupt(f"truth interrupted after {len(run.nodes)} of {plan.nodes} nodes")
        for i, w in enumerate(plan.weights):
            _add_node(acc, var_acc, w, run.nodes[i].image, run.nodes[i].variance)
        return _finish(acc, var_acc)
    with progress_sink(progress, "truth") as sink:
        bar: Any = None
        if sink is not None:
            bar = sink if hasattr(sink, "update") else _CallTotal(sink, 0, total)
        for i, w in enumerate(plan.weights):
            img, var = render_node(
                scene,
                i,
                nodes=plan.nodes,
                spp=spp,
                seed=seed,
                threads=threads,
                defines=defines,
                progress=None if bar is None else _Offset(bar),
                return_variance=return_stderr,
            )
            _add_node(acc, var_acc, w, img, var)
    return _finish(acc, var_acc)


def _add_node(
    acc: npt.NDArray[np.float64],
    var_acc: Optional[npt.NDArray[np.float64]],
    w: float,
    img: Image,
    var: Optional[Image],
) -> None:
    """Add node ``w``-weighted (one code path for local and cluster runs, so
    the sums have the same bits)."""
    acc += w * img.astype(np.float64)
    if var_acc is not None and var is not None:
        var_acc += (w * w) * var.astype(np.float64)


def _finish(acc: npt.NDArray[np.float64], var_acc: Optional[npt.NDArray[np.float64]]) -> Image | tuple[Image, Image]:
    out = acc.astype(np.float32)
    if var_acc is not None:
        return out, np.sqrt(np.maximum(var_acc, 0.0)).astype(np.float32)
    return out
