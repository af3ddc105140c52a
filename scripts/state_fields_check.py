#!/usr/bin/env python3
"""Read the states of a balloon run back with meshio and check their fields.

Usage: state_fields_check.py RUN_DIR

RUN_DIR is the output of `memstab run` on the balloon scene (scenes/balloon.toml, any
icosphere frequency): a Mooney-Rivlin sphere with mu H = 1, k = 0.1 and H = 0.01 (the
bundled scene's material) inflated by gas under pressure control. For every state that `path.pvd` and `events.pvd` list, the state's stretch
l (from path.csv, or the turning/critical point's own measures) gives the closed forms

    T = mu H (1 - l^-6)(1 + k l^2)/(1 + k)     (both principal tensions, force per length)
    h = H / l^2                                 (the current thickness)

and the script checks, per triangle, `tension_1` and `tension_2` against T to 5 % (a
faceted sphere: each triangle's stretch is the sphere's to the mesh's O(h^2) error), the
mean `thickness` against h to 2 %, `wrinkled` zero everywhere; per node that `normal` has
unit length and points out of the sphere, that `pressure` is the state's p, that
`displacement` is the position minus the reference; on critical states that
`critical_mode` has unit Euclidean norm; and that both collections parse as ParaView
collections whose every file exists and was read.

Then it opens the first critical state with pyvista (what a reader plots with) and checks
that it holds the triangles' `tension_1` and `tension_2` and the nodes' `displacement`, as
meshio read them. It also tries an off-screen screenshot of the tension field, in a child
process: rendering needs an OpenGL library of the system (Mesa), which a bare machine with
Python and pip only may lack, so a screenshot that cannot be made is reported and skipped,
never a failure; reading the file with pyvista is always checked.

Exits 1 with one line per failure, else prints "state fields: N states, M checks passed".
"""

import csv
import json
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import subprocess

import meshio
import numpy as np

MU_H, K, H = 1.0, 0.1, 0.01


def tension(l):
    return MU_H * (1.0 - l**-6) * (1.0 + K * l * l) / (1.0 + K)


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


def collection(c, path):
    root = ET.parse(path).getroot()
    c.check(
        root.tag == "VTKFile" and root.get("type") == "Collection",
        f"{path.name}: not a ParaView collection",
    )
    return [
        (float(d.get("timestep")), d.get("file"), d.get("name"))
        for d in root.findall("./Collection/DataSet")
    ]


