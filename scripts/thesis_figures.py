"""Renders the figures of docs/thesis.md from memstab's own outputs.

Every figure is drawn from a run's files, never from numbers typed in here:

- a bifurcation diagram from path.csv (the control against a measure; solid where the index
  is 0, dashed where the state is unstable) with the critical points of critical.json, their
  labels stacked apart with leader lines and a cluster closer than a label's height zoomed in
  an inset;
- the critical modes from the critical_NN.vtu states (the mode's normal component at the
  deformed state, drawn on the reference membrane seen from above, one panel per point, titled
  with its kind, irrep, isotropy and m, with a colour bar);
- a critical curve from curve.csv with the events of critical.json;
- a solution surface from surface.vtu, coloured by the index, with its fold lines.

As in memstab's own figures, the legend has an entry for each line style and marker drawn and
for nothing else, and a caption line names each run's scene and mesh.

Usage: python scripts/thesis_figures.py MEMSTAB OUT_DIR FIGURE_DIR
  MEMSTAB     the memstab binary
  OUT_DIR     where the runs are written (one directory per scene)
  FIGURE_DIR  where the PNG figures are written (docs/figures in the repository)

scripts/thesis_figures.sh sets up the Python packages and calls this with the defaults.
"""

import csv
import json
import subprocess
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import meshio  # noqa: E402
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent


