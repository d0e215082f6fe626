"""Reading a run's ``fields.mcap`` (the project's ``docs/mcap.md``).

The file is an MCAP (chunked, zstd-compressed) whose messages are all JSON:

========================  =====================  ==========================================
topic                     schema                 one message per
========================  =====================  ==========================================
``/energy``               ``fracture.EnergyRow``  energy sample (as ``energy.csv``)
``/crack_tips``           ``fracture.CrackTipRow`` tip per history sample (``crack_tips.csv``)
``/snapshot``             ``fracture.Snapshot``   snapshot: ``{"index", "time", "nx", "ny",
                                                  "origin", "cell_size", "fields",
                                                  "components": [{"name", "values"}],
                                                  "cracks"}``, values row-major from the
                                                  lower-left node, ``null`` for NaN
``/fields/<component>``   ``foxglove.Grid``       snapshot and component (base64 f32), for
                                                  Foxglove
========================  =====================  ==========================================

A metadata record named ``scene`` holds ``name``, ``hash``, ``json`` (the canonical scene)
and ``solver_version``.

The file is read front to back, record by record, so that a file whose writer has not
finished (a running job, a crash) reads up to its last complete chunk, as the Rust readers
do; :attr:`McapContents.truncated` then says so.
"""

from __future__ import annotations

import json
import os
import struct
from dataclasses import dataclass, field
from typing import IO, Any, Dict, Iterable, Iterator, List, Optional, Tuple, Union

import numpy as np
import zstandard
from mcap.exceptions import McapError
from mcap.records import Channel, Message, Metadata
from mcap.stream_reader import StreamReader

from .codec import Snapshot

__all__ = [
    "McapContents",
    "read_mcap",
    "iter_snapshots",
    "snapshot_from_message",
    "ENERGY_TOPIC",
    "CRACK_TIPS_TOPIC",
    "SNAPSHOT_TOPIC",
    "FIELDS_TOPIC_PREFIX",
]

ENERGY_TOPIC = "/energy"
CRACK_TIPS_TOPIC = "/crack_tips"
SNAPSHOT_TOPIC = "/snapshot"
FIELDS_TOPIC_PREFIX = "/fields/"

#: The 8 bytes that open (and close) every MCAP file.
MCAP_MAGIC = b"\x89MCAP0\r\n"

PathLike = Union[str, "os.PathLike[str]"]


@dataclass
class McapContents:
    """Everything in a ``fields.mcap`` but the Foxglove grids (which repeat the snapshots).

    Attributes:
        energy: the ``/energy`` rows (dicts, NaN as ``None``).
        crack_tips: the ``/crack_tips`` rows (dicts, NaN as ``None``).
        snapshots: the ``/snapshot`` messages decoded as :class:`Snapshot`.
        scene: the ``scene`` metadata record (``name``, ``hash``, ``json``,
            ``solver_version``), or ``None`` when the writer had no scene.
        truncated: whether the file ended before its writer finished it (everything up to
            the last complete chunk is read).
    """

    energy: List[Dict[str, Any]] = field(default_factory=list)
    crack_tips: List[Dict[str, Any]] = field(default_factory=list)
    snapshots: List[Snapshot] = field(default_factory=list)
    scene: Optional[Dict[str, str]] = None
    truncated: bool = False


