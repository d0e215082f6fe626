"""Format tests that need no server: the FSN1 snapshot codec, the MCAP reader on a file
written like the Rust writer does (finished and unfinished), the CSV readers."""

from __future__ import annotations

import io
import json
import struct
from pathlib import Path
from typing import List

import numpy as np
import pytest
from mcap.writer import CompressionType, Writer

from mpm_fracture import (
    Run,
    RunFormatError,
    Snapshot,
    SnapshotCodecError,
    decode_snapshot,
    encode_snapshot,
    read_crack_tips_csv,
    read_mcap,
)


def _snapshot(index: int = 3, nx: int = 3, ny: int = 2) -> Snapshot:
    vx = np.arange(nx * ny, dtype=np.float32).reshape(ny, nx)
    vx[0, 1] = np.nan
    return Snapshot(
        index=index,
        time=1e-6 * (index + 1),
        nx=nx,
        ny=ny,
        origin=(0.0, 1.0),
        cell_size=0.5,
        fields=["velocity"],
        components={"vx": vx, "vy": -vx},
        cracks=[np.array([[0.0, 0.0], [1.0, 0.5]])],
    )


def test_fsn1_round_trip_keeps_nan_and_layout() -> None:
    s = _snapshot()
    b = encode_snapshot(s)
    assert b[:4] == b"FSN1"
    (hl,) = struct.unpack_from("<I", b, 4)
    header = json.loads(b[8 : 8 + hl])
    assert header["components"] == [["vx", 6], ["vy", 6]]
    assert len(b) == 8 + hl + 2 * 6 * 4
    d = decode_snapshot(b)
    assert (d.index, d.nx, d.ny, d.origin, d.cell_size) == (3, 3, 2, (0.0, 1.0), 0.5)
    assert d["vx"].shape == (2, 3) and d["vx"].dtype == np.float32
    assert np.isnan(d["vx"][0, 1])
    np.testing.assert_array_equal(d["vy"], s["vy"])
    # Row-major from the lower-left node: index iy*nx + ix.
    values = np.frombuffer(b[8 + hl : 8 + hl + 24], dtype="<f4")
    assert values[1 * 3 + 2] == d["vx"][1, 2]
    np.testing.assert_array_equal(d.cracks[0], s.cracks[0])


@pytest.mark.parametrize(
    "mutate, why",
    [
        (lambda b: b"nope", "missing FSN1 header"),
        (lambda b: b[:12], "truncated header"),
        (lambda b: b[:-1], "truncated values"),
        (lambda b: b + b"\0", "trailing bytes"),
    ],
)
def test_fsn1_rejects_malformed(mutate, why: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(SnapshotCodecError, match=why):
        decode_snapshot(mutate(encode_snapshot(_snapshot())))


def _write_mcap(path: Path, snaps: List[Snapshot], finish: bool = True) -> None:
    """A file shaped like the Rust writer's: JSON messages, zstd chunks, one chunk per
    snapshot, the scene as metadata."""
    f = open(path, "wb")
    # chunk_size=1: every message ends its chunk (the Rust writer ends one per snapshot).
    w = Writer(f, compression=CompressionType.ZSTD, chunk_size=1)
    w.start(profile="", library="test")
    sid = w.register_schema("fracture.Snapshot", "jsonschema", b"{}")
    tid = w.register_schema("fracture.CrackTipRow", "jsonschema", b"{}")
    snap_ch = w.register_channel("/snapshot", "json", sid)
    tip_ch = w.register_channel("/crack_tips", "json", tid)
    w.add_metadata("scene", {"name": "t", "hash": "h", "json": '{"name":"t"}', "solver_version": "0"})
    for s in snaps:
        ns = int(round(s.time * 1e9))
        row = {"time": s.time, "crack": 0, "tip": 1, "x": 0.01, "y": None, "length": 0.02,
               "speed": 0.0, "j1": 1.5, "j2": None, "k1": 2.0e5, "k2": None, "growing": False}
        w.add_message(tip_ch, ns, json.dumps(row).encode(), ns)
        msg = {
            "index": s.index, "time": s.time, "nx": s.nx, "ny": s.ny,
            "origin": list(s.origin), "cell_size": s.cell_size, "fields": s.fields,
            "components": [
                {"name": n, "values": [None if np.isnan(v) else float(v) for v in a.ravel()]}
                for n, a in s.components.items()
            ],
            "cracks": [c.tolist() for c in s.cracks],
        }
        w.add_message(snap_ch, ns, json.dumps(msg).encode(), ns)
        f.flush()
    if finish:
        w.finish()  # type: ignore[no-untyped-call]
    f.close()


def _chunk_offsets(data: bytes) -> List[int]:
    """Offsets of the chunk records (opcode 0x06) of an MCAP file's data section."""
    out: List[int] = []
    pos = 8
    while pos + 9 <= len(data):
        op, length = data[pos], struct.unpack_from("<Q", data, pos + 1)[0]
        if op == 0x06:
            out.append(pos)
        pos += 9 + length
    return out


def test_mcap_reader_finished_and_unfinished(tmp_path: Path) -> None:
    snaps = [_snapshot(i) for i in range(3)]
    done = tmp_path / "done.mcap"
    _write_mcap(done, snaps)
    c = read_mcap(done)
    assert not c.truncated
    assert [s.index for s in c.snapshots] == [0, 1, 2]
    assert c.scene is not None and c.scene["name"] == "t"
    assert len(c.crack_tips) == 3 and c.crack_tips[0]["y"] is None
    got = c.snapshots[1]
    assert got["vx"].shape == (2, 3)
    assert np.isnan(got["vx"][0, 1])
    np.testing.assert_array_equal(np.nan_to_num(got["vx"]), np.nan_to_num(snaps[1]["vx"]))

    # A writer that never finished (a running job): cut the file inside its last chunk.
    open_file = tmp_path / "open.mcap"
    _write_mcap(open_file, snaps, finish=False)
    data = open_file.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: _chunk_offsets(data)[-1] + 30])
    c2 = read_mcap(cut)
    assert c2.truncated
    assert [s.index for s in c2.snapshots] == [0, 1]

    # The same through a run folder.
    folder = tmp_path / "run"
    folder.mkdir()
    (folder / "fields.mcap").write_bytes(done.read_bytes())
    run = Run.open(folder)
    assert [s.time for s in run.snapshots(["vy"])] == [s.time for s in snaps]
    assert list(run.snapshot(2).components) == ["vx", "vy"]
    assert run.scene == {"name": "t"}
    assert run.crack_tips["k1"].tolist() == [2.0e5] * 3  # from the MCAP: no CSV here
    assert run.tips.empty and "k1_peak" in run.tips.columns


