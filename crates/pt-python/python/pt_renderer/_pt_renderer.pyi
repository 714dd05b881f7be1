# Type stub of the compiled module (crates/pt-python/src/lib.rs). The public API is
# pt_renderer/__init__.py, which wraps these with argument checks and numpy conversions;
# tests/test_converge_and_api.py checks that this stub lists every name and parameter.

from typing import Any, Callable, List, Optional, Sequence, Tuple

import numpy as np
import numpy.typing as npt

VERSION: str
METHODS: List[str]
BUILTIN_CORNELL: str

class SceneError(ValueError): ...

class Scene:
    @property
    def source(self) -> str: ...
    def info(self) -> dict[str, Any]: ...

class BsdfCore:
    @property
    def mode(self) -> str: ...
    def eval(
        self, wo: npt.NDArray[np.float64], wi: npt.NDArray[np.float64], wavelengths: Optional[npt.NDArray[np.float64]] = None
    ) -> npt.NDArray[np.float32]: ...
    def pdf(
        self, wo: npt.NDArray[np.float64], wi: npt.NDArray[np.float64], wavelengths: Optional[npt.NDArray[np.float64]] = None
    ) -> npt.NDArray[np.float32]: ...
    def sample(
        self, wo: npt.NDArray[np.float64], u: npt.NDArray[np.float64], wavelengths: Optional[npt.NDArray[np.float64]] = None
    ) -> Tuple[
        npt.NDArray[np.float32], npt.NDArray[np.float32], npt.NDArray[np.float32], npt.NDArray[np.bool_], npt.NDArray[np.bool_]
    ]: ...

def load_file(path: Optional[str], defines: List[Tuple[str, str]], camera: Optional[int] = None) -> Scene: ...
def load_string(xml: str, base_dir: str, defines: List[Tuple[str, str]]) -> Scene: ...
def render(
    scene: Scene,
    spp: Optional[int] = None,
    seed: Optional[int] = None,
    integrator: Optional[str] = None,
    threads: Optional[int] = None,
    mode: Optional[str] = None,
    max_depth: Optional[int] = None,
    progress: Optional[Callable[[int, int, str], Any]] = None,
) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.float32], List[str], int, float, List[str]]: ...
def read_exr(path: str) -> npt.NDArray[np.float32]: ...
def read_exr_channels(path: str) -> List[Tuple[str, npt.NDArray[np.float32]]]: ...
def write_exr(path: str, width: int, height: int, channels: Sequence[Tuple[str, npt.NDArray[np.float32]]]) -> None: ...
def compare(
    width: int,
    height: int,
    image: npt.NDArray[np.float32],
    reference: npt.NDArray[np.float32],
    variances: Optional[Tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]],
    block: int,
    alpha: float,
    flip_exposure: float,
) -> dict[str, Any]: ...
def bsdf(model: str, params: List[Tuple[str, Any]], two_sided: bool, mode: str) -> BsdfCore: ...
def bsdf_models() -> List[Tuple[str, List[str]]]: ...
def converge(
    scene: str,
    reference: str,
    spp: List[int],
    strategies: List[str],
    integrators: List[str],
    modes: List[str],
    out: str,
    threads: Optional[int],
    max_depth: Optional[int],
    seed: int,
    defines: List[Tuple[str, str]],
    mitsuba_python: Optional[str],
    log: Optional[Callable[[str], Any]],
) -> Tuple[List[Tuple[str, List[Tuple[int, float, float, float, float]]]], str]: ...
