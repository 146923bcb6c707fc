# Type stubs of the package probecomp (python/probecomp/__init__.py and its compiled core). Lengths in the caller's
# unit (`units`, default mm) unless said otherwise; arrays are numpy float64 unless said otherwise.
from dataclasses import dataclass
from os import PathLike
from typing import Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

ArrayLike = npt.ArrayLike
Path = Union[str, PathLike]
Tolerance = Union[str, Tuple[float, float], None]

class Error(RuntimeError): ...
class InputError(Error): ...
class CadError(Error): ...
class RegistrationError(Error): ...
class FitError(Error): ...

class CadModel:
    def __init__(self, path: str) -> None: ...
    @property
    def path(self) -> str: ...
    @property
    def face_count(self) -> int: ...
    @property
    def units(self) -> str: ...  # the unit the file declares; the geometry is in mm
    @property
    def face_names(self) -> list[str]: ...
    @property
    def face_types(self) -> list[str]: ...
    @property
    def face_boxes(self) -> npt.NDArray[np.float64]: ...  # (F, 2, 3): each face's control-net box (min, max), mm
    def surface(self, index: int) -> Surface: ...          # face `index`'s whole surface (untrimmed), mm

class Surface:
    @property
    def degrees(self) -> Tuple[int, int]: ...
    @property
    def control_point_count(self) -> Tuple[int, int]: ...
    @property
    def domain(self) -> Tuple[float, float, float, float]: ...  # u0, u1, v0, v1
    def evaluate(self, u: ArrayLike, v: ArrayLike) -> npt.NDArray[np.float64]: ...  # u's shape + (3,), mm
    def normal(self, u: ArrayLike, v: ArrayLike) -> npt.NDArray[np.float64]: ...    # unit normals, u's shape + (3,)

class CompensationResult:
    points: npt.NDArray[np.float64]       # (N, 3)
    normals: npt.NDArray[np.float64]      # (N, 3)
    deviation: npt.NDArray[np.float64]    # (N,)
    uncertainty: npt.NDArray[np.float64]  # (N,)
    face: npt.NDArray[np.int64]           # (N,)
    radius: npt.NDArray[np.float64]       # (N,)
    status: list[str]
    transform: npt.NDArray[np.float64]    # (4, 4), CAD to machine
    warnings: list[str]
    stats: dict
    def __len__(self) -> int: ...
    def report_html(self, model: CadModel, characteristics: Optional[Union[str, PathLike]] = None) -> str: ...
    def judge(self, model: CadModel, characteristics: Union[str, PathLike]) -> dict: ...

class FitResult(CompensationResult):
    surfaces: list[Surface]
    surface_faces: list[int]

@dataclass
class PointSet:
    points: npt.NDArray[np.float64]
    normals: Optional[npt.NDArray[np.float64]] = ...
    radii: Optional[npt.NDArray[np.float64]] = ...
    units: str = ...
    columns: dict[str, list[str]] = ...
    def __len__(self) -> int: ...

def compensate(model: CadModel, centres: ArrayLike, probe_radius: Union[float, ArrayLike, None] = ...,
               normals: Optional[ArrayLike] = ..., method: str = ..., *, units: str = ...,
               initial_transform: Optional[ArrayLike] = ..., accept_doubtful_registration: bool = ...,
               tolerance: Tolerance = ..., qualification: Optional[Path] = ...,
               styli: Optional[Sequence[str]] = ...,
               characteristics: Optional[Path] = ...) -> CompensationResult: ...
def fit(model: CadModel, centres: ArrayLike, probe_radius: Union[float, ArrayLike, None] = ...,
        normals: Optional[ArrayLike] = ..., *, units: str = ..., initial_transform: Optional[ArrayLike] = ...,
        accept_doubtful_registration: bool = ..., tolerance: Tolerance = ...) -> FitResult: ...
def read_points(path: Path, units: Optional[str] = ...) -> PointSet: ...
def write_points(path: Path, points: ArrayLike, normals: Optional[ArrayLike] = ..., radii: Optional[ArrayLike] = ...,
                 *, units: str = ..., columns: Optional[dict[str, Sequence[object]]] = ...) -> None: ...