def run(memstab, scene, out, *extra):
    """Runs `memstab run SCENE --out OUT` (quietly) and returns OUT."""
    subprocess.run(
        [memstab, "run", str(ROOT / scene), "--out", str(out), "--quiet", *extra],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    return out


def read_csv(path):
    """The columns of a CSV file as a dict of name -> list of strings."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {k: [r[k] for r in rows] for k in rows[0]}


def numbers(column):
    return np.array([float(v) for v in column])


def caption(fig, run_dirs):
    """The caption line memstab's own figures have: each run's scene and mesh (generator,
    triangles, the mesh's group) and the group it is solved in, from its path.json."""
    parts = []
    for run_dir in run_dirs:
        if run_dir is None:
            continue
        r = json.loads((run_dir / "path.json").read_text())
        m = r["mesh"]
        parts.append(f"scene {r['scene']} · mesh: {m['generator']}, {m['elements']} triangles, "
                     f"group {m['group']} · solved in group {r['group']}")
    parts = list(dict.fromkeys(parts))
    fig.text(0.01, 0.005, "\n".join(parts), fontsize=6.5, color="0.3", ha="left", va="bottom")
    fig.tight_layout(rect=(0, 0.035 * len(parts), 1, 1))


# The markers of the critical points, as memstab's own figures draw them.
MARKERS = {"limit point": ("s", "limit point"), "other": ("X", "bifurcation point")}


def column_labels(ax, points, texts, fontsize=8, avoid=None):
    """Labels of `points` (data coordinates) that do not overlap: stacked in a column right of
    the points, or in one left of them for the labels that would run out of the axes or into
    the box `avoid` (display coordinates), at least a line apart, each joined to its point by
    a thin leader line."""
    if not points:
        return
    fig = ax.figure
    fig.canvas.draw()
    disp = ax.transData.transform(np.array(points, dtype=float))
    line = fontsize * fig.dpi / 72 * 1.35
    box = ax.get_window_extent()
    widths = [0.62 * fontsize * fig.dpi / 72 * len(t) for t in texts]
    right_x = disp[:, 0].max() + 24

    def fits_right(i):
        x0, x1, y = right_x, right_x + widths[i], disp[i, 1]
        if x1 > box.x1 - 4:
            return False
        return avoid is None or not (x0 < avoid.x1 and x1 > avoid.x0
                                     and avoid.y0 - line < y < avoid.y1 + line)

    sides = {True: [], False: []}
    for i in range(len(points)):
        sides[fits_right(i)].append(i)
    to_data = ax.transData.inverted()
    for right, group in sides.items():
        if not group:
            continue
        order = sorted(group, key=lambda i: -disp[i, 1])
        ys = []
        for i in order:
            y = disp[i, 1]
            if ys and ys[-1] - y < line:
                y = ys[-1] - line
            ys.append(y)
        # Shift the column up as a whole if it ran out of the bottom of the axes.
        low = box.y0 + line
        if ys[-1] < low:
            ys = [y + (low - ys[-1]) for y in ys]
        x = right_x if right else disp[group, 0].min() - 24
        for i, y in zip(order, ys):
            ax.annotate(
                texts[i], points[i], xytext=tuple(to_data.transform((x, y))),
                textcoords="data", fontsize=fontsize, va="center",
                ha="left" if right else "right",
                arrowprops=dict(arrowstyle="-", color="0.45", lw=0.6, shrinkA=0, shrinkB=3),
            )


def clusters(ax, points, gap):
    """Groups of points (indices) closer than `gap` display pixels to another of the group;
    only groups of two or more."""
    disp = ax.transData.transform(np.array(points, dtype=float)) if points else []
    group = list(range(len(points)))

    def root(i):
        while group[i] != i:
            i = group[i]
        return i

    for i in range(len(points)):
        for j in range(i):
            if np.hypot(*(disp[i] - disp[j])) < gap:
                group[root(i)] = root(j)
    out = {}
    for i in range(len(points)):
        out.setdefault(root(i), []).append(i)
    return [g for g in out.values() if len(g) > 1]


def path_figure(runs, x, y, title, file, xlabel=None, ylabel=None):
    """Paths in the (x, y) plane, one colour per (run directory, label), solid where the index
    is 0 and dashed where it is positive, with their critical points marked and labelled by
    irrep (and wave number m where the scene has one); a cluster of critical points closer
    than a label's height is drawn again, zoomed, in an inset where its labels go."""
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    kinds = set()
    pieces = []  # (xs, ys, style, colour)
    marks = []  # (x, y, kind, text)
    for n, (run_dir, label) in enumerate(runs):
        colour = f"C{n}"
        cols = read_csv(run_dir / "path.csv")
        xs, ys = numbers(cols[x]), numbers(cols[y])
        index = numbers(cols["index"]).astype(int)
        start = 0
        styles = set()
        for i in range(1, len(xs) + 1):
            if i == len(xs) or index[i] != index[start]:
                style = "-" if index[start] == 0 else "--"
                styles.add(style)
                # Each run of one index, joined to the next point so the line has no gaps.
                stop = min(i + 1, len(xs))
                pieces.append((xs[start:stop], ys[start:stop], style, colour))
                start = i
        # Legend entries for the styles drawn only.
        if "-" in styles:
            ax.plot([], [], "-", color=colour, label=f"{label}: stable (index 0)")
        if "--" in styles:
            ax.plot([], [], "--", color=colour, label=f"{label}: unstable (index > 0)")
        critical = json.loads((run_dir / "critical.json").read_text())
        for c in (p for p in critical if not p.get("curve")):
            px = c["parameters"].get(x, c["measures"].get(x))
            py = c["parameters"].get(y, c["measures"].get(y))
            kind = "limit point" if c["kind"] == "limit point" else "other"
            kinds.add(kind)
            m = f", m = {c['m']}" if c.get("m") is not None else ""
            marks.append((px, py, kind, f"{c['irrep']}{m}"))

    def draw(axes):
        for xs, ys, style, colour in pieces:
            axes.plot(xs, ys, style, color=colour, lw=1.6)
        for px, py, kind, _ in marks:
            axes.plot(px, py, MARKERS[kind][0], color="k", ms=5)

    draw(ax)
    for kind in sorted(kinds):
        ax.plot([], [], MARKERS[kind][0], color="k", ms=5, label=MARKERS[kind][1])
    ax.set_xlabel(xlabel or x)
    ax.set_ylabel(ylabel or y)
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    caption(fig, [d for d, _ in runs])
    legend = ax.legend(fontsize=8, loc="best")
    legend.set_zorder(1)  # under the labels
    fig.canvas.draw()
    points = [(m[0], m[1]) for m in marks]
    label_h = 8 * fig.dpi / 72 * 1.2
    cluster = max(clusters(ax, points, label_h), key=len, default=[])
    inset = None
    if cluster:
        # The inset in the corner of the axes that holds the fewest line points and not the
        # legend.
        allx = np.concatenate([p[0] for p in pieces])
        ally = np.concatenate([p[1] for p in pieces])
        frac = ax.transAxes.inverted().transform(ax.transData.transform(np.c_[allx, ally]))
        leg = legend.get_window_extent().transformed(ax.transAxes.inverted())
        best = None
        for cx, cy in ((0.58, 0.56), (0.05, 0.56), (0.58, 0.06), (0.05, 0.06)):
            w, h = 0.38, 0.38
            inside = ((frac[:, 0] > cx) & (frac[:, 0] < cx + w)
                      & (frac[:, 1] > cy) & (frac[:, 1] < cy + h)).sum()
            overlaps = not (leg.x1 < cx or leg.x0 > cx + w or leg.y1 < cy or leg.y0 > cy + h)
            cfrac = ax.transAxes.inverted().transform(
                ax.transData.transform(np.array([points[i] for i in cluster])))
            covers = ((cfrac[:, 0] > cx) & (cfrac[:, 0] < cx + w)
                      & (cfrac[:, 1] > cy) & (cfrac[:, 1] < cy + h)).any()
            cost = (overlaps or covers, inside)
            if best is None or cost < best[0]:
                best = (cost, (cx, cy, w, h))
        inset = ax.inset_axes(best[1])
        draw(inset)
        cxs = [points[i][0] for i in cluster]
        cys = [points[i][1] for i in cluster]
        spanx = (max(cxs) - min(cxs)) or abs(np.ptp(allx)) * 0.01
        spany = (max(cys) - min(cys)) or abs(np.ptp(ally)) * 0.01
        inset.set_xlim(min(cxs) - 0.8 * spanx, max(cxs) + 1.6 * spanx)
        inset.set_ylim(min(cys) - 0.8 * spany, max(cys) + 0.8 * spany)
        inset.tick_params(labelsize=6)
        inset.grid(alpha=0.3)
        ax.indicate_inset_zoom(inset, edgecolor="0.4")
        column_labels(inset, [points[i] for i in cluster], [marks[i][3] for i in cluster], 7)
    rest = [i for i in range(len(marks)) if i not in cluster]
    avoid = inset.get_tightbbox() if inset is not None else None
    column_labels(ax, [points[i] for i in rest], [marks[i][3] for i in rest], avoid=avoid)
    fig.savefig(file, dpi=130)
    plt.close(fig)


def mode_figure(run_dir, title, file, limit=6):
    """The critical modes of a run: the normal component of each mode at the deformed state,
    drawn on the reference membrane seen from above (red and blue: outward and inward)."""
    report = json.loads((run_dir / "path.json").read_text())
    saved = [s for s in report["saved"] if s["file"].startswith("critical_")][:limit]
    # critical_NN.vtu is the NN-th critical point of critical.json.
    points = [c for c in json.loads((run_dir / "critical.json").read_text()) if not c.get("curve")]
    control = report["control"]
    cols = min(len(saved), 3)
    rows = (len(saved) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(3.0 * cols, 3.5 * rows), squeeze=False)
    for ax in axes.flat:
        ax.set_axis_off()
    for ax, s in zip(axes.flat, saved):
        mesh = meshio.read(run_dir / s["file"])
        tri = mesh.cells_dict["triangle"]
        mode = mesh.point_data["critical_mode"]
        normal = mesh.point_data["normal"]
        w = np.einsum("ij,ij->i", mode, normal)
        scale = np.abs(w).max() or 1.0
        # The reference membrane: a bulge that overhangs its rim would hide itself from above.
        p = mesh.points - mesh.point_data["displacement"]
        image = ax.tripcolor(
            p[:, 0], p[:, 1], tri, w / scale, cmap="RdBu_r", vmin=-1, vmax=1,
            shading="gouraud",
        )
        ax.set_aspect("equal")
        c = points[int(s["file"][len("critical_"):-len(".vtu")]) - 1]
        m = f", m = {c['m']}" if c.get("m") is not None else ""
        ax.set_title(f"{c['kind']}\n{c['irrep']}, isotropy {c['isotropy']}{m}\n"
                     f"{control} = {s['control']:.4f}", fontsize=8)
    bar = fig.colorbar(image, ax=axes.ravel().tolist(), shrink=0.8, ticks=[-1, 0, 1])
    bar.set_label("normal component w / max|w|\n(+: outward, −: inward)", fontsize=8)
    fig.suptitle(title, fontsize=10)
    caption(fig, [run_dir])
    # The colour bar takes its room from the panels; tight_layout would undo it.
    fig.subplots_adjust(right=0.8, hspace=0.55, top=1 - 1.0 / (3.5 * rows))
    fig.savefig(file, dpi=130)
    plt.close(fig)


def curve_figure(runs, x, y, title, file):
    """Critical curves in (x, y), one per run directory, with their events (hilltops, cusps,
    irrep changes) marked, and labelled on the first curve."""
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    events_drawn = False
    labelled = []
    for n, run_dir in enumerate(runs):
        cols = read_csv(run_dir / "curve.csv")
        ax.plot(numbers(cols[x]), numbers(cols[y]), "-", color=f"C{n}", lw=1.6,
                label=f"critical curve of the {cols['irrep'][0]} block")
        critical = json.loads((run_dir / "critical.json").read_text())
        events = (c for c in critical if c.get("curve") and c["kind"] not in ("start", "end"))
        for e in events:
            px, py = e["parameters"][x], e["parameters"][y]
            ax.plot(px, py, "o", color="C3", ms=5)
            events_drawn = True
            if n > 0:
                continue  # the same points as the first curve's: labelled once
            what = f"{e['kind']} with {e['irrep']}" if e.get("irrep") else e["kind"]
            labelled.append(((px, py), what))
    if events_drawn:
        ax.plot([], [], "o", color="C3", ms=5, label="event (hilltop, cusp, irrep change)")
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8, loc="best")
    ax.grid(alpha=0.3)
    caption(fig, runs)
    column_labels(ax, [p for p, _ in labelled], [t for _, t in labelled])
    fig.savefig(file, dpi=130)
    plt.close(fig)


def surface_figure(run_dir, xlabel, ylabel, zlabel, title, file):
    """A solution surface from surface.vtu: its triangles in (a, b, measure), coloured by
    the index (blue where stable, orange where unstable), with its critical lines in black."""
    import meshio

    surface = meshio.read(run_dir / "surface.vtu")
    x, y, z = surface.points.T
    index = surface.point_data["index"]
    fig = plt.figure(figsize=(6.4, 5.0))
    ax = fig.add_subplot(projection="3d")
    for block in surface.cells:
        if block.type == "triangle":
            tri = block.data
            stable = index[tri].max(axis=1) == 0
            for mask, colour, label in ((stable, "C0", "stable (index 0)"),
                                        (~stable, "C1", "unstable (index > 0)")):
                if mask.any():
                    ax.plot_trisurf(x, y, z, triangles=tri[mask], color=colour, alpha=0.55,
                                    linewidth=0.1, edgecolor="k", label=label)
        elif block.type == "line":
            for a, b in block.data:
                ax.plot([x[a], x[b]], [y[a], y[b]], [z[a], z[b]], "-", color="k", lw=1.8)
    ax.plot([], [], "-", color="k", lw=1.8, label="fold lines")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_zlabel(zlabel)
    ax.view_init(elev=22, azim=-58)
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8, loc="upper left")
    caption(fig, [run_dir])
    fig.savefig(file, dpi=130)
    plt.close(fig)


