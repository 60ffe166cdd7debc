"""Type stubs of the `inimtrace` package (the extension module `inimtrace._inimtrace` and the
pure-Python part). Lengths are millimetres; images are (rows, columns, 3) float32 arrays."""

from dataclasses import dataclass
from os import PathLike
from typing import Any, Callable, Dict, List, Literal, Mapping, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

_Path = Union[str, PathLike[str]]
_Set = Union[Mapping[str, Any], Sequence[str], None]
_Image = npt.NDArray[np.float32]
_Progress = Optional[Callable[[str, int, int], Any]]

__version__: str
git_revision: str
has_embree: bool

class Error(Exception):
    """Base class of inimtrace's errors; `str(e)` is the CLI's message."""

    source: Optional[str]
    field: Optional[str]

class ConfigError(Error): ...
class MeshError(Error): ...
class ImageError(Error): ...
class OpticsError(Error): ...
class OutOfMemoryError(Error, MemoryError): ...

class Display:
    @staticmethod
    def load(path: _Path, set: _Set = None) -> Display: ...
    @staticmethod
    def paper(set: _Set = None) -> Display: ...
    @property
    def name(self) -> str: ...
    @property
    def eye_to_lenslets_mm(self) -> float: ...
    @property
    def lenslets_to_lcd_mm(self) -> float: ...
    @property
    def focal_length_mm(self) -> float: ...
    @property
    def lenslet_pitch_matrix_mm(self) -> List[float]: ...
    @property
    def lenslet_shift_mm(self) -> List[float]: ...
    @property
    def elemental_image_pitch_matrix_mm(self) -> List[float]: ...
    @property
    def elemental_image_shift_mm(self) -> List[float]: ...
    @property
    def lcd_size_mm(self) -> List[float]: ...
    @property
    def lcd_resolution(self) -> List[int]: ...
    @property
    def image_shape(self) -> Tuple[int, int, int]: ...
    @property
    def central_depth_plane_mm(self) -> Optional[float]: ...
    def to_dict(self) -> Dict[str, Any]: ...
    def design(self, pupil: float = 5.0) -> Dict[str, Any]: ...

class Eye:
    def __init__(
        self,
        *,
        pinhole: bool = False,
        focus_mm: Optional[float] = None,
        focus_diopters: Optional[float] = None,
        pupil: float = 5.0,
        pupil_grid: int = 8,
        retina: int = 512,
        half_tangent: float = 0.3,
        retina_samples: int = 1,
        retina_distance: float = 17.0,
        position: Tuple[float, float, float] = (0.0, 0.0, 0.0),
        model: Optional[str] = None,
        spectrum: Optional[str] = None,
        stiles_crawford_rho: Optional[float] = None,
        gaze: Tuple[float, float] = (0.0, 0.0),
        centre_of_rotation: Optional[float] = None,
    ) -> None: ...
    @property
    def pinhole(self) -> bool: ...
    @property
    def focus_mm(self) -> Optional[float]: ...
    @property
    def focus_diopters(self) -> Optional[float]: ...
    @property
    def pupil(self) -> Optional[float]: ...
    @property
    def pupil_grid(self) -> int: ...
    @property
    def pupil_samples(self) -> int: ...
    @property
    def retina(self) -> int: ...
    @property
    def half_tangent(self) -> float: ...
    @property
    def retina_samples(self) -> int: ...
    @property
    def retina_distance(self) -> float: ...
    @property
    def position(self) -> Tuple[float, float, float]: ...
    @property
    def gaze(self) -> Tuple[float, float]: ...
    @property
    def centre_of_rotation(self) -> float: ...
    @property
    def pupil_centre(self) -> Tuple[float, float, float]: ...
    @property
    def model(self) -> str: ...

class Scene:
    @staticmethod
    def load(path: _Path, set: _Set = None) -> Scene: ...
    @staticmethod
    def paper(set: _Set = None) -> Scene: ...
    @property
    def name(self) -> str: ...
    @property
    def warnings(self) -> List[str]: ...
    @property
    def object_count(self) -> int: ...
    @property
    def triangle_count(self) -> int: ...
    def summary(self) -> Dict[str, Any]: ...

