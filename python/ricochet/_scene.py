"""``ricochet.Scene``: a scene file (or TOML text, or a dict) validated by the library, with keys
overridden by the key paths of studies, checked into its plan, and run in-process."""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Any, Callable, Mapping, Optional, Union

import numpy as np
import numpy.typing as npt

from . import _native
from ._progress import ProgressLine
from ._result import Result

PathLike = Union[str, "os.PathLike[str]"]
ProgressArg = Union[bool, Callable[[float, float, int], Any], None]

BACKENDS = ("auto", "cpu", "gpu")


class Scene:
    """A validated scene.

    Build one with :meth:`load`, :meth:`from_toml` or :meth:`from_dict`; every check of the
    command line applies (``ricochet check``), and a refused scene raises
    :class:`ricochet.SceneError` with the command line's message.
    """

    def __init__(self, core: _native.SceneCore) -> None:
        self._core = core

    # -- construction -------------------------------------------------------------------

    @classmethod
    def load(cls, path: PathLike) -> "Scene":
        """Reads and validates the scene file ``path``.

        Raises:
            SceneError: the file cannot be read, is not TOML of the scene format, or a value is
                refused (``file``, ``key``, ``value`` say which).
        """
        return cls(_native.SceneCore.load(os.fspath(path)))

    @classmethod
    def from_toml(cls, text: str, name: str = "scene", folder: Optional[PathLike] = None) -> "Scene":
        """Validates scene text.

        Args:
            text: the scene in the scene format (README, "Scene format").
            name: the scene's name (the stem of the file it is read as: ``<name>.toml``), which
                names the default output folder ``out/<name>``.
            folder: the folder it is read from (relative Gmsh mesh paths start there); the
                working folder by default.
        """
        return cls(_native.SceneCore.from_text(text, _virtual(name, folder)))

    @classmethod
    def from_dict(cls, tables: Mapping[str, Any], name: str = "scene", folder: Optional[PathLike] = None) -> "Scene":
        """Validates a scene given as a dict of its tables (``{"run": {...}, "material": [...],
        "body": [...]}``, as ``tomllib`` reads a scene file); as :meth:`from_toml` otherwise."""
        return cls(_native.SceneCore.from_table(dict(tables), _virtual(name, folder)))

    # -- overrides ----------------------------------------------------------------------

    def set(self, key: str, value: Any) -> "Scene":
        """Sets the key at the path ``key`` to ``value`` and validates the scene again.

        The paths are those of studies: ``body[striker].initial_velocity[1]``,
        ``material[steel].yield_stress``, ``run.end_time``, ``contact[0].friction``. Returns the
        scene itself, so that calls chain.

        Raises:
            SceneError: the key does not exist or the value is refused (the scene is left as it
                was).
        """
        self._core = self._core.set(key, value)
        return self

    @property
    def overrides(self) -> list[tuple[str, Any]]:
        """The keys set with :meth:`set`, in order, with their values."""
        return self._core.overrides

    @property
    def name(self) -> str:
        """The scene's name (its file's stem)."""
        return self._core.name

    @property
    def file(self) -> Path:
        """The file the scene is read as (for a scene built in Python, ``<folder>/<name>.toml``,
        which need not exist)."""
        return Path(self._core.file)

    def to_toml(self) -> str:
        """The scene as TOML with its overrides applied (comments dropped, Gmsh paths absolute);
        the text itself when nothing is overridden."""
        return self._core.to_toml()

    def to_dict(self) -> dict[str, Any]:
        """The scene's tables as a dict, overrides applied."""
        return self._core.to_dict()

    def save(self, path: PathLike) -> Path:
        """Writes :meth:`to_toml` to ``path`` (a scene file ``ricochet run`` reads)."""
        p = Path(path)
        p.write_text(self.to_toml(), encoding="utf-8")
        return p

    # -- plan and mesh ------------------------------------------------------------------

    def check(self) -> dict[str, Any]:
        """The plan that ``ricochet check`` prints, as a dict: nodes, elements, bodies (mass,
        wave speed, hourglass form), the stable and chosen time step and the number of steps,
        contact (tables, walls, margin, methods), friction, the overlaps at t = 0, pressures,
        gravity and mass damping, the memory estimate, history rows and snapshots, and the
        stages (``plan``). The Gmsh groups and load curves that ``check`` prints are left out.

        Raises:
            SceneError: the model cannot be built, or a fixed ``run.time_step`` exceeds the
                stable step (the command line's exit 2).
        """
        return self._core.check()

    def mesh(self) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.uint32], npt.NDArray[np.uint32]]:
        """The model's mesh at t = 0, as a run starts (overlaps resolved): node positions
        ``(n, 2)``, quads ``(m, 4)`` (a triangle repeats its last node) and each element's body
        index ``(m,)``. The arrays take over the buffers the library built: no copy is made."""
        return self._core.mesh()

    # -- run ----------------------------------------------------------------------------

    def run(
        self,
        backend: str = "auto",
        out: Optional[PathLike] = None,
        progress: ProgressArg = True,
        adapter: Optional[str] = None,
    ) -> Result:
        """Runs the scene in this process, as ``ricochet run`` does, and returns its outputs.

        The GIL is released while the solver steps. Between batches of steps the run reads
        Ctrl-C (Python's SIGINT handler, on the main thread): it then stops after the batch
        under way, with complete outputs and ``summary["status"] == "interrupted"``
        (``interrupted by SIGINT at step ...``), as the command line's run does, and the
        :class:`Result` is returned (a message on stderr says so).

        Args:
            backend: ``"auto"`` (the GPU when a hardware adapter exists, else the CPU
                reference, with a notice), ``"cpu"`` (the f64 CPU reference) or ``"gpu"``.
            out: the output folder; ``out/<scene name>`` by default.
            progress: ``True`` for a progress line on stderr, ``False``/``None`` for none, or a
                callable ``(t, end_time, steps)`` called after each batch (an exception it
                raises stops the run, then is raised again once the outputs are written).
            adapter: the GPU adapter, by a substring of its name, its index or PCI bus id (as
                ``--adapter``).

        Raises:
            SceneError: the model or the run's limits refuse the scene.
            RicochetError: the GPU cannot be used, the output folder is in use, an output
                cannot be written.
        """
        if backend not in BACKENDS:
            raise ValueError(f'backend must be "auto", "cpu" or "gpu", not {backend!r}')
        line, callback = _progress(progress, self.name)
        try:
            outcome = self._core.run(backend, None if out is None else os.fspath(out), adapter, callback)
        finally:
            if line is not None:
                line.close()
        return _finish(outcome)

    def __repr__(self) -> str:
        return repr(self._core)