def variant(scene, out, name, *replacements):
    """A copy of a bundled scene with lines replaced ((old, new) pairs), written beside the
    runs as NAME.toml."""
    text = (ROOT / scene).read_text()
    for old, new in replacements:
        if old not in text:
            sys.exit(f"{scene}: no line {old!r} to replace")
        text = text.replace(old, new, 1)
    path = out / f"{name}.toml"
    path.write_text(text)
    return path


def main(memstab, out, figures):
    out.mkdir(parents=True, exist_ok=True)
    figures.mkdir(parents=True, exist_ok=True)

    below = run(memstab, "scenes/disc_fluid_below.toml", out / "disc_fluid_below")
    path_figure([(below, "C7v")], "max_displacement", "h",
                "Paper 1: the C7v disc pushed up by fluid from below (k = 0)",
                figures / "paper1_disc_below_path.png",
                xlabel="largest displacement / a", ylabel="level h / a")
    mode_figure(below, "Paper 1: critical modes of the disc from below (normal component)",
                figures / "paper1_disc_below_modes.png")

    irregular = run(memstab, "scenes/thesis/paper1_disc_irregular.toml", out / "disc_irregular")
    path_figure([(below, "C7v, 1 792 triangles"), (irregular, "irregular, 1 800 triangles")],
                "max_displacement", "h",
                "Paper 1: the disc from below on a symmetric and an irregular mesh",
                figures / "paper1_disc_irregular_path.png",
                xlabel="largest displacement / a", ylabel="level h / a")

    scene = "scenes/thesis/paper1_disc_limit_curve_k.toml"
    limit = run(memstab, scene, out / "disc_curve_k_limit")
    double = run(memstab, variant(scene, out, "disc_curve_k_e1", ('from = "limit"', 'from = "E1"')),
                 out / "disc_curve_k_e1")
    curve_figure([limit, double], "k", "h",
                 "Paper 1: the disc's limit point and first double point followed in k",
                 figures / "paper1_disc_limit_curve_k.png")

    fold = run(memstab, "scenes/thesis/paper2_gas_pressure_fold_f8.toml", out / "paper2_fold")
    curve_figure([fold], "V", "p",
                 "Paper 2: the gas pressure's maximum followed in the fluid volume",
                 figures / "paper2_gas_pressure_fold.png")

    surface = run(memstab, "scenes/thesis/paper2_solution_surface_f8.toml", out / "paper2_surface")
    surface_figure(surface, "gas over-pressure p", "fluid volume V", "stretch",
                   "Paper 2: the solution surface of the sphere on a plane",
                   figures / "paper2_solution_surface.png")

    cubic = run(memstab, "scenes/thesis/paper3_gas_fluid_squeeze.toml", out / "paper3_cubic")
    linear = run(memstab, "scenes/thesis/paper3_gas_fluid_squeeze_linear.toml",
                 out / "paper3_linear")
    path_figure([(cubic, "cubic penalty, κ = 1e3"), (linear, "linear penalty, κ = 1e3")],
                "volume", "d",
                "Paper 3: gas above fluid squeezed between two planes x = ±a",
                figures / "paper3_penalty_laws.png",
                xlabel="enclosed volume / R³", ylabel="plane offset d = −a")

    cap = run(memstab, "scenes/thesis/paper4_spinning_cap.toml", out / "paper4_c8v")
    path_figure([(cap, "C8v")], "max_displacement", "w2",
                "Paper 4: the filled cap spinning on the floor (C8v mesh)",
                figures / "paper4_spinning_cap_path.png",
                xlabel="largest displacement / R", ylabel="w2 (angular speed squared)")
    mode_figure(cap, "Paper 4: critical modes of the spinning cap (normal component)",
                figures / "paper4_spinning_cap_modes.png")

    scene = "scenes/thesis/paper4_hilltop_k.toml"
    b2 = run(memstab, scene, out / "paper4_hilltop_b2")
    b1 = run(memstab, variant(scene, out, "paper4_hilltop_b1", ('from = "B2"', 'from = "B1"')),
             out / "paper4_hilltop_b1")
    limit = run(memstab, variant(scene, out, "paper4_limit_k",
                                 ('from = "B2"', 'from = "limit"'), ("steps = 60", "steps = 80")),
                out / "paper4_limit_k")
    curve_figure([limit, b2, b1], "k", "w2",
                 "Paper 4: the limit curve's cusp, and the m = 4 pair's curves meeting it",
                 figures / "paper4_hilltop_k.png")


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    main(sys.argv[1], Path(sys.argv[2]), Path(sys.argv[3]))
