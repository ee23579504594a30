"""``ricochet.study``: many runs of one scene from Python. The study's cases are made, written and
checked by the study library code that ``ricochet study`` uses (``DIR/cases/<id>/scene.toml``
and ``manifest.json``, ``DIR/study.json``), each case runs in-process on a worker of any
``concurrent.futures.Executor``, and the table is collected by the code of ``ricochet collect``
(``DIR/results.csv`` and ``results.json``): the same figures as the command line for the same
study."""

from __future__ import annotations

import io
import multiprocessing
import os
import shutil
import sys
from concurrent.futures import Executor, ProcessPoolExecutor
from pathlib import Path
from typing import Any, Iterable, Mapping, Optional, Sequence, Union

from . import _native

PathLike = Union[str, "os.PathLike[str]"]

# Exit statuses a case's runner records in its `exit` file, as `ricochet run` ends.
_EXIT = {"completed": 0, "failed": 3, "interrupted": 130}


def study(
    base: Any,
    parameters: Union[Mapping[str, Any], Sequence[Mapping[str, Any]], None] = None,
    collect: Union[Mapping[str, Mapping[str, Any]], Sequence[Mapping[str, Any]]] = (),
    executor: Optional[Executor] = None,
    *,
    kind: str = "grid",
    name: Optional[str] = None,
    out: Optional[PathLike] = None,
    backend: Optional[str] = None,
    samples: Optional[int] = None,
    seed: Optional[int] = None,
    checkpoint_interval: Optional[float] = None,
    progress: bool = True,
) -> Any:
    """Runs a study and returns its table, one row per case.

    Args:
        base: a study file (``[study]`` table; then ``parameters`` and ``collect`` are left out),
            a scene file, or a :class:`ricochet.Scene` (its overrides apply to every case).
        parameters: the scene keys to vary. A mapping ``{key path: values}`` (a list of
            values; or a dict of the study format's ``[[parameter]]`` keys: ``name``,
            ``values``, ``range = {from, to, count, log}``, ``min``, ``max``, ``log``), or a list
            of ``[[parameter]]`` dicts (each with its ``key``). A parameter's name (its
            results column) defaults to its key; keys with brackets need a ``name``.
        collect: the figures: a mapping ``{name: {"summary": ...}}`` or ``{name: {"history":
            column, "reduce": "final"|"max"|"min"|"at", "time": t}}``, or a list of
            ``[[collect]]`` dicts (each with its ``name``).
        executor: where the cases run: any ``concurrent.futures.Executor`` whose workers can
            import ricochet (Dask: ``client.get_executor()``); by default a local
            ``ProcessPoolExecutor`` with one spawned worker per CPU core (a script that calls
            ``study`` then needs the ``if __name__ == "__main__":`` guard, as any spawned pool
            does).
        kind: ``"grid"`` (every combination), ``"zip"`` (lists side by side) or ``"lhs"``
            (a seeded Latin hypercube of ``samples`` points over ``min``..``max``). Threshold
            searches run through ``ricochet study``.
        name: the study's name (default: the scene's): the folder is ``out/<name>``.
        out: the study's folder (``DIR``); ``out/<name>`` by default.
        backend: ``"auto"``, ``"cpu"`` or ``"gpu"`` for every case (default: the study's).
        samples, seed: of an ``"lhs"`` study.
        checkpoint_interval: every case's checkpoint interval (default: a tenth of its end
            time), so that a study stopped part way continues where it stopped when run again.
        progress: a line on stderr as each case ends.

    Returns:
        ``results.csv`` as a pandas DataFrame (``id``, ``status``, the parameters, the figures),
        or a numpy structured array without pandas; its ``attrs["out"]`` (DataFrame) names the
        folder. A rerun into the same folder runs only the cases not yet finished.

    Raises:
        SceneError: the study or a case's scene is refused (naming the key, the value and the
            case, as ``ricochet check STUDY`` does).
    """
    text, path, root = _study_file(base, parameters, collect, kind, name, out, backend, samples, seed, checkpoint_interval)
    study_name, study_backend, ids = _native.study_prepare(text, os.fspath(path), os.fspath(root))
    use_backend = backend or study_backend
    if progress:
        print(f"study {study_name}: {len(ids)} cases ({kind}); folder {root}", file=sys.stderr)
    own = executor is None
    # Spawned, not forked: a process that has opened a GPU device has driver threads that a
    # fork would copy mid-flight.
    pool = executor if executor is not None else ProcessPoolExecutor(max_workers=os.cpu_count() or 1, mp_context=multiprocessing.get_context("spawn"))
    try:
        futures = [pool.submit(run_case, os.fspath(root), i, use_backend) for i in ids]
        done = 0
        for f in futures:
            case_id, status = f.result()
            done += 1
            if progress:
                print(f"study {study_name}: case {case_id} {status} ({done}/{len(ids)})", file=sys.stderr)
    finally:
        if own:
            pool.shutdown()
    csv = _native.collect(os.fspath(root))
    return _table(csv, root)