class Experiment:
    @staticmethod
    def load(path: _Path, set: _Set = None, scene: Optional[_Path] = None) -> Experiment: ...
    @staticmethod
    def paper(set: _Set = None, scene: Optional[_Path] = None) -> Experiment: ...
    @staticmethod
    def paper_grid(set: _Set = None) -> Experiment: ...
    @property
    def name(self) -> str: ...
    @property
    def scene(self) -> Scene: ...
    @property
    def display(self) -> Display: ...
    @property
    def methods(self) -> List[str]: ...  # "LC", "PC", "LA", "LA<k>" or "OPT" (its [optimize] table: settings()["optimize"])
    @property
    def eye_cases(self) -> List[Tuple[str, Eye]]: ...
    @property
    def estimator(self) -> Literal["converged", "grid"]: ...
    def settings(self) -> Dict[str, Any]: ...
    def to_toml(self) -> str: ...

@overload
def render_display(
    scene: Scene,
    display: Display,
    method: str = "LA",  # "LC", "PC", "LA", "LA<k>" or "OPT" (trained on the paper's four eye states)
    backend: str = "auto",
    *,
    samples_per_pixel: int = 1,
    reference_plane: float = 0.0,
    eye_position: Tuple[float, float, float] = (0.0, 0.0, 0.0),
    depth: Literal[False] = False,
    threads: Optional[int] = None,
    progress: _Progress = None,
) -> _Image: ...
@overload
def render_display(
    scene: Scene,
    display: Display,
    method: str = "LA",  # "LC", "PC", "LA", "LA<k>" or "OPT"
    backend: str = "auto",
    *,
    samples_per_pixel: int = 1,
    reference_plane: float = 0.0,
    eye_position: Tuple[float, float, float] = (0.0, 0.0, 0.0),
    depth: Literal[True],
    threads: Optional[int] = None,
    progress: _Progress = None,
) -> Tuple[_Image, Optional[npt.NDArray[np.float32]]]: ...
def simulate(
    display_image: _Image, display: Display, eye: Eye, *, threads: Optional[int] = None, progress: _Progress = None
) -> _Image: ...
def ground_truth(
    scene: Scene,
    eye: Eye,
    backend: str = "auto",
    *,
    display: Optional[Display] = None,
    threads: Optional[int] = None,
    progress: _Progress = None,
) -> _Image: ...
def compare(
    a: _Image,
    b: _Image,
    ssim: str = "wang2004",
    *,
    scores: Optional[List[str]] = None,
    peak_white: float = 100.0,
    black: float = 0.1,
    ppd: Optional[float] = None,
) -> Dict[str, Any]: ...
def read_replicates(path: _Path) -> npt.NDArray[np.float32]: ...
def read_exr(path: _Path) -> Tuple[_Image, Optional[npt.NDArray[np.float32]]]: ...
@dataclass
class Assessment:
    scores: List[Dict[str, Any]]
    images: Dict[str, _Image]
    depths: Dict[str, Optional[npt.NDArray[np.float32]]]
    stages: List[Dict[str, Any]]
    report: Dict[str, Any]
    out: Optional[str] = None
    optimization: Optional[Dict[str, Any]] = None  # OPT's convergence record (results.json's "optimization")
    provenance: Dict[str, Any] = ...
    def score(self, method: str, eye_case: str) -> Dict[str, Any]: ...

def assess(
    experiment: Experiment,
    out: Optional[_Path] = None,
    backend: str = "auto",
    *,
    exr_compression: str = "zip",
    threads: Optional[int] = None,
    progress: _Progress = None,
) -> Assessment: ...

@dataclass
class Resolution:
    out: str
    mtf: List[Dict[str, Any]]
    mtf50: List[Dict[str, Any]]
    accommodation: List[Dict[str, Any]]
    display: Dict[str, Any]
    timings: List[Dict[str, Any]] = ...

def resolution(
    study: Optional[_Path] = None,
    out: Optional[_Path] = None,
    set: _Set = None,
    *,
    threads: Optional[int] = None,
    progress: _Progress = None,
) -> Resolution: ...
