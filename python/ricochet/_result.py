"""``ricochet.Result`` and ``ricochet.read``: a run's output folder (``summary.json``,
``history.csv``, ``fields.pvd`` and its VTU files) as Python objects. The same object comes from a
run just made (``Scene.run``) and from an existing folder (``read``)."""

from __future__ import annotations

import json
import os
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any, Optional, Union

import numpy as np

PathLike = Union[str, "os.PathLike[str]"]


class Result:
    """The outputs of one run, read from its output folder ``out``.

    Attributes are read when first asked for: ``summary`` from ``summary.json``, ``history`` from
    ``history.csv`` (a copy: the file is parsed), ``fields(t)`` from the VTU snapshots (meshio's
    numpy arrays).
    """

    def __init__(self, out: PathLike) -> None:
        self.out = Path(out)
        if not (self.out / "summary.json").is_file():
            raise FileNotFoundError(f"{self.out} holds no summary.json: not the output folder of a ricochet run")
        self._summary: Optional[dict[str, Any]] = None
        self._history: Any = None

    @property
    def summary(self) -> dict[str, Any]:
        """``summary.json`` as a dict (status, message, steps, end time, energy error, ...)."""
        if self._summary is None:
            with open(self.out / "summary.json", encoding="utf-8") as f:
                self._summary = json.load(f)
        return self._summary

    @property
    def status(self) -> str:
        """``completed``, ``failed``, ``interrupted`` (or ``running`` for a run still going or
        killed)."""
        return str(self.summary.get("status"))

    @property
    def history(self) -> Any:
        """``history.csv``: a pandas DataFrame when pandas is installed, else a numpy structured
        array with the same column names (``time``, ``step``, ``kinetic_energy``, ...,
        ``striker.vx``). A comment line (axisymmetric scenes) is skipped."""
        if self._history is None:
            self._history = read_history(self.out / "history.csv")
        return self._history

    @property
    def field_times(self) -> list[float]:
        """The times of the snapshots in ``fields.pvd`` (empty without fields)."""
        return sorted({t for t, _, _ in self._snapshots()})

    def fields(self, time: Optional[float] = None) -> dict[str, Any]:
        """The snapshot nearest to ``time`` (the last when ``None``) as meshio meshes, one per
        body: ``{body name: meshio.Mesh}`` with the point and cell data of the VTU files
        (displacement, velocity, stress, ...).

        Raises:
            ImportError: meshio is not installed (``pip install meshio``).
            LookupError: the run wrote no fields (``run.field_interval`` not set).
        """
        try:
            import meshio
        except ImportError as e:  # pragma: no cover - depends on the machine
            raise ImportError("Result.fields needs meshio: pip install meshio") from e
        snaps = self._snapshots()
        if not snaps:
            raise LookupError(f"{self.out} has no field snapshots (set run.field_interval in the scene)")
        times = sorted({t for t, _, _ in snaps})
        t = times[-1] if time is None else min(times, key=lambda x: abs(x - time))
        return {part: meshio.read(self.out / file) for s, part, file in snaps if s == t}

    def _snapshots(self) -> list[tuple[float, str, str]]:
        pvd = self.out / "fields.pvd"
        if not pvd.is_file():
            return []
        root = ET.parse(pvd).getroot()
        return [
            (float(d.get("timestep", "nan")), d.get("name", ""), d.get("file", ""))
            for d in root.iter("DataSet")
        ]

    def __repr__(self) -> str:
        s = self.summary
        return f"Result({str(self.out)!r}, status={s.get('status')!r}, steps={s.get('steps')}, end_time={s.get('end_time')})"


def read(path: PathLike) -> Result:
    """The outputs of the run whose output folder is ``path`` (as :class:`Result`)."""
    return Result(path)


def read_history(path: PathLike) -> Any:
    """``history.csv`` as a DataFrame (pandas) or a numpy structured array."""
    with open(path, encoding="utf-8") as f:
        lines = [line for line in f if not line.startswith("#")]
    if not lines:
        raise ValueError(f"{path} is empty")
    names = lines[0].strip().split(",")
    try:
        import pandas as pd
    except ImportError:
        dtype = np.dtype([(n, np.int64 if n == "step" else np.float64) for n in names])
        rows = [tuple(_cell(c, dtype[i]) for i, c in enumerate(line.strip().split(","))) for line in lines[1:]]
        return np.array(rows, dtype=dtype)
    import io

    return pd.read_csv(io.StringIO("".join(lines)))


def _cell(text: str, dtype: np.dtype) -> Union[int, float]:
    return int(text) if dtype.kind == "i" else float(text)