def restart(out: PathLike, progress: ProgressArg = True, adapter: Optional[str] = None) -> Result:
    """Continues the run whose output folder ``out`` holds a checkpoint (``checkpoint.bin``), as
    ``ricochet run --restart OUT`` does: on the checkpoint's backend, with its scene, into the
    same folder; the outputs end as those of the run that was never stopped.

    Raises:
        SceneError: the checkpoint cannot be continued.
    """
    name = Path(out).name
    line, callback = _progress(progress, name)
    try:
        outcome = _native.restart(os.fspath(out), adapter, callback)
    finally:
        if line is not None:
            line.close()
    return _finish(outcome)


def _virtual(name: str, folder: Optional[PathLike]) -> str:
    """The path a scene built in Python is read as: ``<folder>/<name>.toml``."""
    base = Path(folder) if folder is not None else Path.cwd()
    return os.fspath(base / f"{name}.toml")


def _progress(progress: ProgressArg, name: str) -> tuple[Optional[ProgressLine], Optional[Callable[[float, float, int], Any]]]:
    if progress is True:
        line = ProgressLine(name)
        return line, line
    if progress is False or progress is None:
        return None, None
    if callable(progress):
        return None, progress
    raise TypeError("progress must be True, False, None or a callable (t, end_time, steps)")


def _finish(outcome: tuple[str, str, str, list[str], Optional[BaseException]]) -> Result:
    status, message, out, notices, error = outcome
    for n in notices:
        print(f"notice: {n}", file=sys.stderr)
    if error is not None:
        raise error
    if status == "interrupted":
        print(f"{message}; history, fields and summary.json are complete up to there", file=sys.stderr)
    elif status == "failed":
        print(f"error: {message}", file=sys.stderr)
    return Result(out)