def run_case(root: str, case_id: str, backend: str, adapter: Optional[str] = None) -> tuple[str, str]:
    """Runs case ``case_id`` of the study folder ``root`` in this process, as a worker of
    ``ricochet study`` does with a child ``ricochet run``: a finished case is skipped, a stopped
    one continues from its checkpoint, any other runs from the start; its messages go to the
    case's ``run.log`` and its exit status to its ``exit`` file. Returns (id, status)."""
    action = _native.case_action(root, case_id)
    if action == "skip":
        return case_id, _native.case_finished(root, case_id)
    folder = Path(root) / "cases" / case_id
    out = folder / "out"
    scene = folder / "scene.toml"
    if action == "fresh":
        shutil.rmtree(out, ignore_errors=True)
    (folder / "exit").unlink(missing_ok=True)
    with open(folder / "run.log", "a", encoding="utf-8") as log:
        if action == "restart":
            log.write(f"$ ricochet run --restart {out} --backend {backend}\n")
        else:
            log.write(f"$ ricochet run {scene} --out {out} --backend {backend}\n")
        log.flush()
        try:
            if action == "restart":
                status, message, _, notices, _ = _native.restart(os.fspath(out), adapter, None)
            else:
                core = _native.SceneCore.load(os.fspath(scene))
                status, message, _, notices, _ = core.run(backend, os.fspath(out), adapter, None)
            for n in notices:
                log.write(f"notice: {n}\n")
            if status != "completed":
                log.write(f"{'error: ' if status == 'failed' else ''}{message}\n")
            code = _EXIT.get(status, 1)
        except _native.SceneError as e:
            log.write(f"error: {e}\n")
            code = 2
        except _native.RicochetError as e:
            log.write(f"error: {e}\n")
            code = 1
    (folder / "exit").write_text(f"{code}\n", encoding="utf-8")
    return case_id, _native.case_finished(root, case_id)


def _study_file(
    base: Any,
    parameters: Any,
    collect: Any,
    kind: str,
    name: Optional[str],
    out: Optional[PathLike],
    backend: Optional[str],
    samples: Optional[int],
    seed: Optional[int],
    checkpoint_interval: Optional[float],
) -> tuple[str, Path, Path]:
    """The study's text, the file it is read as, and its folder."""
    from ._scene import Scene

    if not isinstance(base, Scene) and parameters is None:
        path = Path(base)
        text = path.read_text(encoding="utf-8")
        if name is not None or not collect == ():
            raise TypeError("a study file gives its own name and figures: pass only out, executor, backend")
        root = Path(out) if out is not None else Path("out") / _file_name(text, path)
        return text, path, root
    if parameters is None:
        raise TypeError("parameters are required with a scene (or pass a study file)")
    scene = base if isinstance(base, Scene) else Scene.load(base)
    study_name = name or scene.name
    root = Path(out) if out is not None else Path("out") / study_name
    root.mkdir(parents=True, exist_ok=True)
    if isinstance(base, Scene) and (scene.overrides or not scene.file.is_file()):
        scene_file = root / "base.toml"
        scene_file.write_text(scene.to_toml(), encoding="utf-8")
    else:
        scene_file = scene.file
    header: dict[str, Any] = {"name": study_name, "scene": os.fspath(scene_file.resolve()), "kind": kind}
    for k, v in (("backend", backend), ("samples", samples), ("seed", seed), ("checkpoint_interval", checkpoint_interval)):
        if v is not None:
            header[k] = v
    tables = {
        "study": header,
        "parameter": list(_parameters(parameters)),
        "collect": list(_figures(collect)),
    }
    path = root / "study.toml"
    text = _toml(tables)
    path.write_text(text, encoding="utf-8")
    return text, path, root


def _file_name(text: str, path: Path) -> str:
    """A study file's name: ``[study] name``, else its stem (the library checks it)."""
    try:
        import tomllib  # Python 3.11+
    except ImportError:  # pragma: no cover
        return path.stem
    try:
        return str(tomllib.loads(text).get("study", {}).get("name", path.stem))
    except tomllib.TOMLDecodeError:
        return path.stem


def _parameters(parameters: Any) -> Iterable[dict[str, Any]]:
    if isinstance(parameters, Mapping):
        for key, spec in parameters.items():
            if isinstance(spec, Mapping):
                yield {"key": key, **spec}
            else:
                yield {"key": key, "values": list(spec)}
    else:
        for p in parameters:
            yield dict(p)


def _figures(collect: Any) -> Iterable[dict[str, Any]]:
    if isinstance(collect, Mapping):
        for figure, spec in collect.items():
            yield {"name": figure, **spec}
    else:
        for c in collect:
            yield dict(c)


def _toml(tables: dict[str, Any]) -> str:
    """The study's tables as TOML text: `[study]`, then each `[[parameter]]` and `[[collect]]`."""
    lines: list[str] = ["[study]"]
    lines += [f"{k} = {_value(v)}" for k, v in tables["study"].items()]
    for section in ("parameter", "collect"):
        for t in tables[section]:
            lines += ["", f"[[{section}]]"]
            lines += [f"{k} = {_value(v)}" for k, v in t.items()]
    return "\n".join(lines) + "\n"


def _value(v: Any) -> str:
    """A value as inline TOML."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, Mapping):
        return "{ " + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + " }"
    if hasattr(v, "tolist") and hasattr(v, "dtype"):
        return _value(v.tolist())
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, float):
        return repr(v) if v == v and v not in (float("inf"), float("-inf")) else ("nan" if v != v else ("inf" if v > 0 else "-inf"))
    if isinstance(v, int):
        return str(v)
    raise TypeError(f"{type(v).__name__} cannot be a study value")


def _key(k: str) -> str:
    return k if k.replace("_", "").replace("-", "").isalnum() else _value(k)


def _table(csv: str, root: Path) -> Any:
    try:
        import pandas as pd
    except ImportError:
        import numpy as np

        return np.genfromtxt(io.StringIO(csv), delimiter=",", names=True, dtype=None, encoding="utf-8", deletechars="")
    df = pd.read_csv(io.StringIO(csv), dtype={"id": str}, keep_default_na=False, na_values=[""])
    df.attrs["out"] = os.fspath(root)
    return df
