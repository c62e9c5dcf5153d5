#!/usr/bin/env python3
"""Check strike's VTK output with VTK's own XML reader.

    vtk_check.py FILE.vtp|FILE.pvtp|FILE.pvd [--points N] [--fields a,b,c] [--time T]
    vtk_check.py FILE.pvd --same OTHER.pvd
    vtk_check.py --png FILE.png [--size WxH] [--min-colours K]

A .vtp is opened with vtkXMLPolyDataReader, a .pvtp (a parallel run's snapshot: an index and
one piece per rank) with vtkXMLPPolyDataReader. A .pvd is parsed as XML; every referenced file
must exist (relative to the .pvd's folder) and is checked the same way. With --same, the two
series must list the same times, and each pair of snapshots hold the same points and point
data, bit for bit, as VTK's readers read them (a serial .vtp against a parallel .pvtp). Checks: the reader reports no
error, the point count (if --points), every named point-data array exists with one tuple per
point, all point-data and point values are finite, each point has one vertex cell, and the
FieldData TIME exists. With --png, the picture is read with vtkPNGReader and its size and
number of distinct colours are checked (a picture of one colour is an error). Prints "ok ..."
and exits 0, or prints the problem and exits 1.
"""
import argparse
import math
import os
import sys
import xml.etree.ElementTree as ET


class CheckError(Exception):
    pass


def check_vtp(path, points, fields, time=None):
    import vtk

    if not os.path.isfile(path):
        raise CheckError(f"{path}: no such file")
    parallel = path.endswith(".pvtp")
    reader = vtk.vtkXMLPPolyDataReader() if parallel else vtk.vtkXMLPolyDataReader()
    errors = []

    def on_error(obj, event):
        errors.append(event)

    reader.AddObserver("ErrorEvent", on_error)
    reader.GetExecutive().AddObserver("ErrorEvent", on_error)
    reader.SetFileName(path)
    if not reader.CanReadFile(path):
        raise CheckError(f"{path}: {reader.GetClassName()} cannot read this file")
    reader.Update()
    if errors or reader.GetErrorCode() != 0:
        raise CheckError(f"{path}: reader reported an error (code {reader.GetErrorCode()})")
    poly = reader.GetOutput()
    n = poly.GetNumberOfPoints()
    if points is not None and n != points:
        raise CheckError(f"{path}: {n} points, expected {points}")
    if poly.GetNumberOfVerts() != n:
        raise CheckError(f"{path}: {poly.GetNumberOfVerts()} vertex cells for {n} points")
    pts = poly.GetPoints()
    if n > 0:
        for i in range(n):
            if not all(math.isfinite(c) for c in pts.GetPoint(i)):
                raise CheckError(f"{path}: point {i} is not finite: {pts.GetPoint(i)}")
    pd = poly.GetPointData()
    for name in fields:
        arr = pd.GetArray(name)
        if arr is None:
            have = [pd.GetArrayName(k) for k in range(pd.GetNumberOfArrays())]
            raise CheckError(f"{path}: no point-data array `{name}` (have {have})")
        if arr.GetNumberOfTuples() != n:
            raise CheckError(
                f"{path}: `{name}` has {arr.GetNumberOfTuples()} tuples for {n} points")
    for k in range(pd.GetNumberOfArrays()):
        arr = pd.GetArray(k)
        nc = arr.GetNumberOfComponents()
        for i in range(arr.GetNumberOfTuples()):
            for c in range(nc):
                v = arr.GetComponent(i, c)
                if not math.isfinite(v):
                    raise CheckError(
                        f"{path}: `{arr.GetName()}` tuple {i} component {c} is {v}")
    fd = poly.GetFieldData()
    t = fd.GetArray("TIME") if fd is not None else None
    if t is None or t.GetNumberOfTuples() != 1:
        raise CheckError(f"{path}: no FieldData TIME with one value")
    tv = t.GetComponent(0, 0)
    if not math.isfinite(tv):
        raise CheckError(f"{path}: TIME is {tv}")
    if time is not None and tv != time:
        raise CheckError(f"{path}: TIME = {tv!r}, expected {time!r}")
    return n, tv


def check_pvd(path, points, fields):
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as e:
        raise CheckError(f"{path}: not readable XML: {e}")
    if root.tag != "VTKFile" or root.get("type") != "Collection":
        raise CheckError(f"{path}: not a VTKFile of type Collection")
    coll = root.find("Collection")
    if coll is None:
        raise CheckError(f"{path}: no <Collection>")
    sets = coll.findall("DataSet")
    if not sets:
        raise CheckError(f"{path}: empty collection")
    base = os.path.dirname(os.path.abspath(path))
    times = []
    for ds in sets:
        f = ds.get("file")
        ts = ds.get("timestep")
        if f is None or ts is None:
            raise CheckError(f"{path}: DataSet without file or timestep")
        t = float(ts)
        if times and t < times[-1]:
            raise CheckError(f"{path}: timesteps not increasing ({times[-1]} then {t})")
        times.append(t)
        _, tv = check_vtp(os.path.join(base, f), points, fields)
        if tv != t:
            raise CheckError(f"{path}: {f} has TIME {tv!r}, the collection says {t!r}")
    return len(sets)


