"""Runs in-process: the CPU reference and the GPU (lavapipe here) give `history.csv` byte for byte
as `ricochet run` does on the same backend; the Result reads the output folder (summary, history,
fields), and `ricochet.read` gives the same object for an existing folder."""

from __future__ import annotations

import filecmp

import numpy as np
import pandas as pd
import pytest

import ricochet
from conftest import ASSETS

RODS = ASSETS / "rods_impact.toml"
BLOCK = ASSETS / "vibrating_block.toml"


def same_bytes(a, b) -> bool:
    return filecmp.cmp(a, b, shallow=False)


@pytest.mark.parametrize("backend", ["cpu", "gpu"])
def test_history_is_byte_identical_to_the_command_line(tmp_path, cli, backend) -> None:
    scene = ricochet.Scene.load(RODS)
    result = scene.run(backend=backend, out=tmp_path / "py", progress=False)
    cli("run", RODS, "--backend", backend, "--out", tmp_path / "cli")
    assert result.status == "completed"
    assert result.summary["backend"] == backend
    assert same_bytes(tmp_path / "py" / "history.csv", tmp_path / "cli" / "history.csv")


def test_an_overridden_scene_runs_as_its_saved_file(tmp_path, cli) -> None:
    scene = ricochet.Scene.load(RODS)
    scene.set("body[striker].initial_velocity[0]", 6.0).set("run.end_time", 2.0e-4)
    result = scene.run(backend="cpu", out=tmp_path / "py", progress=False)
    saved = scene.save(tmp_path / "rods_impact.toml")
    cli("run", saved, "--backend", "cpu", "--out", tmp_path / "cli")
    assert same_bytes(tmp_path / "py" / "history.csv", tmp_path / "cli" / "history.csv")
    assert result.summary["end_time"] == pytest.approx(2.0e-4, rel=0.05)
    # The first row is after the first step, whose plastic impact takes 1/(4n) of the speed.
    assert result.history["striker.vx"].iloc[0] == pytest.approx(6.0, rel=0.01)


def test_result_reads_summary_history_and_fields(tmp_path) -> None:
    calls = []
    result = ricochet.Scene.load(BLOCK).run(
        backend="cpu", out=tmp_path / "block", progress=lambda t, end, steps: calls.append((t, end, steps))
    )
    assert len(calls) > 1
    assert all(a[0] < b[0] and a[2] < b[2] for a, b in zip(calls, calls[1:]))
    assert all(end == 2.0e-4 and t <= end for t, end, _ in calls)
    assert result.out == tmp_path / "block"
    assert result.summary["status"] == "completed"
    h = result.history
    assert isinstance(h, pd.DataFrame)
    assert list(h.columns[:4]) == ["time", "step", "dt", "kinetic_energy"]
    assert len(h) == result.summary["history_rows"]
    times = result.field_times
    assert len(times) == result.summary["snapshots"] == 11
    last = result.fields()
    assert list(last) == ["block"]
    mesh = last["block"]
    assert mesh.points.shape[1] == 3
    assert "displacement" in mesh.point_data
    first = result.fields(0.0)["block"]
    assert np.abs(first.point_data["displacement"]).max() == 0.0
    again = ricochet.read(tmp_path / "block")
    assert again.summary == result.summary
    assert again.history.equals(h)
    assert again.field_times == times


def test_read_refuses_a_folder_without_a_run(tmp_path) -> None:
    with pytest.raises(FileNotFoundError):
        ricochet.read(tmp_path)


def test_bad_backend_and_gpu_limits_raise(tmp_path) -> None:
    scene = ricochet.Scene.load(RODS)
    with pytest.raises(ValueError):
        scene.run(backend="tpu", out=tmp_path / "x", progress=False)


def test_a_callback_exception_stops_the_run_and_is_raised(tmp_path) -> None:
    def stop(t, end, steps):
        raise RuntimeError("enough")

    with pytest.raises(RuntimeError, match="enough"):
        ricochet.Scene.load(RODS).run(backend="cpu", out=tmp_path / "r", progress=stop)
    r = ricochet.read(tmp_path / "r")
    assert r.status == "interrupted"
    assert r.summary["message"].startswith("interrupted by an exception in the progress callback")
