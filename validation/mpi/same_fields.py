#!/usr/bin/env python3
"""Reads two field snapshots with VTK's own readers (a .vti, or a .pvti and its pieces, as ParaView
opens them) and checks that they hold the same grid and the same density and velocity, bit for bit.

    pip install vtk numpy
    lbm-server run SCENE.toml --out one
    mpirun -np 4 lbm-server run SCENE.toml --out four
    python3 validation/mpi/same_fields.py one/fields/step000000012.vti four/fields/step000000012.pvti
"""
import sys

import vtk
from vtk.util.numpy_support import vtk_to_numpy


def read(path):
    reader = vtk.vtkXMLPImageDataReader() if path.endswith(".pvti") else vtk.vtkXMLImageDataReader()
    reader.SetFileName(path)
    reader.Update()
    data = reader.GetOutput()
    cells = data.GetCellData()
    grid = (data.GetDimensions(), data.GetOrigin(), data.GetSpacing())
    return grid, [vtk_to_numpy(cells.GetArray(name)) for name in ("density", "velocity")]


def main():
    (grid_a, a), (grid_b, b) = read(sys.argv[1]), read(sys.argv[2])
    if grid_a != grid_b:
        sys.exit(f"different grids: {grid_a} vs {grid_b}")
    for name, x, y in zip(("density", "velocity"), a, b):
        if x.tobytes() != y.tobytes():
            sys.exit(f"{name} differs")
    print(f"same grid {grid_a[0]} points and the same density and velocity, bit for bit")


if __name__ == "__main__":
    main()