def test_not_an_mcap(tmp_path: Path) -> None:
    p = tmp_path / "fields.mcap"
    p.write_bytes(b"hello world, not mcap")
    with pytest.raises(RunFormatError, match="not an MCAP file"):
        read_mcap(p)


def test_crack_tips_csv_types() -> None:
    text = (
        "time,crack,tip,x,y,length,speed,j1,j2,k1,k2,growing,j1_half\n"
        "0,0,1,0.01,0.02,0.017,0,NaN,inf,1.5e5,-inf,0,1e-5\n"
        "1e-6,0,1,0.01,0.02,0.017,12.5,4.8,0,1.6e5,0,1,NaN\n"
    )
    df = read_crack_tips_csv(io.StringIO(text))
    assert df["crack"].dtype == np.int64 and df["growing"].dtype == bool
    assert df["growing"].tolist() == [False, True]
    assert np.isnan(df["j1"][0]) and df["j2"][0] == np.inf and df["k2"][0] == -np.inf
    assert df["time"][1] == 1e-6


def test_run_open_errors_and_tips(tmp_path: Path) -> None:
    with pytest.raises(RunFormatError, match="no run folder"):
        Run.open(tmp_path / "missing")
    with pytest.raises(RunFormatError, match="not a run folder"):
        Run.open(tmp_path)
    summary = {
        "status": "completed",
        "steps": 10,
        "tips": [
            {"crack": 0, "tip": 0, "samples": 5, "x": 0.01, "y": 0.02, "initiation_time": None,
             "growth": 0.0, "j1_final": 4.8, "j1_peak": 4.9, "k1_final": 1.6e5, "k1_peak": 1.7e5,
             "k2_final": 1.0, "k2_peak": 2.0, "mean_speed": 0.0, "peak_speed": 0.0,
             "speed_window": 1e-6},
        ],
        "references": [
            {"quantity": "K_I", "value": 167948.0, "measured": 167600.0,
             "relative_error": -0.002, "source": "Tada"},
        ],
    }
    (tmp_path / "summary.json").write_text(json.dumps(summary))
    run = Run.open(tmp_path / "summary.json")
    assert run.status == "completed"
    tips = run.tips
    assert len(tips) == 1 and tips["k1_final"][0] == 1.6e5
    assert np.isnan(tips["initiation_time"][0])
    assert run.references["source"].tolist() == ["Tada"]
    with pytest.raises(RunFormatError, match="no crack_tips.csv"):
        run.crack_tips
