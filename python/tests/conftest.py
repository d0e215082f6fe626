"""Fixtures: the `fracture` binary, and a real server started for the test session.

The binary is ``$FRACTURE_BIN``, else ``target/release/fracture``, else
``target/debug/fracture`` of the checkout this folder belongs to (``cargo build`` or
``cargo test --workspace`` makes the debug one).
"""

from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path
from typing import Iterator

import pytest

from mpm_fracture import Client, FractureError, Job

REPO = Path(__file__).resolve().parents[2]
SCENES = Path(__file__).resolve().parent / "scenes"
TINY_SCENE = SCENES / "tiny-crack.json"


def find_binary() -> Path:
    """The `fracture` binary the tests run."""
    env = os.environ.get("FRACTURE_BIN")
    if env:
        p = Path(env)
        if not p.is_file():
            pytest.fail(f"FRACTURE_BIN={env} is not a file")
        return p
    for profile in ("release", "debug"):
        p = REPO / "target" / profile / "fracture"
        if p.is_file():
            return p
    pytest.fail(
        f"no fracture binary: set FRACTURE_BIN, or build one in {REPO} "
        "(`cargo build --release` or `cargo build -p fracture-cli`)"
    )


@pytest.fixture(scope="session")
def fracture_bin() -> Path:
    return find_binary()


@pytest.fixture(scope="session")
def tiny_scene() -> Path:
    return TINY_SCENE


@pytest.fixture(scope="session")
def server(fracture_bin: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """A `fracture serve` on a free loopback port with its own data folder; yields its
    base URL and stops it after the session."""
    data = tmp_path_factory.mktemp("fracture-data")
    log_path = data.parent / (data.name + "-server.log")
    log = open(log_path, "wb")
    # Port 0: the server picks a free port and writes it to <data>/server.addr (no race
    # between choosing a port and binding it).
    cmd = [
        str(fracture_bin), "serve",
        "--bind", "127.0.0.1:0",
        "--data", str(data),
        "--workers", "1",
        "--worker-threads", "1",
    ]
    # The flags above, not a FRACTURE_* setting of the environment (a token, a database).
    env = {k: v for k, v in os.environ.items() if not k.startswith("FRACTURE_")}
    proc = subprocess.Popen(
        cmd, stdout=log, stderr=subprocess.STDOUT, env=env, start_new_session=True
    )

    def server_log() -> str:
        log.flush()
        return log_path.read_text(errors="replace")[-4000:]

    url = None
    deadline = time.monotonic() + 60
    try:
        while time.monotonic() < deadline:
            if proc.poll() is not None:
                pytest.fail(f"fracture serve exited with {proc.returncode}:\n{server_log()}")
            addr = data / "server.addr"
            if url is None and addr.exists() and addr.read_text().strip():
                url = "http://" + addr.read_text().strip()
            if url is not None:
                try:
                    if Client(url, timeout=2).health()["status"] == "ok":
                        break
                except FractureError:
                    pass
            time.sleep(0.1)
        else:
            pytest.fail(f"fracture serve did not answer /api/v1/health within 60 s:\n{server_log()}")
        yield url
    finally:
        if proc.poll() is None:
            proc.terminate()  # SIGTERM: the server stops its workers and exits
            try:
                proc.wait(timeout=15)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)  # the session this fixture started
                proc.wait(timeout=5)
        log.close()


@pytest.fixture(scope="session")
def client(server: str) -> Client:
    return Client(server, timeout=30)


@pytest.fixture(scope="session")
def completed_job(client: Client, tiny_scene: Path) -> Job:
    """The tiny scene, submitted and waited for once per session."""
    job = client.submit(tiny_scene, labels={"suite": "python"})
    return client.wait(job, progress=False, timeout=120, check=True)
