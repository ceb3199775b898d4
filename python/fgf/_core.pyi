"""Type stubs for the private native module ``fgf._core`` (crate ``fgf-py``).

One section per area, in the order of the crates below the binding:
errors, progress, transmittance (``fgf-core``), field (``fgf-field``),
io (``fgf-io`` through ``fgf-field``'s exporter and the image writers),
render and ensemble (``fgf-render``). The typed public API is the Python
package ``fgf``; these functions take already-converted arguments.
"""

from collections.abc import Callable, Sequence
from typing import Any, ClassVar, Protocol, TypeAlias, TypedDict, final

import numpy as np
import numpy.typing as npt

__version__: str
simd: str
__all__ = [
    "__version__",
    "simd",
    "FgfError",
    "ParameterError",
    "SceneError",
    "_Model",
    "ModelFunction",
    "c_const",
    "s_p",
    "s_kf",
    "binom",
    "kfbm_point_variance",
    "line_average_variance",
    "synthesize",
    "synthesis_info",
    "sample_optical_depth",
    "sample_kfbm_1d",
    "sw_3d_for_ray_statistics",
    "variogram",
    "covariance",
    "radial_power_spectrum",
    "line_average_second_moment",
    "write_field",
    "write_vdb",
    "read_vdb",
    "render_scene",
    "write_exr",
    "write_png",
    "bsdf_eval_pdf",
    "bsdf_sample",
    "shading_frame",
    "ensemble_scene",
    "PreparedScene",
    "prepare_scene",
    "render_range",
    "film_merge",
    "film_finish",
    "truth_plan",
    "render_truth_node",
    "TruthBar",
]

_F64Array: TypeAlias = npt.NDArray[np.float64]
_F32Array: TypeAlias = npt.NDArray[np.float32]
_FloatArray: TypeAlias = npt.NDArray[np.floating[Any]]  # float32 or float64

# --- errors ---------------------------------------------------------------------

class FgfError(ValueError):
    """Base class of fgf's errors."""

class ParameterError(FgfError):
    """A parameter outside its valid range; the message names it and the range."""

class SceneError(FgfError):
    """An invalid scene file or one outside the supported subset (file:line:col)."""

# --- progress -------------------------------------------------------------------
# Every long job takes ``progress``: None or False (quiet), "bar" (an
# indicatif bar on stderr), an object with ``update(n)`` (units finished since
# the last call, e.g. a tqdm bar) or a callable ``progress(done, total)``.
# Ctrl-C cancels the job.

class _Updatable(Protocol):
    def update(self, n: int, /) -> object: ...

_Progress: TypeAlias = bool | str | _Updatable | Callable[[int, int], object] | None

# --- transmittance --------------------------------------------------------------

@final
class ModelFunction:
    """The function of a model that :meth:`_Model.eval` maps over an array
    (a native enum: members compare equal to their index, ``int(member)``)."""

    TR: ClassVar[ModelFunction]
    PDF: ClassVar[ModelFunction]
    MEDIUM_SURFACE: ClassVar[ModelFunction]
    MEDIUM_MEDIUM: ClassVar[ModelFunction]
    SAMPLE_SURFACE: ClassVar[ModelFunction]
    SAMPLE_MEDIUM: ClassVar[ModelFunction]
    VARIANCE: ClassVar[ModelFunction]
    ALPHA: ClassVar[ModelFunction]
    def __int__(self) -> int: ...

class _ModelParams(TypedDict, total=False):
    """What :meth:`_Model.params` returns: ``kind`` and ``sigma_t`` always,
    then the parameters of that kind."""

    kind: str  # "exponential", "fgf", "davis" or "davis_weinstein"
    sigma_t: float
    hurst: float  # fgf
    sw: float  # fgf
    length: float | None  # fgf (None unless k-fBm)
    regime: str  # fgf: "white", "pink" or "k-fbm"
    k: int  # fgf: k-fBm order, 0 for white and pink noise
    alpha: float  # davis
    h: float  # davis_weinstein
    c: float  # davis_weinstein

