"""The client against a real server (the `server` fixture of conftest.py)."""

from __future__ import annotations

import io
import json
import socket
import zipfile
from pathlib import Path
from typing import List

import numpy as np
import pandas as pd
import pytest

from mpm_fracture import ApiError, Client, Job, Run, ServerNotRunning, read_crack_tips_csv


def free_port() -> int:
    """A loopback port nothing listens on (bound, then released)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _same(a: pd.Series, b: pd.Series) -> None:
    """Equal column by column, NaN equal to NaN."""
    np.testing.assert_array_equal(a.to_numpy(), b.to_numpy())


def test_health_and_version(client: Client) -> None:
    assert client.health()["status"] == "ok"
    assert client.version()["service"] == "fracture-server"


def test_submit_wait_read_histories_compare_with_csv(
    client: Client, completed_job: Job, tmp_path: Path
) -> None:
    """The acceptance: submit, wait, read histories, compare a column with the CSV."""
    job = completed_job
    assert job.status == "completed" and job.summary is not None
    assert job.summary["steps"] > 0

    tips = client.crack_tips(job)  # JSON rows -> DataFrame
    energy = client.energy(job)
    files = client.download(job, tmp_path, ["crack_tips.csv", "energy.csv"])
    csv_tips = pd.read_csv(files["crack_tips.csv"])  # the server's CSV, read by pandas alone
    csv_energy = pd.read_csv(files["energy.csv"])

    assert list(tips.columns) == list(csv_tips.columns)
    assert len(tips) == len(csv_tips) > 0
    for col in ("time", "x", "length", "j1", "k1", "k2"):
        _same(tips[col], csv_tips[col])
    _same(tips["growing"], csv_tips["growing"].astype(bool))
    assert list(energy.columns) == list(csv_energy.columns)
    _same(energy["strain"], csv_energy["strain"])

    # The same through a Run of the job's downloaded folder.
    run = client.run(job, tmp_path / "run")
    _same(run.crack_tips["k1"], csv_tips["k1"])
    _same(run.energy["kinetic"], csv_energy["kinetic"])
    assert run.summary["scene_hash"] == job.summary["scene_hash"]
    assert run.scene is not None and run.scene["name"] == "tiny-crack"
    # K_I loads up with the traction: positive at both tips by the end.
    last = run.crack_tips[run.crack_tips.time == run.crack_tips.time.max()]
    assert sorted(last.tip.tolist()) == [0, 1]
    assert (last.k1 > 0).all()

    # The CSV text the client returns reads the same too.
    _same(read_crack_tips_csv(io.StringIO(client.crack_tips_csv(job)))["j1"], csv_tips["j1"])


def test_snapshots_decode_to_grids(client: Client, completed_job: Job, tmp_path: Path) -> None:
    run = Run.from_job(client, completed_job.id, tmp_path)
    index = client.snapshots(completed_job)
    snaps = list(run.snapshots())
    assert [s.index for s in snaps] == [e["index"] for e in index]
    assert [s.time for s in snaps] == [e["time"] for e in index]
    scene = json.loads((Path(__file__).parent / "scenes" / "tiny-crack.json").read_text())
    h = scene["grid"]["cell_size"]
    nx = round((scene["grid"]["max"][0] - scene["grid"]["min"][0]) / h) + 1
    ny = round((scene["grid"]["max"][1] - scene["grid"]["min"][1]) / h) + 1
    for s in snaps:
        assert (s.nx, s.ny) == (nx, ny)
        assert list(s.components) == index[s.index]["components"]
        for name, a in s.components.items():
            assert a.shape == (ny, nx), name
            finite = np.isfinite(a)
            assert finite.mean() > 0.8, name  # NaN only at nodes no material touches
    last = snaps[-1]
    syy = last["syy"]
    assert np.nanmax(syy) > 0  # tension
    assert len(last.cracks) == 1 and last.cracks[0].shape[1] == 2
    # The lower-left node is row 0: the y of the rows rises.
    assert last.y[0] == pytest.approx(scene["grid"]["min"][1]) and last.y[-1] > last.y[0]


def test_wait_reports_progress_and_stream_yields_events(client: Client, tiny_scene: Path) -> None:
    seen: List[str] = []
    job = client.submit(tiny_scene, cache=False, labels={"suite": "python-stream"})
    events = list(client.stream(job, timeout=60))
    names = [e["event"] for e in events]
    assert names[-1] == "status" and events[-1]["data"]["status"] == "completed"
    assert all(isinstance(e["data"], (dict, list)) for e in events)
    assert {"status"} <= set(names) <= {"status", "progress", "energy", "crack_tip", "snapshot"}
    for e in events:
        if e["event"] == "progress":
            assert 0.0 <= e["data"]["fraction"] <= 1.0
        if e["event"] == "crack_tip":
            assert isinstance(e["data"], list) and "k1" in e["data"][0]

    done = client.wait(job, progress=lambda j: seen.append(j.status), timeout=60)
    assert done.status == "completed" and seen[-1] == "completed"
    assert [j.id for j in client.jobs(label="suite:python-stream")] == [job.id]


def test_wait_prints_a_progress_line(
    client: Client, completed_job: Job, capsys: pytest.CaptureFixture[str]
) -> None:
    completed_job.wait(timeout=30)
    err = capsys.readouterr().err
    assert f"job {completed_job.id[:12]} (tiny-crack): completed" in err


def test_download_every_file(client: Client, completed_job: Job, tmp_path: Path) -> None:
    files = client.download(completed_job, tmp_path)
    assert set(files) == {"summary.json", "crack_tips.csv", "energy.csv", "fields.mcap", "vtk.zip"}
    assert json.loads(files["summary.json"].read_text())["status"] == "completed"
    assert files["fields.mcap"].read_bytes()[:8] == b"\x89MCAP0\r\n"
    with zipfile.ZipFile(files["vtk.zip"]) as z:
        assert any(n.endswith("fields.pvd") for n in z.namelist())


def test_api_errors_carry_the_error_body(client: Client, tiny_scene: Path) -> None:
    with pytest.raises(ApiError) as e:
        client.job("no-such-job")
    assert e.value.status == 404 and e.value.error == "not_found"
    assert "no-such-job" in e.value.message

    scene = json.loads(tiny_scene.read_text())
    scene["materials"]["homalite"]["poissons_ratio"] = 0.7
    with pytest.raises(ApiError) as e:
        client.submit(scene)
    assert e.value.status == 422 and e.value.error == "invalid_scene"
    assert [d["path"] for d in e.value.details] == ["materials.homalite.poissons_ratio"]
    assert "poissons_ratio" in str(e.value)


def test_connection_refused_says_how_to_start_the_server() -> None:
    url = f"http://127.0.0.1:{free_port()}"
    with pytest.raises(ServerNotRunning) as e:
        Client(url, timeout=5).health()
    msg = str(e.value)
    assert f"not running at {url}" in msg
    assert "cargo run --release" in msg and "fracture serve" in msg


def test_validate_and_pictures(client: Client, completed_job: Job, tiny_scene: Path) -> None:
    v = client.validate(tiny_scene)
    assert v["valid"] is True and v["particles"] == 2400 and v["steps"] > 0
    png = client.snapshot_png(completed_job, 0, "syy", px_per_cell=2, legend=False)
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ApiError) as e:
        client.snapshot_png(completed_job, 0, "syy", px_per_cell=-1)
    assert e.value.status == 400 and e.value.details[0]["path"] == "px_per_cell"
