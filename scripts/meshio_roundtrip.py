#!/usr/bin/env python3
"""Check that meshio reads back exactly what `meshes::write` wrote.

Usage: meshio_roundtrip.py OUTDIR [--surface RUNDIR]

OUTDIR is what `cargo run --release -p meshes --example write_formats -- OUTDIR` produced:
mesh files in every format, a `.pvd`, and `expected.json` with the exact nodes, triangles and
fields. For every mesh file this script compares, bit for bit (so -0.0 and subnormals count):
the coordinates, the triangles (one `triangle` cell block), and every point and cell field by
name, with vectors as (n, 3) arrays. Readers may add their own bookkeeping arrays (Gmsh:
`gmsh:dim_tags`, `gmsh:geometrical`, ...); names starting with `gmsh:` are ignored, any other
extra array is an error. The `.pvd` is parsed as XML and its entries (time, file) compared;
each listed file must exist and have been read above.

With --surface, RUNDIR is a finished `memstab run` of a `surface` analysis: its
`surface.vtu` is read with meshio and compared, bit for bit, with its `surface.json`: the
points (a, b, measure) of every path vertex then of every critical-line point, the triangles
and the critical lines' segments as the `triangle` and `line` cell blocks, and the point data
(`index`, `path`, `critical_line` as integers, every measure).

Exits 1 with one line per mismatch, else prints
"meshio round-trip: N files, M checks passed".
"""

import json
import os
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import meshio
import numpy as np

IGNORED_PREFIXES = ("gmsh:",)


class Checker:
    def __init__(self):
        self.passed = 0
        self.failures = []

    def check(self, ok, what):
        if ok:
            self.passed += 1
        else:
            self.failures.append(what)
        return ok


def bits(a):
    """float64 array as its bit patterns, so -0.0 != 0.0 and NaN == NaN compare as stored."""
    return np.ascontiguousarray(np.asarray(a, dtype=np.float64)).view(np.uint64)


def describe_diff(got, want):
    got = np.asarray(got, dtype=np.float64)
    want = np.asarray(want, dtype=np.float64)
    if got.shape != want.shape:
        return f"shape {got.shape}, expected {want.shape}"
    bad = np.argwhere(bits(got) != bits(want))
    i = tuple(int(k) for k in bad[0])
    return (
        f"{len(bad)} entries differ, first at {list(i)}: "
        f"got {float(got[i])!r}, expected {float(want[i])!r}"
    )


def same_floats(c, label, got, want):
    got = np.asarray(got)
    want = np.asarray(want, dtype=np.float64)
    if not c.check(
        got.dtype.kind == "f", f"{label}: dtype {got.dtype}, expected floating point"
    ):
        return
    ok = got.shape == want.shape and np.array_equal(bits(got), bits(want))
    if not ok:
        c.check(False, f"{label}: {describe_diff(got, want)}")
    else:
        c.check(True, label)


def check_mesh(c, name, mesh, expected):
    same_floats(c, f"{name}: points", mesh.points, expected["nodes"])

    want_tri = np.asarray(expected["triangles"], dtype=np.int64)
    types = [block.type for block in mesh.cells]
    if c.check(types == ["triangle"], f"{name}: cell blocks {types}, expected ['triangle']"):
        got_tri = np.asarray(mesh.cells[0].data)
        c.check(
            got_tri.shape == want_tri.shape and np.array_equal(got_tri, want_tri),
            f"{name}: triangles differ (shape {got_tri.shape}, expected {want_tri.shape})",
        )

    for kind, got_all, want_all in [
        ("point", mesh.point_data, expected["point_data"]),
        ("cell", mesh.cell_data, expected["cell_data"]),
    ]:
        extra = sorted(
            k for k in got_all if k not in want_all and not k.startswith(IGNORED_PREFIXES)
        )
        c.check(not extra, f"{name}: unexpected {kind} data {extra}")
        for field, want in want_all.items():
            label = f"{name}: {kind} data {field!r}"
            if not c.check(
                field in got_all,
                f"{label} missing (found {sorted(got_all)})",
            ):
                continue
            got = got_all[field]
            if kind == "cell":
                # meshio keeps one array per cell block
                if not c.check(
                    len(got) == 1, f"{label}: {len(got)} cell blocks, expected 1"
                ):
                    continue
                got = got[0]
            same_floats(c, label, got, want)


def check_pvd(c, outdir, pvd, read_files):
    path = outdir / pvd["file"]
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as e:
        c.check(False, f"{pvd['file']}: not readable as XML: {e}")
        return
    c.check(
        root.tag == "VTKFile" and root.get("type") == "Collection",
        f"{pvd['file']}: root <{root.tag} type={root.get('type')!r}>, "
        "expected <VTKFile type='Collection'>",
    )
    datasets = root.findall("./Collection/DataSet")
    got = [(float(d.get("timestep")), d.get("file")) for d in datasets]
    want = [(e["time"], e["file"]) for e in pvd["entries"]]
    c.check(got == want, f"{pvd['file']}: entries {got}, expected {want}")
    for _, f in got:
        if c.check((outdir / f).is_file(), f"{pvd['file']}: lists {f}, which does not exist"):
            c.check(
                os.path.normpath(f) in read_files,
                f"{pvd['file']}: lists {f}, which was not among the files checked",
            )