@final
class _Model:
    """Native transmittance model behind fgf.Exponential/Fgf/Davis/DavisWeinstein."""

    @staticmethod
    def exponential(sigma_t: float) -> _Model: ...
    @staticmethod
    def fgf(sigma_t: float, hurst: float, sw: float, length: float | None = None) -> _Model: ...
    @staticmethod
    def davis(sigma_t: float, alpha: float) -> _Model: ...
    @staticmethod
    def davis_weinstein(sigma_t: float, h: float, c: float) -> _Model: ...
    def eval(self, what: ModelFunction, x: _F64Array) -> _F64Array:
        """``what`` elementwise over a 1-D contiguous float64 array (samplers
        check ``0 <= u < 1``; ``VARIANCE``/``ALPHA`` need an Fgf model)."""
    @property
    def sigma_bar(self) -> float: ...
    def params(self) -> _ModelParams: ...
    def to_davis(self) -> _Model: ...
    def to_davis_weinstein(self) -> _Model: ...

def c_const(hurst: float, d: int = 1) -> float: ...
def s_p(hurst: float, sw: float) -> float: ...
def s_kf(hurst: float, sw: float) -> float: ...
def binom(a: float, k: int) -> float: ...
def kfbm_point_variance(hurst: float, sw: float, x: _F64Array) -> _F64Array: ...
def line_average_variance(hurst: float, sw: float, t: _F64Array, length: float | None = None) -> _F64Array: ...

# --- field ----------------------------------------------------------------------

def synthesize(
    shape: Sequence[int],
    hurst: float,
    sw: float,
    spacing: float,
    seed: int,
    anchor: str | Sequence[int] | None,
    padding: float | None,
    dtype: str,
    progress: _Progress,
) -> _FloatArray:
    """One realization, C order, ``dtype`` "float32" or "float64"."""

def synthesis_info(
    shape: Sequence[int], hurst: float, sw: float, spacing: float, padding: float | None, dtype: str
) -> tuple[float, list[int], int | None]:
    """``(discrete spectral variance, padded shape, peak bytes or None)``."""

def sample_optical_depth(
    n_rays: int, n_steps: int, t_max: float, hurst: float, sw: float, seed: int, progress: _Progress
) -> tuple[_F64Array, _F64Array]:
    """``(tau (n_rays, n_steps + 1), t (n_steps + 1))``."""

def sample_kfbm_1d(
    n_samples: int, n_steps: int, length: float, hurst: float, sw: float, seed: int, progress: _Progress
) -> tuple[_F64Array, _F64Array]:
    """``(values (n_samples, n_steps + 1), x (n_steps + 1))``."""

def sw_3d_for_ray_statistics(hurst: float, sw: float) -> float: ...
def variogram(field: _FloatArray, axis: int, max_lag: int) -> list[float]: ...
def covariance(field: _FloatArray, axis: int, max_lag: int) -> list[float]: ...
def radial_power_spectrum(field: _FloatArray, spacing: float, n_bins: int) -> tuple[list[float], list[float], list[int]]:
    """``(mean |k|, mean periodogram, mode count)`` per non-empty bin."""

def line_average_second_moment(field: _FloatArray, axis: int, lengths: Sequence[int]) -> list[float]: ...

# --- io -------------------------------------------------------------------------

def write_field(
    path: str,
    field: _FloatArray,
    spacing: float,
    mean: float,
    scale: float,
    clamp_min: float | None,
    png_percentiles: tuple[float, float],
) -> dict[str, Any]:
    """Write by extension (.npy, .vol, .exr, .png), atomically; returns
    ``format``, ``min``, ``max``, ``n_negative`` of the written values."""

def write_exr(path: str, img: _F32Array) -> None:
    """Write an ``(H, W, 3)`` float32 image as a linear float32 EXR (atomically)."""

def write_png(path: str, img: _F32Array, exposure: float = 0.0) -> None:
    """Write an ``(H, W, 3)`` float32 linear image as an sRGB PNG preview (atomically)."""

# --- render ---------------------------------------------------------------------

def render_scene(
    scene: str,
    spp: int | None = None,
    seed: int | None = None,
    threads: int | None = None,
    defines: Sequence[tuple[str, str]] | None = None,
    progress: _Progress = None,
    return_variance: bool = False,
) -> tuple[_F32Array, _F32Array | None, int, bool]:
    """Render a scene file: ``(image (H, W, 3) float32, variance or None, spp_done, interrupted)``."""

def bsdf_eval_pdf(
    scene: str,
    shape: int,
    wi: _F32Array,
    wo: _F32Array,
    defines: Sequence[tuple[str, str]] | None = None,
) -> tuple[_F32Array, _F32Array]:
    """The BSDF of shape ``shape`` at ``(n, 3)`` local-frame direction pairs (normal ``+z``):
    ``(f(wi, wo)·|cos θ_o| (n, 3), pdf of sampling wo (n,))``, as Mitsuba's ``BSDF.eval``/``pdf``."""

