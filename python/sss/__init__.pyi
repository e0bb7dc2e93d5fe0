# Typing stub of the sss package (docs/python.md). tests/python/test_stub.py
# checks that it names what the module has, no more and no less, with the
# same parameters; python.stubtest runs mypy's stubtest on it.

import builtins
import os
from typing import Any, Callable, Dict, Iterable, List, Literal, Mapping, Optional
from typing import Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str
__all__ = [
    "BrickMap",
    "Cloud",
    "Error",
    "FormatError",
    "IoError",
    "LimitError",
    "OutOfMemoryError",
    "PointCloudLookup",
    "UsageError",
    "__version__",
    "expand_frame_pattern",
    "has_frame_pattern",
    "isa_names",
    "make_brickmap",
    "ptfilter",
    "read_cloud",
    "ssdiffusion",
    "write_cloud",
]

_Path = Union[str, bytes, os.PathLike[str], os.PathLike[bytes]]
_Floats = npt.NDArray[np.float32]
_ArrayLike = npt.ArrayLike
_Progress = Optional[Callable[[int, int], Any]]
_Channels = Union[None, str, Sequence[str]]
_Report = Dict[str, Any]

# help() lists only what a class defines (sss/_errors.py).
class _Brief(type): ...

class Error(Exception, metaclass=_Brief): ...
class UsageError(Error, builtins.ValueError): ...
class ValueError(Error, builtins.ValueError): ...
class LimitError(Error, builtins.ValueError): ...
class OutOfMemoryError(Error, builtins.MemoryError): ...

class FormatError(Error, builtins.ValueError):
    path: Optional[str]
    point: Optional[int]
    def __init__(self, message: str, path: Optional[str] = ...,
                 point: Optional[int] = ...) -> None: ...

class IoError(Error, builtins.OSError):
    def __init__(self, message: str, path: Optional[str] = ..., errno: int = ...) -> None: ...
    @property
    def path(self) -> Optional[str]: ...

class FileNotFoundError(IoError, builtins.FileNotFoundError): ...

class Cloud(Dict[str, _Floats]):
    types: Dict[str, str]
    world_to_eye: _Floats
    world_to_ndc: _Floats
    format: Tuple[float, float, float]
    file_version: int
    compressed: bool
    report: _Report
    def __init__(self, arrays: Union[Mapping[str, _ArrayLike],
                                     Iterable[Tuple[str, _ArrayLike]]] = ...,
                 types: Optional[Mapping[str, str]] = ...,
                 world_to_eye: Optional[_ArrayLike] = ...,
                 world_to_ndc: Optional[_ArrayLike] = ...,
                 format: Optional[Sequence[float]] = ...) -> None: ...
    @property
    def channels(self) -> List[str]: ...
    @property
    def size(self) -> int: ...

_CloudLike = Mapping[str, _ArrayLike]

def read_cloud(path: _Path) -> Cloud: ...
def write_cloud(path: _Path, cloud: _CloudLike, *, types: Optional[Mapping[str, str]] = ...,
                ptcversion: int = ..., compress: bool = ...) -> None: ...
def ssdiffusion(source: Union[_CloudLike, _Path, Sequence[_Path]], *,
                progress: _Progress = ..., **options: Any) -> Cloud: ...
def ptfilter(inputs: Union[_Path, Sequence[_Path]], output: _Path, *,
             progress: _Progress = ..., **options: Any) -> _Report: ...
def make_brickmap(source: Union[_Path, Sequence[_Path], _CloudLike, Sequence[_CloudLike]],
                  output: _Path, *, progress: _Progress = ...,
                  **options: Any) -> _Report: ...
def isa_names() -> List[str]: ...
def has_frame_pattern(path: _Path) -> bool: ...
def expand_frame_pattern(path: _Path, frame: Optional[int] = ...,
                         what: str = ...) -> str: ...

class BrickMap:
    path: str
    def __init__(self, path: _Path, cache_bytes: int = ...) -> None: ...
    @property
    def info(self) -> Dict[str, Any]: ...
    @property
    def channels(self) -> List[Tuple[str, str]]: ...
    @property
    def bricks_loaded(self) -> int: ...
    @overload
    def lookup(self, points: _ArrayLike, channel: _Channels = ..., *,
               normals: Optional[_ArrayLike] = ..., filterradius: Union[float, _ArrayLike] = ...,
               threads: int = ..., return_found: Literal[False] = ...) -> _Floats: ...
    @overload
    def lookup(self, points: _ArrayLike, channel: _Channels = ..., *,
               normals: Optional[_ArrayLike] = ..., filterradius: Union[float, _ArrayLike] = ...,
               threads: int = ..., return_found: Literal[True]
               ) -> Tuple[_Floats, Union[npt.NDArray[np.bool_], bool]]: ...
    def verify(self) -> int: ...

class PointCloudLookup:
    path: Optional[str]
    def __init__(self, source: Union[_Path, _CloudLike]) -> None: ...
    @property
    def channels(self) -> List[Tuple[str, str]]: ...
    @property
    def size(self) -> int: ...
    @overload
    def lookup(self, points: _ArrayLike, channel: _Channels = ..., *,
               normals: Optional[_ArrayLike] = ..., filterradius: Union[float, _ArrayLike] = ...,
               threads: int = ..., return_found: Literal[False] = ...) -> _Floats: ...
    @overload
    def lookup(self, points: _ArrayLike, channel: _Channels = ..., *,
               normals: Optional[_ArrayLike] = ..., filterradius: Union[float, _ArrayLike] = ...,
               threads: int = ..., return_found: Literal[True]
               ) -> Tuple[_Floats, Union[npt.NDArray[np.bool_], bool]]: ...