def series(path):
    """The (time, file) entries of a .pvd, files as paths."""
    root = ET.parse(path).getroot()
    base = os.path.dirname(os.path.abspath(path))
    return [(float(ds.get("timestep")), os.path.join(base, ds.get("file")))
            for ds in root.find("Collection").findall("DataSet")]


def read_poly(path):
    import vtk

    parallel = path.endswith(".pvtp")
    reader = vtk.vtkXMLPPolyDataReader() if parallel else vtk.vtkXMLPolyDataReader()
    reader.SetFileName(path)
    reader.Update()
    return reader.GetOutput()


def check_same(a, b):
    """Every snapshot of series a holds the points and point data of b's, bit for bit."""
    from vtk.util.numpy_support import vtk_to_numpy

    sa, sb = series(a), series(b)
    if [t for t, _ in sa] != [t for t, _ in sb]:
        raise CheckError(f"{a} and {b} list different times: {sa} against {sb}")
    for (_, fa), (_, fb) in zip(sa, sb):
        pa, pb = read_poly(fa), read_poly(fb)
        if pa.GetNumberOfPoints() != pb.GetNumberOfPoints() or pa.GetNumberOfPoints() == 0:
            raise CheckError(
                f"{fa}: {pa.GetNumberOfPoints()} points, {fb}: {pb.GetNumberOfPoints()}")
        bits = lambda arr: vtk_to_numpy(arr).tobytes()
        if bits(pa.GetPoints().GetData()) != bits(pb.GetPoints().GetData()):
            raise CheckError(f"{fa} and {fb}: the points differ")
        da, db = pa.GetPointData(), pb.GetPointData()
        names = [da.GetArrayName(k) for k in range(da.GetNumberOfArrays())]
        if sorted(names) != sorted(db.GetArrayName(k) for k in range(db.GetNumberOfArrays())):
            raise CheckError(f"{fa} and {fb}: different point-data arrays")
        for name in names:
            if bits(da.GetArray(name)) != bits(db.GetArray(name)):
                raise CheckError(f"{fa} and {fb}: `{name}` differs")
    return len(sa)


def check_png(path, size, min_colours):
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
    import numpy as np

    if not os.path.isfile(path):
        raise CheckError(f"{path}: no such file")
    reader = vtk.vtkPNGReader()
    if not reader.CanReadFile(path):
        raise CheckError(f"{path}: not a PNG vtkPNGReader can read")
    reader.SetFileName(path)
    reader.Update()
    img = reader.GetOutput()
    w, h, _ = img.GetDimensions()
    if size is not None and (w, h) != size:
        raise CheckError(f"{path}: {w}x{h} pixels, expected {size[0]}x{size[1]}")
    px = vtk_to_numpy(img.GetPointData().GetScalars())
    px = px.reshape(w * h, -1)[:, :3]
    colours = len(np.unique(px, axis=0))
    if colours < min_colours:
        raise CheckError(f"{path}: {colours} distinct colours, expected at least {min_colours}")
    non_white = float(np.mean(np.any(px < 250, axis=1)))
    return w, h, colours, non_white


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("file")
    ap.add_argument("--points", type=int, default=None)
    ap.add_argument("--fields", default="")
    ap.add_argument("--time", type=float, default=None)
    ap.add_argument("--png", action="store_true", help="FILE is a PNG picture")
    ap.add_argument("--size", default=None, help="expected WxH of a PNG")
    ap.add_argument("--min-colours", type=int, default=2)
    ap.add_argument("--same", default=None, help="another .pvd whose snapshots must be equal")
    args = ap.parse_args()
    fields = [f for f in args.fields.split(",") if f]
    try:
        import vtk  # noqa: F401
    except ImportError:
        print("vtk_check: python package `vtk` missing; run .ci/setup_python.sh", file=sys.stderr)
        return 2
    try:
        if args.png:
            size = None
            if args.size:
                w, h = args.size.lower().split("x")
                size = (int(w), int(h))
            w, h, k, nw = check_png(args.file, size, args.min_colours)
            print(f"ok {args.file}: {w}x{h}, {k} colours, {nw:.3f} non-white")
        elif args.same:
            k = check_same(args.file, args.same)
            print(f"ok {args.file}: {k} snapshots the same as {args.same}")
        elif args.file.endswith(".pvd"):
            k = check_pvd(args.file, args.points, fields)
            print(f"ok {args.file}: {k} snapshots, points {args.points}, fields {','.join(fields)}")
        else:
            n, t = check_vtp(args.file, args.points, fields, args.time)
            print(f"ok {args.file}: {n} points, time {t!r}, fields {','.join(fields)}")
    except CheckError as e:
        print(f"vtk_check: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
