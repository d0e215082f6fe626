"""Read a VTK series written by fracture_results::vtk with VTK's own XML readers (Kitware's
`vtk` wheel from PyPI: an implementation independent of vtkio) and print what was read as
JSON, for results/tests/vtk_export.rs to compare with the snapshots it wrote.

Usage: python3 vtk_readback.py DIR. Exit 77 (with the reason on stdout) when the `vtk`
package cannot be imported; meshio is no alternative here: it reads only .vtk and .vtu.
"""

import json
import math
import os
import sys
import xml.etree.ElementTree as ET

try:
    from vtkmodules.vtkIOXML import vtkXMLImageDataReader, vtkXMLPolyDataReader
    from vtkmodules.vtkCommonCore import vtkVersion
except ImportError as e:  # pragma: no cover - depends on the machine
    print(f"SKIP: the Python `vtk` package is not importable ({e}); "
          "install it with `python3 -m pip install vtk`")
    sys.exit(77)


def num(x):
    return None if math.isnan(x) else x


def arrays(data):
    out = {}
    for i in range(data.GetNumberOfArrays()):
        a = data.GetArray(i)
        nc = a.GetNumberOfComponents()
        vals = [num(a.GetComponent(t, c)) for t in range(a.GetNumberOfTuples()) for c in range(nc)]
        out[a.GetName()] = {"components": nc, "type": a.GetDataTypeAsString(), "values": vals}
    return out


def read_checked(reader, path):
    reader.SetFileName(path)
    reader.Update()
    if reader.GetErrorCode() != 0:
        raise SystemExit(f"VTK could not read {path}: error code {reader.GetErrorCode()}")
    return reader.GetOutput()


def main():
    d = sys.argv[1]
    out = {"vtk_version": vtkVersion.GetVTKVersion(), "pvd": {}, "grids": {}, "cracks": {}}
    for name in ("fields.pvd", "cracks.pvd"):
        root = ET.parse(os.path.join(d, name)).getroot()
        assert root.get("type") == "Collection", root.attrib
        out["pvd"][name] = [
            {"time": float(ds.get("timestep")), "file": ds.get("file")}
            for ds in root.find("Collection").findall("DataSet")
        ]
    for entry in out["pvd"]["fields.pvd"]:
        img = read_checked(vtkXMLImageDataReader(), os.path.join(d, entry["file"]))
        out["grids"][entry["file"]] = {
            "dimensions": list(img.GetDimensions()),
            "origin": list(img.GetOrigin()),
            "spacing": list(img.GetSpacing()),
            "points": img.GetNumberOfPoints(),
            "point_data": arrays(img.GetPointData()),
        }
    for entry in out["pvd"]["cracks.pvd"]:
        poly = read_checked(vtkXMLPolyDataReader(), os.path.join(d, entry["file"]))
        lines = []
        for c in range(poly.GetNumberOfCells()):
            cell = poly.GetCell(c)
            pts = cell.GetPointIds()
            lines.append({
                "type": cell.GetCellType(),
                "points": [list(poly.GetPoint(pts.GetId(j))) for j in range(pts.GetNumberOfIds())],
            })
        out["cracks"][entry["file"]] = {
            "points": poly.GetNumberOfPoints(),
            "lines": lines,
            "cell_data": arrays(poly.GetCellData()),
        }
    print(json.dumps(out))


main()
