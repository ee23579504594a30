"""Studies from Python: the cases made by the study library code, run on a local process pool and
on a Dask LocalCluster, collected as `ricochet collect` does: the same results.csv as `ricochet
study` for the same study."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import pandas as pd
import pytest

import ricochet
from conftest import ASSETS, DATA

STUDY = DATA / "rods_4.toml"
PARAMETERS = [
    {"name": "v0", "key": "body[striker].initial_velocity[0]", "values": [4.0, 10.0]},
    {"name": "target_thickness", "key": "body[target].thickness", "values": [0.004, 0.008]},
]
COLLECT = {
    "target_v": {"history": "target.vx", "reduce": "final"},
    "peak_force": {"history": "striker-target.fx", "reduce": "min"},
    "steps": {"summary": "steps"},
}


@pytest.fixture(scope="module")
def reference(tmp_path_factory, cli):
    """`ricochet study` of the same study: its results.csv."""
    root = tmp_path_factory.mktemp("cli") / "rods_4"
    cli("study", STUDY, "--out", root)
    return (root / "results.csv").read_text()


def test_a_study_file_on_the_default_process_pool(tmp_path, reference) -> None:
    table = ricochet.study(STUDY, out=tmp_path / "rods_4", progress=False)
    assert (tmp_path / "rods_4" / "results.csv").read_text() == reference
    assert isinstance(table, pd.DataFrame)
    assert list(table["id"]) == ["0000", "0001", "0002", "0003"]
    assert list(table["status"]) == ["completed"] * 4
    assert table.attrs["out"] == str(tmp_path / "rods_4")
    # A rerun skips the finished cases and gives the same table.
    again = ricochet.study(STUDY, out=tmp_path / "rods_4", progress=False)
    assert again.equals(table)


def test_a_study_from_arguments_gives_the_same_table(tmp_path, reference) -> None:
    with ThreadPoolExecutor(max_workers=2) as pool:
        table = ricochet.study(
            ASSETS / "rods_impact.toml",
            PARAMETERS,
            collect=COLLECT,
            executor=pool,
            name="rods_4",
            out=tmp_path / "rods_4",
            backend="cpu",
            progress=False,
        )
    assert (tmp_path / "rods_4" / "results.csv").read_text() == reference
    assert table["target_v"].iloc[0] == pytest.approx(4.0, rel=0.05)
    # The study file it wrote is one `ricochet study` reads.
    assert (tmp_path / "rods_4" / "study.toml").is_file()


def test_a_study_on_a_dask_local_cluster(tmp_path, reference) -> None:
    from dask.distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with Client(cluster) as client:
            table = ricochet.study(STUDY, executor=client.get_executor(), out=tmp_path / "rods_4", progress=False)
    assert (tmp_path / "rods_4" / "results.csv").read_text() == reference
    assert len(table) == 4


def test_a_refused_case_names_key_value_and_case(tmp_path) -> None:
    with pytest.raises(ricochet.SceneError) as e:
        ricochet.study(
            ASSETS / "rods_impact.toml",
            {"material[steel].density": {"name": "rho", "values": [7850.0, -1.0]}},
            collect={"steps": {"summary": "steps"}},
            name="bad",
            out=tmp_path / "bad",
            progress=False,
        )
    assert e.value.key == "material[steel].density"
    assert "case 0001" in str(e.value)
