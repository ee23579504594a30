"""Scenes from Python: loaded, from TOML text and from a dict, overridden by key path, checked
into the plan; refusals raise SceneError with the command line's message, file, key and value."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

import ricochet
from conftest import ASSETS

RODS = ASSETS / "rods_impact.toml"


def plan_of(scene: ricochet.Scene) -> dict:
    """The plan without the file it names (a scene built from text is read as ./<name>.toml)."""
    plan = scene.check()
    assert plan.pop("file") == str(scene.file)
    return plan


def test_load_from_toml_and_from_dict_give_the_same_plan() -> None:
    loaded = ricochet.Scene.load(RODS)
    text = RODS.read_text()
    from_text = ricochet.Scene.from_toml(text, name="rods_impact")
    from_dict = ricochet.Scene.from_dict(tomllib.loads(text), name="rods_impact")
    assert loaded.name == from_text.name == from_dict.name == "rods_impact"
    plan = plan_of(loaded)
    assert plan_of(from_text) == plan
    assert plan_of(from_dict) == plan
    assert plan["nodes"] == 164 and plan["elements"] == 80
    assert [b["name"] for b in plan["bodies"]] == ["striker", "target"]
    assert plan["contact"]["tables"] == 1
    assert plan["time_step"] == pytest.approx(4.350184725e-6)


def test_check_reports_what_the_command_line_prints(cli) -> None:
    plan = ricochet.Scene.load(RODS).check()
    out = cli("check", RODS).stdout
    assert f"model      {plan['nodes']} nodes, {plan['elements']} elements, 2 bodies" in out
    assert f"plan       {plan['plan']}" in out
    assert f"about {plan['steps']} steps" in out


def test_overrides_use_the_study_key_paths() -> None:
    scene = ricochet.Scene.load(RODS)
    same = scene.set("body[striker].initial_velocity[0]", -3.5).set("run.end_time", 1.0e-4)
    assert same is scene
    assert scene.overrides == [("body[striker].initial_velocity[0]", -3.5), ("run.end_time", 1.0e-4)]
    tables = scene.to_dict()
    assert tables["body"][0]["initial_velocity"] == [-3.5, 0.0]
    assert tables["run"]["end_time"] == 1.0e-4
    # An integer for a float key is taken as a float, numpy scalars as numbers.
    scene.set("material[steel].density", np.int64(7800))
    assert scene.to_dict()["material"][0]["density"] == 7800.0
    # The text written back reads as the same scene.
    again = ricochet.Scene.from_toml(scene.to_toml(), name="rods_impact")
    assert plan_of(again) == plan_of(scene)


def test_a_refused_override_raises_scene_error_and_leaves_the_scene() -> None:
    scene = ricochet.Scene.load(RODS)
    with pytest.raises(ricochet.SceneError) as e:
        scene.set("material[steel].density", -1.0)
    err = e.value
    assert isinstance(err, ValueError)
    assert err.file == str(RODS)
    assert err.key == "material[0].density"
    assert err.value == "-1.0"
    assert str(err).startswith(f"{RODS}: key `material[0].density` = -1.0: ")
    with pytest.raises(ricochet.SceneError) as e:
        scene.set("body[nobody].thickness", 0.1)
    assert e.value.key == "body[nobody].thickness"
    assert "no `body` table is named" in e.value.reason
    assert scene.overrides == []


def test_bad_scene_files_raise_the_command_lines_exit_2_message(tmp_path, cli) -> None:
    text = RODS.read_text()
    cases = {
        "bad_value.toml": text.replace("density = 7850.0", "density = -7850.0"),
        "unknown_key.toml": text.replace("[run]", "[run]\nend_tme = 1.0"),
        "not_toml.toml": text.replace("[run]", "[run"),
    }
    for name, body in cases.items():
        path = tmp_path / name
        path.write_text(body)
        with pytest.raises(ricochet.SceneError) as e:
            ricochet.Scene.load(path)
        p = cli("check", path, check=False)
        assert p.returncode == 2, name
        assert p.stderr.startswith(f"error: {e.value}\n"), name
        assert e.value.file == str(path)
    with pytest.raises(ricochet.SceneError) as e:
        ricochet.Scene.load(tmp_path / "missing.toml")
    assert "cannot read" in str(e.value)


def test_mesh_arrays_come_from_the_model() -> None:
    positions, quads, body = ricochet.Scene.load(RODS).mesh()
    assert positions.shape == (164, 2) and positions.dtype == np.float64
    assert quads.shape == (80, 4) and quads.dtype == np.uint32
    assert body.shape == (80,) and set(body.tolist()) == {0, 1}
    assert positions[:, 0].min() == pytest.approx(-1.0)
    assert quads.max() < 164
