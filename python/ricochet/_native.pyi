"""Type stubs of the extension module ``ricochet._native`` (python/src/*.rs)."""

from os import PathLike
from typing import Any, Callable, Optional, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, PathLike[str]]

__version__: str

class SceneError(ValueError):
    """A scene that cannot be read, parsed or validated (the command line's exit 2)."""

    file: Optional[str]
    key: Optional[str]
    value: Optional[str]
    reason: Optional[str]

class RicochetError(RuntimeError):
    """A run or study that could not be made."""

class SceneCore:
    @staticmethod
    def load(path: _Path) -> SceneCore: ...
    @staticmethod
    def from_text(text: str, path: _Path) -> SceneCore: ...
    @staticmethod
    def from_table(table: dict[str, Any], path: _Path) -> SceneCore: ...
    def set(self, key: str, value: Any) -> SceneCore: ...
    def to_toml(self) -> str: ...
    def to_dict(self) -> dict[str, Any]: ...
    @property
    def name(self) -> str: ...
    @property
    def file(self) -> str: ...
    @property
    def overrides(self) -> list[tuple[str, Any]]: ...
    def check(self) -> dict[str, Any]: ...
    def mesh(
        self,
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.uint32], npt.NDArray[np.uint32]]: ...
    def run(
        self,
        backend: str,
        out: Optional[_Path],
        adapter: Optional[str],
        progress: Optional[Callable[[float, float, int], Any]],
    ) -> tuple[str, str, str, list[str], Optional[BaseException]]: ...

def restart(
    out: _Path,
    adapter: Optional[str] = None,
    progress: Optional[Callable[[float, float, int], Any]] = None,
) -> tuple[str, str, str, list[str], Optional[BaseException]]: ...
def study_prepare(text: str, path: _Path, root: _Path) -> tuple[str, str, list[str]]: ...
def case_action(root: _Path, id: str) -> str: ...
def case_finished(root: _Path, id: str) -> str: ...
def collect(root: _Path) -> str: ...