def snapshot_from_message(
    msg: Dict[str, Any], components: Optional[Iterable[str]] = None
) -> Snapshot:
    """A :class:`Snapshot` from a decoded ``/snapshot`` message (``null`` values become NaN).

    Args:
        msg: the message's JSON object.
        components: keep only these components (all when ``None``).
    """
    nx = int(msg["nx"])
    ny = int(msg["ny"])
    wanted = None if components is None else set(components)
    comps: Dict[str, np.ndarray] = {}
    for c in msg.get("components", []):
        name = str(c["name"])
        if wanted is not None and name not in wanted:
            continue
        # float64 first: None converts to NaN there; then the values' own f32 precision.
        vals = np.array(c["values"], dtype=np.float64).astype(np.float32)
        if vals.size != nx * ny:
            raise ValueError(
                f"snapshot {msg.get('index')}: component {name} has {vals.size} values "
                f"for {nx}x{ny} nodes"
            )
        comps[name] = vals.reshape(ny, nx)
    origin = msg.get("origin", [0.0, 0.0])
    return Snapshot(
        index=int(msg["index"]),
        time=float(msg["time"]),
        nx=nx,
        ny=ny,
        origin=(float(origin[0]), float(origin[1])),
        cell_size=float(msg["cell_size"]),
        fields=[str(f) for f in msg.get("fields", [])],
        components=comps,
        cracks=[np.asarray(c, dtype=np.float64).reshape(-1, 2) for c in msg.get("cracks", [])],
    )


def _records(f: IO[bytes]) -> Iterator[Tuple[Optional[Channel], Any]]:
    """Records of the file in order as ``(channel of a message or None, record)``; stops
    quietly at a truncated tail, yielding ``(None, _TRUNCATED)`` then."""
    channels: Dict[int, Channel] = {}
    magic = f.read(len(MCAP_MAGIC))
    if magic != MCAP_MAGIC:
        from .errors import RunFormatError

        raise RunFormatError(
            f"{getattr(f, 'name', 'the file')} is not an MCAP file (it starts with {magic[:8]!r})"
        )
    reader = StreamReader(f, skip_magic=True, emit_chunks=False, validate_crcs=False)
    it = iter(reader.records)
    while True:
        try:
            rec = next(it)
        except StopIteration:
            return
        except (McapError, EOFError, struct.error, zstandard.ZstdError) as e:
            # An unfinished file ends inside a record or a chunk; everything before is good.
            yield None, _Truncated(str(e))
            return
        if isinstance(rec, Channel):
            channels[rec.id] = rec
            yield None, rec
        elif isinstance(rec, Message):
            yield channels.get(rec.channel_id), rec
        else:
            yield None, rec


class _Truncated:
    def __init__(self, why: str) -> None:
        self.why = why


def _open(path: PathLike) -> IO[bytes]:
    try:
        return open(path, "rb")
    except FileNotFoundError:
        from .errors import RunFormatError

        raise RunFormatError(f"no MCAP file at {os.fspath(path)}") from None


def iter_snapshots(
    path: PathLike, components: Optional[Iterable[str]] = None
) -> Iterator[Snapshot]:
    """The snapshots of a ``fields.mcap``, in file order (= time order), one at a time.

    Only one snapshot is held in memory at a time, so this suits large runs.

    Args:
        path: the ``fields.mcap`` file.
        components: keep only these components (e.g. ``["sxx", "fringe"]``); all when
            ``None``.
    """
    comps = None if components is None else list(components)
    with _open(path) as f:
        for ch, rec in _records(f):
            if ch is not None and ch.topic == SNAPSHOT_TOPIC:
                yield snapshot_from_message(json.loads(rec.data), comps)


def read_mcap(path: PathLike, snapshots: bool = True) -> McapContents:
    """Read a whole ``fields.mcap``: history rows, snapshots and the scene record.

    Args:
        path: the file.
        snapshots: whether to decode the ``/snapshot`` messages (``False`` reads the
            histories and the scene only, which is much faster for large runs).
    """
    out = McapContents()
    with _open(path) as f:
        for ch, rec in _records(f):
            if isinstance(rec, _Truncated):
                out.truncated = True
            elif isinstance(rec, Metadata):
                if rec.name == "scene":
                    out.scene = dict(rec.metadata)
            elif ch is not None:
                if ch.topic == ENERGY_TOPIC:
                    out.energy.append(json.loads(rec.data))
                elif ch.topic == CRACK_TIPS_TOPIC:
                    out.crack_tips.append(json.loads(rec.data))
                elif ch.topic == SNAPSHOT_TOPIC and snapshots:
                    out.snapshots.append(snapshot_from_message(json.loads(rec.data)))
    return out