def check_surface(c, rundir):
    """surface.vtu of a surface run against its surface.json."""
    report = json.loads((rundir / "surface.json").read_text())
    try:
        mesh = meshio.read(rundir / "surface.vtu")
    except Exception as e:  # any reader failure is a failed check, with its message
        c.check(False, f"surface.vtu: meshio.read failed: {type(e).__name__}: {e}")
        return
    c.check(True, "surface.vtu: read")
    a = report["parameters"].index(report["a"])
    b = report["parameters"].index(report["b"])
    m = report["measures"].index(report["measure"])
    vertices = [v for p in report["paths"] for v in p["vertices"]]
    line_points = [q for line in report["lines"] for q in line["points"]]
    every = vertices + line_points
    same_floats(
        c,
        "surface.vtu: points",
        mesh.points,
        [[v["parameters"][a], v["parameters"][b], v["measures"][m]] for v in every],
    )
    segments, first = [], len(vertices)
    for line in report["lines"]:
        n = len(line["points"])
        segments += [[first + i - 1, first + i] for i in range(1, n)]
        first += n
    want = [("triangle", report["triangles"])] + ([("line", segments)] if segments else [])
    got = [(block.type, np.asarray(block.data).tolist()) for block in mesh.cells]
    c.check(
        [t for t, _ in got] == [t for t, _ in want],
        f"surface.vtu: cell blocks {[t for t, _ in got]}, expected {[t for t, _ in want]}",
    )
    for (gt, gd), (_, wd) in zip(got, want):
        c.check(gd == wd, f"surface.vtu: {gt} cells differ from surface.json")
    n_line = len(line_points)
    paths = [j for j, p in enumerate(report["paths"]) for _ in p["vertices"]]
    lines = [k for k, line in enumerate(report["lines"]) for _ in line["points"]]
    integers = {
        "index": [-1 if v["index"] is None else v["index"] for v in vertices] + [-1] * n_line,
        "path": paths + [-1] * n_line,
        "critical_line": [-1] * len(vertices) + lines,
    }
    for name, want in integers.items():
        got = mesh.point_data.get(name)
        if not c.check(got is not None, f"surface.vtu: point data {name!r} missing"):
            continue
        got = np.asarray(got)
        c.check(
            got.dtype.kind == "i" and got.tolist() == want,
            f"surface.vtu: point data {name!r} differs from surface.json",
        )
    for k, name in enumerate(report["measures"]):
        got = mesh.point_data.get(name)
        if c.check(got is not None, f"surface.vtu: point data {name!r} missing"):
            same_floats(
                c, f"surface.vtu: point data {name!r}", got, [v["measures"][k] for v in every]
            )
    extra = sorted(set(mesh.point_data) - set(integers) - set(report["measures"]))
    c.check(not extra, f"surface.vtu: unexpected point data {extra}")


def main():
    args = sys.argv[1:]
    surface = None
    if len(args) == 3 and args[1] == "--surface":
        surface = Path(args[2]).resolve()
        args = args[:1]
    if len(args) != 1:
        sys.exit(f"usage: {sys.argv[0]} OUTDIR [--surface RUNDIR]")
    outdir = Path(args[0]).resolve()
    expected = json.loads((outdir / "expected.json").read_text())
    c = Checker()
    read_files = set()
    # meshio resolves XDMF Format="Binary" side files against the current directory, not the
    # .xdmf's directory: read from OUTDIR.
    os.chdir(outdir)
    for entry in expected["files"]:
        name = entry["file"]
        try:
            mesh = meshio.read(name)
        except Exception as e:  # any reader failure is a failed check, with its message
            c.check(False, f"{name}: meshio.read failed: {type(e).__name__}: {e}")
            continue
        c.check(True, f"{name}: read")
        read_files.add(os.path.normpath(name))
        check_mesh(c, name, mesh, expected)
    check_pvd(c, outdir, expected["pvd"], read_files)
    if surface is not None:
        check_surface(c, surface)

    if c.failures:
        for f in c.failures:
            print(f"MISMATCH {f}", file=sys.stderr)
        print(
            f"meshio round-trip FAILED: {len(c.failures)} failed, {c.passed} passed "
            f"(meshio {meshio.__version__}, numpy {np.__version__}; files in {outdir})",
            file=sys.stderr,
        )
        sys.exit(1)
    print(
        f"meshio round-trip: {len(expected['files'])} files, {c.passed} checks passed "
        f"(meshio {meshio.__version__}, numpy {np.__version__})"
    )


if __name__ == "__main__":
    main()
