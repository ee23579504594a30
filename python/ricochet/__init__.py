"""ricochet: explicit contact-impact simulation of 2D solids, from Python.

The same library as the ``ricochet`` command line, in-process::

    import ricochet

    scene = ricochet.Scene.load("assets/rods_impact.toml")
    scene.set("body[striker].initial_velocity[0]", 8.0)   # a study's key path
    result = scene.run(backend="cpu", out="out/rods_8")   # GIL released; Ctrl-C stops it
    result.summary["status"], result.history["kinetic_energy"]

- :class:`Scene`: load a scene file, build one from TOML text or a dict, override keys by
  path, check it into its plan, run it.
- :class:`Result` and :func:`read`: a run's outputs (``summary.json``, ``history.csv``, the
  VTU snapshots) as Python objects, for a run just made or an existing output folder.
- :func:`restart`: continue a run from the checkpoint in its output folder.
- :func:`study`: the cases of a study on any ``concurrent.futures.Executor`` (a local process
  pool by default, Dask's ``client.get_executor()`` for a cluster), collected into one table as
  ``ricochet collect`` does.
- :class:`SceneError` (a ``ValueError``): a scene that cannot be read or is refused, with the
  command line's message and its ``file``, ``key`` and ``value``; :class:`RicochetError` (a
  ``RuntimeError``): a run that could not be made.
"""

from ._native import RicochetError, SceneError, __version__
from ._result import Result, read
from ._scene import Scene, restart
from ._study import study

__all__ = [
    "Scene",
    "Result",
    "read",
    "restart",
    "study",
    "SceneError",
    "RicochetError",
    "__version__",
]
