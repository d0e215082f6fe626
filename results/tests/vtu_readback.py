"""Read a VTK series' particle files (`particles_*.vtu`, `particles.pvd`) with meshio, an
independent reader, and print what it found as JSON. Exit 77 when meshio is missing."""

import json
import re
import sys
from pathlib import Path

try:
    import meshio
except ImportError as e:  # pragma: no cover - depends on the machine
    print(f"meshio is not installed ({e})")
    sys.exit(77)


def main(folder: str) -> None:
    d = Path(folder)
    out = {"meshio_version": meshio.__version__, "files": {}, "pvd": []}
    pvd = (d / "particles.pvd").read_text()
    for m in re.finditer(r'timestep="([^"]+)"[^>]*file="([^"]+)"', pvd):
        out["pvd"].append({"time": float(m.group(1)), "file": m.group(2)})
    for f in sorted(d.glob("particles_*.vtu")):
        mesh = meshio.read(f)
        cells = {c.type: int(len(c.data)) for c in mesh.cells}
        out["files"][f.name] = {
            "points": mesh.points.tolist(),
            "cells": cells,
            "point_data": {k: v.tolist() for k, v in mesh.point_data.items()},
        }
    print(json.dumps(out))


if __name__ == "__main__":
    main(sys.argv[1])