def main():
    if len(sys.argv) != 2:
        sys.exit(f"usage: {sys.argv[0]} RUN_DIR")
    run = Path(sys.argv[1])
    report = json.loads((run / "path.json").read_text())
    with open(run / "path.csv", newline="") as f:
        rows = {int(r["step"]): r for r in csv.DictReader(f)}
    c = Checker()

    path_entries = collection(c, run / "path.pvd")
    event_entries = collection(c, run / "events.pvd")
    c.check(len(path_entries) > 0, "path.pvd lists no state")
    c.check(
        any(f.startswith("turning_") for _, f, _ in event_entries)
        and any(f.startswith("critical_") for _, f, _ in event_entries),
        f"events.pvd lists {[f for _, f, _ in event_entries]}: no turning or no critical state",
    )
    saved = {s["file"]: s for s in report["saved"]}
    listed = [f for _, f, _ in path_entries + event_entries]
    c.check(
        sorted(listed) == sorted(saved),
        f"the collections list {sorted(listed)}, path.json saved {sorted(saved)}",
    )
    # The turning and critical points' own stretch and pressure, in the order saved.
    turning = iter(report["turning_points"])
    critical = iter(report["critical"])

    reference = None
    for time, name, label in path_entries + event_entries:
        mesh = meshio.read(run / name)
        if name.startswith("turning_"):
            point = next(turning)
        elif name.startswith("critical_"):
            point = next(critical)
        else:
            point = None
        if point is None:
            row = rows[int(time)]
            l = float(row["stretch"])
            p = float(row["p"])
        else:
            # path.json holds turning and critical points by name.
            l = point["measures"]["stretch"]
            p = point["parameters"]["p"]
        t = tension(l)
        cd = {k: v[0] for k, v in mesh.cell_data.items()}
        pd = mesh.point_data
        for field in ("tension_1", "tension_2"):
            err = np.max(np.abs(cd[field] / t - 1.0))
            c.check(err < 0.05, f"{name}: {field} differs from T = {t} by {err:.3g} relative")
        mean_h = float(np.mean(cd["thickness"]))
        c.check(
            abs(mean_h / (H / l**2) - 1.0) < 0.02,
            f"{name}: mean thickness {mean_h}, closed form {H / l**2}",
        )
        c.check(np.all(cd["wrinkled"] == 0.0), f"{name}: wrinkled triangles on a taut balloon")
        n = pd["normal"]
        c.check(
            np.max(np.abs(np.linalg.norm(n, axis=1) - 1.0)) < 1e-12,
            f"{name}: normals not of unit length",
        )
        c.check(
            np.all(np.sum(n * mesh.points, axis=1) > 0.0),
            f"{name}: a normal points into the sphere",
        )
        c.check(
            np.max(np.abs(pd["pressure"] - p)) <= 1e-12 * abs(p),
            f"{name}: pressure {pd['pressure'][:3]}..., the state's p = {p}",
        )
        x0 = mesh.points - pd["displacement"]
        if reference is None:
            reference = x0
        c.check(
            np.max(np.abs(x0 - reference)) < 1e-12,
            f"{name}: position minus displacement is not the reference mesh",
        )
        if name.startswith("critical_"):
            norm = float(np.linalg.norm(pd["critical_mode"]))
            c.check(abs(norm - 1.0) < 1e-9, f"{name}: |critical_mode| = {norm}")
            c.check(
                label is not None and point["irrep"] in label,
                f"events.pvd names {name} {label!r}, its irrep is {point['irrep']}",
            )
    critical_files = [f for _, f, _ in event_entries if f.startswith("critical_")]
    if critical_files:
        pyvista_check(c, run / critical_files[0])

    if c.failures:
        for f in c.failures:
            print(f"FAIL {f}", file=sys.stderr)
        print(f"state fields FAILED: {len(c.failures)} failed, {c.passed} passed", file=sys.stderr)
        sys.exit(1)
    print(f"state fields: {len(listed)} states, {c.passed} checks passed")


SCREENSHOT = """
import sys
import pyvista as pv
pv.OFF_SCREEN = True
mesh = pv.read(sys.argv[1])
plotter = pv.Plotter(off_screen=True, window_size=(400, 300))
plotter.add_mesh(mesh, scalars="tension_1", preference="cell")
plotter.screenshot(sys.argv[2])
"""


def pyvista_check(c, vtu):
    """The state read with pyvista: its tension fields and displacement, as meshio read them."""
    import pyvista as pv

    mesh = pv.read(vtu)
    ref = meshio.read(vtu)
    c.check(mesh.n_points == len(ref.points), f"pyvista: {vtu.name} has {mesh.n_points} points")
    c.check(mesh.n_cells == len(ref.cells_dict["triangle"]), f"pyvista: {vtu.name}: cells")
    for field in ("tension_1", "tension_2"):
        ok = field in mesh.cell_data
        c.check(ok, f"pyvista: {vtu.name} has no cell field {field}")
        if ok:
            same = np.array_equal(np.asarray(mesh.cell_data[field]), ref.cell_data[field][0])
            c.check(same, f"pyvista: {vtu.name}: {field} differs from meshio's")
    ok = "displacement" in mesh.point_data
    c.check(ok, f"pyvista: {vtu.name} has no point field displacement")
    if ok:
        same = np.array_equal(np.asarray(mesh.point_data["displacement"]), ref.point_data["displacement"])
        c.check(same, f"pyvista: {vtu.name}: displacement differs from meshio's")
    # The screenshot, in a child process: without a system OpenGL the renderer may abort the
    # interpreter rather than raise.
    png = vtu.with_suffix(".png")
    try:
        done = subprocess.run(
            [sys.executable, "-c", SCREENSHOT, str(vtu), str(png)],
            capture_output=True,
            timeout=120,
        )
        rendered = done.returncode == 0 and png.is_file() and png.stat().st_size > 0
    except subprocess.TimeoutExpired:
        rendered = False
    if rendered:
        print(f"pyvista: off-screen screenshot of {vtu.name}'s tension_1 in {png.name}")
    else:
        print(f"pyvista: no off-screen rendering on this machine (no system OpenGL); {vtu.name} was read only")


if __name__ == "__main__":
    main()
