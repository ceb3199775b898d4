"""Type stubs for the private native module ``fgf._core``.

Each area owns one section below; edit only your own section.
"""

__version__: str

class FgfError(ValueError): ...
class ParameterError(FgfError): ...
class SceneError(FgfError): ...

# --- transmittance (issue 2) ---
import numpy as _np
import numpy.typing as _npt

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
    def eval(self, what: str, x: _npt.NDArray[_np.float64]) -> _npt.NDArray[_np.float64]: ...
    @property
    def sigma_bar(self) -> float: ...
    def params(self) -> dict[str, object]: ...
    def to_davis(self) -> _Model: ...
    def to_davis_weinstein(self) -> _Model: ...

def c_const(hurst: float, d: int = 1) -> float: ...
def s_p(hurst: float, sw: float) -> float: ...
def s_kf(hurst: float, sw: float) -> float: ...
def binom(a: float, k: int) -> float: ...
def kfbm_point_variance(
    hurst: float, sw: float, x: _npt.NDArray[_np.float64]
) -> _npt.NDArray[_np.float64]: ...
def line_average_variance(
    hurst: float, sw: float, t: _npt.NDArray[_np.float64], length: float | None = None
) -> _npt.NDArray[_np.float64]: ...

# --- field (issue 3) ---
import numpy as np  # noqa: E402

def synthesize(
    shape: list[int],
    hurst: float,
    sw: float,
    spacing: float,
    seed: int,
    anchor: object,
    padding: float | None,
    dtype: str,
    progress: object,
) -> np.ndarray: ...
def synthesis_info(
    shape: list[int], hurst: float, sw: float, spacing: float, padding: float | None, dtype: str
) -> tuple[float, list[int], int | None]: ...
def sample_optical_depth(
    n_rays: int, n_steps: int, t_max: float, hurst: float, sw: float, seed: int, progress: object
) -> tuple[np.ndarray, np.ndarray]: ...
def sample_kfbm_1d(
    n_samples: int, n_steps: int, length: float, hurst: float, sw: float, seed: int, progress: object
) -> tuple[np.ndarray, np.ndarray]: ...
def sw_3d_for_ray_statistics(hurst: float, sw: float) -> float: ...
def variogram(field: np.ndarray, axis: int, max_lag: int) -> list[float]: ...
def covariance(field: np.ndarray, axis: int, max_lag: int) -> list[float]: ...
def radial_power_spectrum(field: np.ndarray, spacing: float, n_bins: int) -> tuple[list[float], list[float], list[int]]: ...
def line_average_second_moment(field: np.ndarray, axis: int, lengths: list[int]) -> list[float]: ...
def write_field(
    path: str,
    field: np.ndarray,
    spacing: float,
    mean: float,
    scale: float,
    clamp_min: float | None,
    png_percentiles: tuple[float, float],
) -> dict[str, object]: ...
# --- render (issue 4/5) ---
import numpy as np  # noqa: E402

def render_scene(
    scene: str,
    spp: int | None = None,
    seed: int | None = None,
    threads: int | None = None,
    defines: list[tuple[str, str]] | None = None,
    progress: object = None,
    return_variance: bool = False,
) -> tuple[np.ndarray, np.ndarray | None, int, bool]:
    """Render a scene file: ``(image (H, W, 3) float32, variance or None, spp_done, interrupted)``."""

def write_exr(path: str, img: np.ndarray) -> None:
    """Write an ``(H, W, 3)`` float32 image as a linear float32 EXR (atomically)."""

def write_png(path: str, img: np.ndarray, exposure: float = 0.0) -> None:
    """Write an ``(H, W, 3)`` float32 linear image as an sRGB PNG preview (atomically)."""

# --- ensemble (issue 5) ---
def ensemble_scene(
    scene: str,
    realizations: int,
    resolution: int | None = None,
    spp: int | None = None,
    seed: int = 0,
    threads: int | None = None,
    defines: list[tuple[str, str]] | None = None,
    progress: object = None,
) -> tuple[np.ndarray, np.ndarray, dict[str, object], bool]:
    """Ensemble of explicit realizations: ``(mean, stderr, info, interrupted)``, images ``(H, W, 3)`` float32."""
