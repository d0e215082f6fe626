"""Field snapshots: the :class:`Snapshot` type and the project's binary snapshot codec.

The service keeps snapshots, and workers upload them, in a small binary format (the Rust
side is ``results/src/codec.rs``)::

    b"FSN1"                      4 bytes, magic
    header length                u32, little-endian
    header                       JSON: {"index", "time", "nx", "ny", "origin", "cell_size",
                                        "fields", "components": [[name, count], ...],
                                        "cracks"}
    values                       for each component in header order, ``count`` f32
                                 little-endian values (count = nx * ny), NaN where no
                                 material touches the node

Values are at the grid nodes, row-major from the lower-left node: index = iy * nx + ix.
:func:`decode_snapshot` reads it (for instance a ``snapshots`` blob of the service's SQLite
store); :func:`encode_snapshot` writes it. ``fields.mcap`` carries the same snapshots as
JSON (see :mod:`mpm_fracture.mcapfile`).
"""

from __future__ import annotations

import json
import struct
from dataclasses import dataclass, field
from typing import Dict, Iterator, List, Sequence, Tuple

import numpy as np

__all__ = ["Snapshot", "decode_snapshot", "encode_snapshot", "SnapshotCodecError", "MAGIC"]

#: Magic bytes that open an encoded snapshot.
MAGIC = b"FSN1"


class SnapshotCodecError(ValueError):
    """An encoded snapshot that cannot be decoded (the message says why)."""


@dataclass
class Snapshot:
    """One field snapshot of a run: node-sampled fields and the crack lines at one time.

    Attributes:
        index: index of the snapshot in its run (0, 1, ...).
        time: simulated time (s).
        nx, ny: nodes in x and y.
        origin: position (x, y) of node (0, 0) (m).
        cell_size: node spacing h (m).
        fields: field kinds recorded (``stress``, ``strain``, ``velocity``,
            ``displacement``, ``fringe``, ``material``).
        components: the components of those fields by name, each a ``float32`` array of
            shape ``(ny, nx)``: ``values[iy, ix]`` is the node at
            ``(origin[0] + ix*h, origin[1] + iy*h)`` (row 0 is the lowest y). NaN where no
            material touches the node. Units: ``sxx``, ``syy``, ``sxy`` Pa; ``exx``,
            ``eyy``, ``exy`` strain (1); ``vx``, ``vy``, ``speed`` m/s; ``ux``, ``uy`` m;
            ``fringe`` isochromatic fringe order N = t·(σ1 − σ2)/f_s (no unit; t the
            scene's ``thickness``, f_s its ``output.fringe_constant``); ``material`` the
            material's index.
        cracks: each crack's line as an ``(n, 2)`` float64 array of points (m).
    """

    index: int
    time: float
    nx: int
    ny: int
    origin: Tuple[float, float]
    cell_size: float
    fields: List[str]
    components: Dict[str, np.ndarray]
    cracks: List[np.ndarray] = field(default_factory=list)

    def __getitem__(self, name: str) -> np.ndarray:
        """The ``(ny, nx)`` array of component ``name`` (e.g. ``snap["sxx"]``)."""
        try:
            return self.components[name]
        except KeyError:
            raise KeyError(
                f"snapshot {self.index} has no component {name!r}; it has "
                f"{', '.join(self.components) or 'none'}"
            ) from None

    def __contains__(self, name: object) -> bool:
        return name in self.components

    def __iter__(self) -> Iterator[str]:
        return iter(self.components)

    @property
    def x(self) -> np.ndarray:
        """x of the node columns (m), shape ``(nx,)``."""
        return self.origin[0] + self.cell_size * np.arange(self.nx, dtype=np.float64)

    @property
    def y(self) -> np.ndarray:
        """y of the node rows (m), shape ``(ny,)``."""
        return self.origin[1] + self.cell_size * np.arange(self.ny, dtype=np.float64)

    @property
    def extent(self) -> Tuple[float, float, float, float]:
        """``(left, right, bottom, top)`` of the cells centred on the nodes (m): pass it to
        ``matplotlib.pyplot.imshow(snap["sxx"], origin="lower", extent=snap.extent)``."""
        h = self.cell_size
        x0, y0 = self.origin
        return (x0 - 0.5 * h, x0 + (self.nx - 0.5) * h, y0 - 0.5 * h, y0 + (self.ny - 0.5) * h)

    def __repr__(self) -> str:
        return (
            f"Snapshot(index={self.index}, time={self.time:.6g} s, grid {self.nx}x{self.ny} "
            f"nodes at h={self.cell_size:g} m, components={list(self.components)})"
        )


def decode_snapshot(data: bytes) -> Snapshot:
    """Decode an ``FSN1`` snapshot, checking every length (like the Rust decoder).

    Raises:
        SnapshotCodecError: missing magic, truncated header or values, a component whose
            count is not ``nx * ny``, or trailing bytes.
    """
    b = memoryview(data)
    if len(b) < 8 or bytes(b[:4]) != MAGIC:
        raise SnapshotCodecError("malformed snapshot: missing FSN1 header")
    (hl,) = struct.unpack_from("<I", b, 4)
    if len(b) < 8 + hl:
        raise SnapshotCodecError("malformed snapshot: truncated header")
    try:
        header = json.loads(bytes(b[8 : 8 + hl]))
        nx = int(header["nx"])
        ny = int(header["ny"])
        comps: Sequence[Tuple[str, int]] = [(str(n), int(c)) for n, c in header["components"]]
    except (ValueError, KeyError, TypeError) as e:
        raise SnapshotCodecError(f"malformed snapshot: header: {e}") from None
    nodes = nx * ny
    pos = 8 + hl
    components: Dict[str, np.ndarray] = {}
    for name, count in comps:
        if count != nodes:
            raise SnapshotCodecError(
                f"malformed snapshot: component {name} has {count} values for {nodes} nodes"
            )
        if len(b) - pos < 4 * count:
            raise SnapshotCodecError("malformed snapshot: truncated values")
        vals = np.frombuffer(b, dtype="<f4", count=count, offset=pos)
        components[name] = vals.astype(np.float32).reshape(ny, nx)
        pos += 4 * count
    if pos != len(b):
        raise SnapshotCodecError("malformed snapshot: trailing bytes")
    return Snapshot(
        index=int(header["index"]),
        time=float(header["time"]),
        nx=nx,
        ny=ny,
        origin=(float(header["origin"][0]), float(header["origin"][1])),
        cell_size=float(header["cell_size"]),
        fields=[str(f) for f in header.get("fields", [])],
        components=components,
        cracks=[np.asarray(c, dtype=np.float64).reshape(-1, 2) for c in header.get("cracks", [])],
    )


def encode_snapshot(s: Snapshot) -> bytes:
    """Encode a snapshot as ``FSN1`` (the inverse of :func:`decode_snapshot`)."""
    header = {
        "index": int(s.index),
        "time": float(s.time),
        "nx": int(s.nx),
        "ny": int(s.ny),
        "origin": [float(s.origin[0]), float(s.origin[1])],
        "cell_size": float(s.cell_size),
        "fields": list(s.fields),
        "components": [[name, int(np.asarray(v).size)] for name, v in s.components.items()],
        "cracks": [np.asarray(c, dtype=np.float64).reshape(-1, 2).tolist() for c in s.cracks],
    }
    h = json.dumps(header, separators=(",", ":")).encode()
    parts = [MAGIC, struct.pack("<I", len(h)), h]
    for v in s.components.values():
        parts.append(np.ascontiguousarray(v, dtype="<f4").tobytes())
    return b"".join(parts)
