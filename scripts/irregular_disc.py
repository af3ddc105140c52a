"""Writes an irregular disc mesh: no symmetry at all, for comparing a symmetric mesh's double
points with what a mesh without symmetry makes of them.

The nodes are a jittered hexagonal lattice inside the disc (seeded, so the file is
reproducible) and equally spaced rim nodes; the triangles are their Delaunay triangulation
(matplotlib's), oriented with normals along +z. The file is VTK XML (ascii) with the rim as
the node set `set_rim`, which `[mesh] generator = "file"` reads.

Usage: python scripts/irregular_disc.py OUT.vtu [RADIUS RIM_NODES SPACING SEED]
  defaults: 1.1 112 0.0695 7 (957 nodes and 1 800 triangles, about the size of the
  1 792-triangle C7v disc)
"""

import sys

import numpy as np
from matplotlib.tri import Triangulation


def irregular_disc(radius, rim_nodes, spacing, seed):
    rng = np.random.default_rng(seed)
    theta = 2 * np.pi * (np.arange(rim_nodes) + 0.5 * rng.random()) / rim_nodes
    rim = np.column_stack([radius * np.cos(theta), radius * np.sin(theta)])
    n = int(np.ceil(radius / spacing)) + 1
    i, j = np.meshgrid(np.arange(-n, n + 1), np.arange(-n, n + 1))
    x = spacing * (i + 0.5 * (j % 2))
    y = spacing * (np.sqrt(3) / 2) * j
    lattice = np.column_stack([x.ravel(), y.ravel()])
    lattice += spacing * 0.3 * (rng.random(lattice.shape) - 0.5)
    inside = np.hypot(lattice[:, 0], lattice[:, 1]) < radius - 0.6 * spacing
    points = np.vstack([lattice[inside], rim])
    tri = Triangulation(points[:, 0], points[:, 1]).triangles
    a, b, c = points[tri[:, 0]], points[tri[:, 1]], points[tri[:, 2]]
    area = 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))
    tri[area < 0] = tri[area < 0][:, [0, 2, 1]]
    if np.abs(area).min() < 1e-3 * spacing**2:
        sys.exit("a degenerate triangle: choose another seed")
    on_rim = np.zeros(len(points), dtype=int)
    on_rim[len(points) - rim_nodes:] = 1
    return points, tri, on_rim


def write_vtu(path, points, tri, on_rim):
    def ints(v):
        return " ".join(str(int(k)) for k in v)

    xyz = " ".join(f"{x:.17g} {y:.17g} 0" for x, y in points)
    with open(path, "w") as f:
        f.write(
            '<?xml version="1.0"?>\n'
            '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian">\n'
            "<UnstructuredGrid>\n"
            f'<Piece NumberOfPoints="{len(points)}" NumberOfCells="{len(tri)}">\n'
            "<PointData>\n"
            f'<DataArray type="Int32" Name="set_rim" format="ascii">{ints(on_rim)}</DataArray>\n'
            "</PointData>\n"
            f'<Points>\n<DataArray type="Float64" NumberOfComponents="3" format="ascii">{xyz}'
            "</DataArray>\n</Points>\n"
            "<Cells>\n"
            f'<DataArray type="Int64" Name="connectivity" format="ascii">{ints(tri.ravel())}'
            "</DataArray>\n"
            f'<DataArray type="Int64" Name="offsets" format="ascii">'
            f"{ints(3 * np.arange(1, len(tri) + 1))}</DataArray>\n"
            f'<DataArray type="UInt8" Name="types" format="ascii">{ints([5] * len(tri))}'
            "</DataArray>\n"
            "</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n"
        )


if __name__ == "__main__":
    if len(sys.argv) not in (2, 6):
        sys.exit(__doc__)
    radius, rim_nodes, spacing, seed = (1.1, 112, 0.0695, 7)
    if len(sys.argv) == 6:
        radius, rim_nodes, spacing, seed = (
            float(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4]), int(sys.argv[5])
        )
    points, tri, on_rim = irregular_disc(radius, rim_nodes, spacing, seed)
    write_vtu(sys.argv[1], points, tri, on_rim)
    print(f"{sys.argv[1]}: {len(points)} nodes, {len(tri)} triangles, {rim_nodes} on the rim")
