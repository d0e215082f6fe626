"""Reading the folder `fracture run SCENE --out DIR` writes."""

from __future__ import annotations

import base64
import json
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
from mcap.reader import make_reader

from mpm_fracture import CRACK_TIPS_UNITS, ENERGY_UNITS, Run, read_mcap


def test_local_run_folder(fracture_bin: Path, tiny_scene: Path, tmp_path: Path) -> None:
    out = tmp_path / "tiny"
    r = subprocess.run(
        [str(fracture_bin), "run", str(tiny_scene), "--out", str(out), "--threads", "1"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 0, r.stderr
    run = Run.open(out)
    assert run.status == "completed"
    assert run.summary["particles"] == 2400

    tips = run.crack_tips
    assert list(tips.columns)[:12] == list(CRACK_TIPS_UNITS)[:12]
    assert set(tips.columns) <= set(CRACK_TIPS_UNITS)
    assert tips["crack"].dtype == np.int64 and tips["growing"].dtype == bool
    assert list(run.energy.columns) == list(ENERGY_UNITS)
    # The histories in the MCAP file are the CSV's.
    m = read_mcap(run.mcap_path, snapshots=False)
    assert not m.truncated
    mk1 = pd.Series([np.nan if row["k1"] is None else row["k1"] for row in m.crack_tips])
    np.testing.assert_array_equal(mk1.to_numpy(), tips["k1"].to_numpy())
    assert m.scene is not None and json.loads(m.scene["json"])["name"] == "tiny-crack"

    # tips: built from summary["tips"] when the solver writes it, else empty.
    t = run.tips
    if "tips" in run.summary:
        assert len(t) == len(run.summary["tips"])
    else:
        assert t.empty

    # Snapshots: (ny, nx) arrays equal, bit for bit, to the Foxglove grids of the same file.
    snaps = list(run.snapshots())
    assert len(snaps) == 5
    grids = {}
    with open(run.mcap_path, "rb") as f:
        for _, ch, msg in make_reader(f).iter_messages(topics=["/fields/syy"]):
            g = json.loads(msg.data)
            grids[msg.log_time] = np.frombuffer(base64.b64decode(g["data"]), dtype="<f4")
    assert len(grids) == len(snaps)
    for s, (ns, flat) in zip(snaps, sorted(grids.items())):
        a = s["syy"]
        assert a.shape == (s.ny, s.nx)
        assert np.isfinite(a).mean() > 0.8
        np.testing.assert_array_equal(a.ravel(), flat)
    assert run.snapshot(-1).index == 4