def bsdf_sample(
    scene: str,
    shape: int,
    wi: _F32Array,
    u: _F32Array,
    defines: Sequence[tuple[str, str]] | None = None,
) -> tuple[_F32Array, _F32Array, _F32Array]:
    """The BSDF of shape ``shape`` sampled at ``(n, 3)`` local-frame directions ``wi`` with the
    random numbers ``u`` (``(n, 3)``: the lobe choice, then the direction): ``(wo (n, 3),
    weight f·|cos θ_o|/pdf (n, 3), pdf (n,))``, zeros where no sample, as Mitsuba's ``BSDF.sample``."""

def shading_frame(
    scene: str,
    origins: _F32Array,
    directions: _F32Array,
    defines: Sequence[tuple[str, str]] | None = None,
) -> tuple[_F32Array, npt.NDArray[np.int64]]:
    """The shading frame ``(s, t, n)`` at the first hits of ``(n, 3)`` rays: ``(frames (n, 9), NaN
    for a miss; the shape hit (n,), -1 for a miss)``, the frame anisotropic BSDFs are evaluated in."""

_U64Array: TypeAlias = npt.NDArray[np.uint64]

@final
class PreparedScene:
    """A compiled scene kept by a worker (see ``fgf.cluster``)."""

    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def spp(self) -> int: ...
    @property
    def seed(self) -> int: ...

def prepare_scene(scene: str, defines: Sequence[tuple[str, str]] | None = None) -> PreparedScene:
    """Load and compile a scene file for :func:`render_range`."""

def render_range(
    prepared: PreparedScene,
    s0: int,
    s1: int,
    seed: int | None = None,
    variance: bool = False,
    threads: int | None = None,
    progress: _Progress = None,
) -> tuple[_U64Array, _U64Array | None, int, bool]:
    """Exact sums of samples ``[s0, s1)``: ``(sum, sum_sq or None, samples_done, interrupted)``,
    sums as ``(H, W, 3, 3)`` uint64 fixed-point limbs."""

def film_merge(dst: _U64Array, src: _U64Array) -> None:
    """``dst += src`` for exact sums, in place."""

def film_finish(
    sum: _U64Array, sum_sq: _U64Array | None, samples: int, spp_requested: int
) -> tuple[_F32Array, _F32Array | None]:
    """The image (and variance of the mean, if ``sum_sq``) of exact sums."""

# --- ensemble -------------------------------------------------------------------

def ensemble_scene(
    scene: str,
    realizations: int,
    resolution: int | None = None,
    spp: int | None = None,
    seed: int = 0,
    threads: int | None = None,
    defines: Sequence[tuple[str, str]] | None = None,
    progress: _Progress = None,
    padding: float | None = None,
    marginal: str | None = None,
    keep_realizations: bool = False,
    first: int = 0,
) -> tuple[_F32Array, _F32Array, dict[str, Any], bool]:
    """Ensemble of explicit realizations: ``(mean, stderr, info, interrupted)``, images ``(H, W, 3)`` float32."""

# --- truth (constant-alpha media) -----------------------------------------------

def truth_plan(
    scene: str,
    nodes: int | None = None,
    defines: Sequence[tuple[str, str]] | None = None,
) -> dict[str, Any]:
    """The truth quadrature: ``alpha``, ``x``, ``weights``, ``tau_max``, ``auto_nodes``,
    ``closed_form_error``, ``media``, ``width``, ``height``, ``spp``."""

def render_truth_node(
    scene: str,
    node: int,
    nodes: int | None = None,
    spp: int | None = None,
    seed: int = 0,
    threads: int | None = None,
    defines: Sequence[tuple[str, str]] | None = None,
    progress: _Progress = None,
    return_variance: bool = False,
) -> tuple[_F32Array | None, _F32Array | None, bool]:
    """One node's classical render: ``(image or None, variance or None, interrupted)``."""

@final
class TruthBar:
    """An indicatif bar on stderr that several calls advance."""

    def __new__(cls, total: int, label: str = "truth") -> TruthBar: ...
    def update(self, n: int) -> None: ...
    def set_message(self, msg: str) -> None: ...
    def close(self) -> None: ...

# --- io: OpenVDB ---
def write_vdb(
    path: str, data: npt.NDArray[np.float32], voxel_size: tuple[float, float, float],
    origin: tuple[float, float, float], name: str,
) -> None: ...
def read_vdb(
    path: str, grid: str,
) -> tuple[npt.NDArray[np.float32], tuple[int, int, int], list[list[float]], float]: ...
