"""Read a 3D run's VTK volumes (fracture_results::vtk3) with VTK's own XML readers (Kitware's
`vtk` wheel from PyPI, independent of vtkio, which wrote them) and print what was read as
JSON for results/tests/vtk3_export.rs.

Usage: python3 vtk3_readback.py DIR. Exit 77 (with the reason) when `vtk` cannot be imported.
"""

import json
import math
import os
import sys
import xml.etree.ElementTree as ET

try:
    from vtkmodules.vtkIOXML import vtkXMLImageDataReader, vtkXMLUnstructuredGridReader
except ImportError as e:  # pragma: no cover - depends on the machine
    print(f"SKIP: the Python `vtk` package is not importable ({e})")
    sys.exit(77)


def num(x):
    return None if math.isnan(x) else x


def arrays(data):
    out = {}
    for i in range(data.GetNumberOfArrays()):
        a = data.GetArray(i)
        nc = a.GetNumberOfComponents()
        vals = [num(a.GetComponent(t, c)) for t in range(a.GetNumberOfTuples()) for c in range(nc)]
        out[a.GetName()] = {"components": nc, "values": vals}
    return out


def read(reader, path):
    reader.SetFileName(path)
    reader.Update()
    if reader.GetErrorCode() != 0:
        raise SystemExit(f"VTK could not read {path}: error code {reader.GetErrorCode()}")
    return reader.GetOutput()


def collection(d, name):
    path = os.path.join(d, name)
    if not os.path.exists(path):
        return []
    root = ET.parse(path).getroot()
    return [
        {"time": float(ds.get("timestep")), "file": ds.get("file")}
        for ds in root.find("Collection").findall("DataSet")
    ]


def main():
    d = sys.argv[1]
    out = {"volumes": [], "particles": []}
    for e in collection(d, "volumes.pvd"):
        img = read(vtkXMLImageDataReader(), os.path.join(d, e["file"]))
        out["volumes"].append({
            "time": e["time"],
            "dimensions": list(img.GetDimensions()),
            "origin": list(img.GetOrigin()),
            "spacing": list(img.GetSpacing()),
            "point": arrays(img.GetPointData()),
        })
    for e in collection(d, "particles.pvd"):
        ug = read(vtkXMLUnstructuredGridReader(), os.path.join(d, e["file"]))
        pts = ug.GetPoints()
        out["particles"].append({
            "time": e["time"],
            "points": [list(pts.GetPoint(i)) for i in range(ug.GetNumberOfPoints())],
            "cells": ug.GetNumberOfCells(),
            "point": arrays(ug.GetPointData()),
        })
    json.dump(out, sys.stdout)


main()
