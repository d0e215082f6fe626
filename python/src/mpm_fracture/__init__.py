"""mpm-fracture: a Python client of the mpm-fracture service and a reader of its runs.

* :class:`Client` talks to a server (``fracture serve`` / ``cargo run --release``):
  submit scenes, wait with progress, follow the event stream, list jobs, download files.
* :class:`Run` reads a run: the folder ``fracture run SCENE.json --out DIR`` writes, or a
  job's downloaded results (:meth:`Client.run`). Histories are pandas DataFrames in SI
  units, snapshots NumPy arrays.

Quick start::

    from mpm_fracture import Client
    client = Client("http://127.0.0.1:8080")
    job = client.submit("scenes/center-crack.json").wait()
    run = job.run()
    print(run.crack_tips[["time", "tip", "k1"]].tail())
"""

from .client import DEFAULT_URL, TERMINAL_STATUSES, Client, Event, Job, load_scene
from .codec import Snapshot, SnapshotCodecError, decode_snapshot, encode_snapshot
from .errors import (
    ApiError,
    FractureError,
    JobFailed,
    RunFormatError,
    ServerNotRunning,
    WaitTimeout,
)
from .mcapfile import McapContents, iter_snapshots, read_mcap
from .run import (
    CRACK_TIPS_UNITS,
    ENERGY_UNITS,
    TIPS_UNITS,
    Run,
    read_crack_tips_csv,
    read_energy_csv,
)

__version__ = "0.1.0"

__all__ = [
    "Client",
    "Job",
    "Event",
    "Run",
    "Snapshot",
    "McapContents",
    "read_mcap",
    "iter_snapshots",
    "decode_snapshot",
    "encode_snapshot",
    "read_crack_tips_csv",
    "read_energy_csv",
    "load_scene",
    "CRACK_TIPS_UNITS",
    "ENERGY_UNITS",
    "TIPS_UNITS",
    "DEFAULT_URL",
    "TERMINAL_STATUSES",
    "FractureError",
    "ServerNotRunning",
    "ApiError",
    "JobFailed",
    "WaitTimeout",
    "RunFormatError",
    "SnapshotCodecError",
    "__version__",
]
