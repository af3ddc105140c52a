"""Renders the figures of docs/thesis.md from memstab's own outputs.

Every figure is drawn from a run's files, never from numbers typed in here:

- a bifurcation diagram from path.csv (the control against a measure; solid where the index
  is 0, dashed where the state is unstable) with the critical points of critical.json, their
  labels stacked apart with leader lines and a cluster closer than a label's height zoomed in
  an inset;
- the critical modes from the critical_NN.vtu states (the mode's normal component at the
  deformed state, drawn on the reference membrane seen from above, one panel per point, titled
  with its kind, irrep, isotropy and m, with a colour bar);
- a critical curve from curve.csv with the events of critical.json, the path that found it
  drawn across it solid where stable and dashed where not (which side of the curve is
  stable), and a panel of differences below when two curves nearly coincide;
- a solution surface from surface.vtu, coloured by the index, with its fold lines.

As in memstab's own figures, every axis is a dimensionless group with its scale named (read
from the layout memstab records in each run's SVG figures, so from the scene's units), the
legend has an entry for each line style and marker drawn and for nothing else, and a caption
line names each run's scene and mesh. Every figure is checked before it is written: no two
labels overlap, and none lies on the legend or (outside it) on the inset.

Usage: python scripts/thesis_figures.py MEMSTAB OUT_DIR FIGURE_DIR
  MEMSTAB     the memstab binary
  OUT_DIR     where the runs are written (one directory per scene)
  FIGURE_DIR  where the PNG figures are written (docs/figures in the repository)

scripts/thesis_figures.sh sets up the Python packages and calls this with the defaults.
"""

import csv
import html
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import matplotlib
import matplotlib.text

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


def scales(run_dir):
    """The dimensionless groups memstab's own figures of a run record in their layout: quantity
    -> (axis title, factor); a quantity the scene fixes no scale for maps to (its name, 1)."""
    out = {}
    for svg in sorted(run_dir.glob("*.svg")):
        m = re.search(r'<metadata id="memstab-layout">(.*?)</metadata>', svg.read_text(), re.S)
        if not m:
            continue
        for q in json.loads(html.unescape(m.group(1))).get("scales", []):
            scaled = q["label"] != q["quantity"] or q["factor"] != 1.0
            if scaled or q["quantity"] not in out:
                out[q["quantity"]] = (q["label"], q["factor"])
    return out


class Axes:
    """The dimensionless axis of quantity `q` over several runs: the title of the first run
    whose scene fixes its scale, and each run's own factor. A run whose scene fixes none (a
    parameter without a known scale) is drawn unscaled and `unscaled` names it."""

    def __init__(self, runs, q):
        self.q = q
        found = [scales(r).get(q, (q, 1.0)) for r in runs]
        self.factors = {str(r): f for r, (_, f) in zip(runs, found)}
        titled = [t for t, f in found if t != q or f != 1.0]
        self.title = titled[0] if titled else q
        self.unscaled = {str(r) for r, (t, f) in zip(runs, found) if titled and t == q and f == 1.0}

    def factor(self, run_dir):
        return self.factors[str(run_dir)]


def note_unscaled(label, run_dir, axes):
    """`label` with a note of the axes `run_dir` is drawn unscaled on."""
    names = [a.q for a in axes if str(run_dir) in a.unscaled]
    return f"{label} ({', '.join(names)} unscaled: no mesh radius)" if names else label


class Refused(Exception):
    """A figure [`check_labels`] refuses."""


def check_labels(fig, file):
    """Refuses a figure whose labels overlap each other, a legend, or (outside it) an inset:
    the boxes of every annotation, legend and inset as drawn. A refused figure is written as
    NAME.refused.png, for a look."""

    def refuse(why):
        if file is not None:
            fig.savefig(Path(file).with_suffix(".refused.png"), dpi=130)
        raise Refused(f"{file}: {why}")

    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    labels, legends, insets = [], [], []
    for ax in fig.axes:
        for t in ax.texts:
            if t.get_visible() and t.get_text():
                # The text's own box (an annotation's would include its leader line).
                box = matplotlib.text.Text.get_window_extent(t, renderer)
                labels.append((t.get_text(), ax, box))
        if ax.get_legend() is not None:
            legends.append(ax.get_legend().get_window_extent(renderer))
        for child in ax.child_axes:
            insets.append((child, child.get_tightbbox(renderer)))
    legends += [leg.get_window_extent(renderer) for leg in fig.legends]
    for i, (a, ax_a, box_a) in enumerate(labels):
        for b, _, box_b in labels[:i]:
            if box_a.overlaps(box_b):
                refuse(f"labels {a!r} and {b!r} overlap")
        for box in legends:
            if box_a.overlaps(box):
                refuse(f"label {a!r} lies on the legend")
        for inset, box in insets:
            if ax_a is not inset and box_a.overlaps(box):
                refuse(f"label {a!r} lies on the inset")


def caption(fig, run_dirs, legend_of=None):
    """The caption line memstab's own figures have: each run's scene and mesh (generator,
    triangles, the mesh's group) and the group it is solved in, from its path.json. With
    `legend_of` (axes), their legend goes above the caption, below the plots, where no label
    or data can run into it."""
    parts = []
    for run_dir in run_dirs:
        if run_dir is None:
            continue
        r = json.loads((run_dir / "path.json").read_text())
        m = r["mesh"]
        unit = "elements" if m["generator"] == "axisymmetric" else "triangles"
        parts.append(f"scene {r['scene']} · mesh: {m['generator']}, {m['elements']} {unit}, "
                     f"group {m['group']} · solved in group {r['group']}")
    parts = list(dict.fromkeys(parts))
    fig.text(0.01, 0.005, "\n".join(parts), fontsize=6.5, color="0.3", ha="left", va="bottom")
    bottom = 0.035 * len(parts)
    if legend_of is not None:
        handles, labels = legend_of.get_legend_handles_labels()
        legend = fig.legend(handles, labels, loc="lower center", bbox_to_anchor=(0.5, bottom),
                            ncol=2 if len(labels) > 3 and max(map(len, labels)) < 45 else 1,
                            fontsize=7.5, frameon=False)
        fig.canvas.draw()
        bottom += legend.get_window_extent().height / fig.bbox.height + 0.01
    fig.tight_layout(rect=(0, bottom, 1, 1))


# The markers of the critical points, as memstab's own figures draw them.
MARKERS = {"limit point": ("s", "limit point"), "other": ("X", "bifurcation point"),
           "unconverged": ("o", "not mesh-converged: no counterpart on the refined mesh")}


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


def path_figure(runs, x, y, title, file):
    """Paths in the (x, y) plane, one colour per (run directory, label), solid where the index
    is 0 and dashed where it is positive, with their critical points marked and labelled by
    irrep (and wave number m where the scene has one); a cluster of critical points closer
    than a label's height is drawn again, zoomed, in an inset where its labels go."""
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    kinds = set()
    pieces = []  # (xs, ys, style, colour)
    marks = []  # (x, y, kind, text)
    ax_x, ax_y = Axes([d for d, _ in runs], x), Axes([d for d, _ in runs], y)
    for n, (run_dir, label) in enumerate(runs):
        colour = f"C{n}"
        label = note_unscaled(label, run_dir, (ax_x, ax_y))
        fx, fy = ax_x.factor(run_dir), ax_y.factor(run_dir)
        cols = read_csv(run_dir / "path.csv")
        xs, ys = numbers(cols[x]) * fx, numbers(cols[y]) * fy
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
        # With the run's refinement (`--refine`), a point without a counterpart on the finer
        # mesh is drawn apart: not a result of the model, an artefact of the mesh.
        unconverged = set()
        if (run_dir / "refine.json").exists():
            refined = json.loads((run_dir / "refine.json").read_text())
            for r in refined["critical"]:
                if r["estimate"]["basis"] == "not-mesh-converged":
                    unconverged.update(r["points"])
        for number, c in enumerate((p for p in critical if not p.get("curve")), start=1):
            px = c["parameters"].get(x, c["measures"].get(x)) * fx
            py = c["parameters"].get(y, c["measures"].get(y)) * fy
            kind = "limit point" if c["kind"] == "limit point" else "other"
            if number in unconverged:
                kind = "unconverged"
            kinds.add(kind)
            m = f", m = {c['m']}" if c.get("m") is not None else ""
            marks.append((px, py, kind, f"{c['irrep']}{m}"))

    def draw(axes):
        for xs, ys, style, colour in pieces:
            axes.plot(xs, ys, style, color=colour, lw=1.6)
        for px, py, kind, _ in marks:
            hollow = kind == "unconverged"
            axes.plot(px, py, MARKERS[kind][0], color="0.45" if hollow else "k", ms=5,
                      mfc="none" if hollow else None)

    draw(ax)
    for kind in sorted(kinds):
        hollow = kind == "unconverged"
        ax.plot([], [], MARKERS[kind][0], color="0.45" if hollow else "k", ms=5,
                mfc="none" if hollow else None, label=MARKERS[kind][1])
    ax.set_xlabel(ax_x.title)
    ax.set_ylabel(ax_y.title)
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    caption(fig, [d for d, _ in runs], legend_of=ax)
    fig.canvas.draw()
    points = [(m[0], m[1]) for m in marks]
    label_h = 8 * fig.dpi / 72 * 1.2
    cluster = max(clusters(ax, points, label_h), key=len, default=[])
    inset = None
    if cluster:
        # The inset in the corner of the axes that holds the fewest line points and not the
        # cluster.
        allx = np.concatenate([p[0] for p in pieces])
        ally = np.concatenate([p[1] for p in pieces])
        frac = ax.transAxes.inverted().transform(ax.transData.transform(np.c_[allx, ally]))
        best = None
        for cx, cy in ((0.58, 0.56), (0.05, 0.56), (0.58, 0.06), (0.05, 0.06)):
            w, h = 0.38, 0.38
            inside = ((frac[:, 0] > cx) & (frac[:, 0] < cx + w)
                      & (frac[:, 1] > cy) & (frac[:, 1] < cy + h)).sum()
            cfrac = ax.transAxes.inverted().transform(
                ax.transData.transform(np.array([points[i] for i in cluster])))
            covers = ((cfrac[:, 0] > cx) & (cfrac[:, 0] < cx + w)
                      & (cfrac[:, 1] > cy) & (cfrac[:, 1] < cy + h)).any()
            cost = (covers, inside)
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
    check_labels(fig, file)
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


def single_valued(xs, ys):
    """(xs, ys) sorted by x if x rises or falls strictly along the curve, else None."""
    d = np.diff(xs)
    if len(xs) < 2 or not ((d > 0).all() or (d < 0).all()):
        return None
    order = np.argsort(xs)
    return xs[order], ys[order]


def near_pairs(curves, span, within=0.03):
    """Pairs (i, j) of curves, each a function of x, that overlap in x and differ there by
    less than `within` of the plot's vertical `span`: drawn as one line, they need a panel of
    their differences."""
    pairs = []
    for j in range(len(curves)):
        for i in range(j):
            a, b = single_valued(*curves[i]), single_valued(*curves[j])
            if a is None or b is None:
                continue
            lo, hi = max(a[0][0], b[0][0]), min(a[0][-1], b[0][-1])
            if hi <= lo:
                continue
            grid = np.linspace(lo, hi, 200)
            diff = np.interp(grid, *b) - np.interp(grid, *a)
            if np.abs(diff).max() < within * span:
                pairs.append((i, j, grid, diff))
    return pairs


def curve_figure(runs, x, y, title, file):
    """Critical curves in (x, y), one per run directory, with their events (hilltops, cusps,
    irrep changes) marked and labelled on the first curve; the path that found the first
    curve drawn across it (solid where stable, dashed where not), so that the stable side
    shows; a panel of differences below for curves that nearly coincide."""
    ax_x, ax_y = Axes(runs, x), Axes(runs, y)
    curves, names = [], []
    for run_dir in runs:
        cols = read_csv(run_dir / "curve.csv")
        curves.append((numbers(cols[x]) * ax_x.factor(run_dir),
                       numbers(cols[y]) * ax_y.factor(run_dir)))
        names.append(cols["irrep"][0])
    ally = np.concatenate([c[1] for c in curves])
    pairs = near_pairs(curves, np.ptp(ally))
    if pairs:
        fig, (ax, dax) = plt.subplots(2, 1, figsize=(6.4, 6.0), sharex=True,
                                      gridspec_kw={"height_ratios": [3, 1.3]})
    else:
        fig, ax = plt.subplots(figsize=(6.4, 4.6))
    events_drawn = False
    labelled = []
    for n, (run_dir, (cx, cy)) in enumerate(zip(runs, curves)):
        ax.plot(cx, cy, "-", color=f"C{n}", lw=1.6,
                label=f"critical curve of the {names[n]} block")
        critical = json.loads((run_dir / "critical.json").read_text())
        events = (c for c in critical if c.get("curve") and c["kind"] not in ("start", "end"))
        for e in events:
            px = e["parameters"][x] * ax_x.factor(run_dir)
            py = e["parameters"][y] * ax_y.factor(run_dir)
            ax.plot(px, py, "o", color="C3", ms=5)
            events_drawn = True
            if n > 0:
                continue  # the same points as the first curve's: labelled once
            what = f"{e['kind']} with {e['irrep']}" if e.get("irrep") else e["kind"]
            labelled.append(((px, py), what))
    if events_drawn:
        ax.plot([], [], "o", color="C3", ms=5, label="event (hilltop, cusp, irrep change)")
    # Which side is stable: the path that found the first curve's start, near the curves.
    first = runs[0]
    report = json.loads((first / "path.json").read_text())
    control = report["control"]
    held = y if control == x else x
    cols = read_csv(first / "path.csv")
    px = numbers(cols[x]) * ax_x.factor(first)
    py = numbers(cols[y]) * ax_y.factor(first)
    index = numbers(cols["index"]).astype(int)
    lo, hi = ally.min() - 0.1 * np.ptp(ally), ally.max() + 0.1 * np.ptp(ally)
    along = py if control == y else px
    if control == x:
        allx = np.concatenate([c[0] for c in curves])
        lo, hi = allx.min() - 0.1 * np.ptp(allx), allx.max() + 0.1 * np.ptp(allx)
    near = (along >= lo) & (along <= hi)
    value = float(cols[held][0])
    drawn = set()
    for stable in (True, False):
        mask = near & ((index == 0) == stable)
        # Each run of rows on one side, joined to the next row so the line has no gaps.
        for run in np.split(np.flatnonzero(mask), np.flatnonzero(np.diff(np.flatnonzero(mask)) > 1) + 1):
            if len(run) == 0:
                continue
            stop = min(run[-1] + 2, len(px))
            ax.plot(px[run[0]:stop], py[run[0]:stop], "-" if stable else "--", color="0.35", lw=1.3)
            drawn.add(stable)
    for stable in (True, False):
        if stable in drawn:
            word = "stable (index 0)" if stable else "unstable (index > 0)"
            ax.plot([], [], "-" if stable else "--", color="0.35", lw=1.3,
                    label=f"path in {control} at {held} = {value:g}: {word}")
    if json.loads((first / "curve.json").read_text())["kind"] == "limit point":
        ax.plot([], [], " ", label="at a limit curve the path turns back: its stable and "
                                   "unstable states lie on one side")
    ax.set_ylabel(ax_y.title)
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    if pairs:
        for i, j, grid, diff in pairs:
            dax.plot(grid, diff, "-", color=f"C{j}", lw=1.4,
                     label=f"{names[j]} curve − {names[i]} curve")
        dax.axhline(0, color="0.5", lw=0.8)
        dax.set_ylabel(f"difference in\n{ax_y.title.split(' (')[0]}", fontsize=9)
        dax.legend(fontsize=7.5, loc="best")
        dax.grid(alpha=0.3)
        dax.set_xlabel(ax_x.title)
    else:
        ax.set_xlabel(ax_x.title)
    caption(fig, runs, legend_of=ax)
    fig.canvas.draw()
    column_labels(ax, [p for p, _ in labelled], [t for _, t in labelled])
    check_labels(fig, file)
    fig.savefig(file, dpi=130)
    plt.close(fig)


def cusp_figure(runs, title, file):
    """The cusps of a limit curve followed in a third parameter (`type = "cusp-curve"`): left,
    each slice's fold line near its cusps in (second, control), coloured by the third
    parameter, the cusps marked; right, the pair's distance in the second parameter against
    the third on every run (one per mesh), with the pair's end and its error."""
    first = json.loads((runs[0][0] / "cusp_curve.json").read_text())
    c, s, t = (first["parameters"].index(first[k]) for k in ("control", "second", "third"))
    ax_x, ax_y = Axes([r for r, _ in runs], first["second"]), Axes([r for r, _ in runs], first["control"])
    fig, (ax, dax) = plt.subplots(1, 2, figsize=(10.0, 4.6), gridspec_kw={"width_ratios": [3, 2]})
    slices = [sl for sl in first["slices"] if "failure" not in sl and not sl["refined"]]
    thirds = [sl["third"] for sl in slices]
    cmap = plt.get_cmap("coolwarm")
    cusps = [(e["parameters"][s], e["parameters"][c]) for sl in slices for e in sl["cusps"]]
    xs, ys = [p[0] for p in cusps], [p[1] for p in cusps]
    wx, wy = max(xs) - min(xs), max(ys) - min(ys)
    fx, fy = ax_x.factor(runs[0][0]), ax_y.factor(runs[0][0])
    for sl in slices:
        colour = cmap((sl["third"] - min(thirds)) / (max(thirds) - min(thirds)))
        line = np.array(sl["line"])
        near = ((line[:, 1] > min(xs) - wx) & (line[:, 1] < max(xs) + wx)
                & (line[:, 0] > min(ys) - wy) & (line[:, 0] < max(ys) + wy))
        ax.plot(line[near, 1] * fx, line[near, 0] * fy, "-", color=colour, lw=1.5,
                label=f"fold line at {first['third']} = {sl['third']:g}")
        for e in sl["cusps"]:
            marker = "o" if e["extremum"] == "maximum" else "s"
            ax.plot(e["parameters"][s] * fx, e["parameters"][c] * fy, marker, color="k", ms=4)
    ax.plot([], [], "o", color="k", ms=4, label=f"cusp, maximum of {first['second']}")
    ax.plot([], [], "s", color="k", ms=4, label=f"cusp, minimum of {first['second']}")
    ax.set_xlabel(ax_x.title)
    ax.set_ylabel(ax_y.title)
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    for n, (run_dir, name) in enumerate(runs):
        report = json.loads((run_dir / "cusp_curve.json").read_text())
        pts = sorted((sl["third"], abs(sl["cusps"][0]["parameters"][s] - sl["cusps"][1]["parameters"][s]))
                     for sl in report["slices"] if len(sl["cusps"]) == 2)
        dax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", color=f"C{n}", ms=3, lw=1.2,
                 label=name)
        for end in report["ends"]:
            if end["estimate"] is not None:
                dax.axvline(end["estimate"], color=f"C{n}", ls="--", lw=1.0,
                            label=f"{name}: {end['kind']} at {first['third']} = "
                                  f"{end['estimate']:.5f} ± {end['error']:.1g}")
    dax.set_xlabel(first["third"])
    dax.set_ylabel(f"the pair's distance in {first['second']}")
    dax.set_title("the pair of cusps draws together and vanishes", fontsize=10)
    dax.grid(alpha=0.3)
    dax.legend(fontsize=7, loc="upper right")
    caption(fig, [r for r, _ in runs], legend_of=ax)
    check_labels(fig, file)
    fig.savefig(file, dpi=130)
    plt.close(fig)
def budget_cut(report):
    """Where memstab's surface.svg cuts a surface's paths (docs/scenes.md, `surface.svg`): where
    paths stopped on their step budget, every path's last monotone stretch in a is cut at the
    end of the first that stopped on it, when all run the same way and reach back to it.
    Returns (the value of a, the direction of the last stretches, how far past the cut each
    vertex lies, the number of paths cut) or None."""
    a = report["parameters"].index(report["a"])
    paths = report["paths"]
    if len(paths) < 2:
        return None
    stretches = []
    for p in paths:
        x = [v["parameters"][a] for v in p["vertices"]]
        steps = [d for d in np.diff(x) if d != 0]
        if not steps:
            return None
        direction = float(np.sign(steps[-1]))
        start = len(x) - 1
        while start > 0 and (x[start] - x[start - 1]) * direction >= 0:
            start -= 1
        stretches.append((start, direction, x))
    direction = stretches[0][1]
    if any(d != direction for _, d, _ in stretches):
        return None
    ends = [x[-1] * direction for (_, _, x), p in zip(stretches, paths)
            if "step budget" in p["stop"]]
    if not ends:
        return None
    at = min(ends) * direction
    if any(x[start] * direction > at * direction for start, _, x in stretches):
        return None
    past = []
    for start, _, x in stretches:
        past += [(v - at) * direction if k >= start else min((v - at) * direction, 0.0)
                 for k, v in enumerate(x)]
    cut = sum(1 for _, _, x in stretches if (x[-1] - at) * direction > 0)
    return (at, direction, np.array(past), cut) if cut else None


def clipped(points, triangles, past):
    """The triangles' parts where `past` <= 0 (linear along their edges), fanned into
    triangles: (their points, the triangles over them)."""
    points = [tuple(p) for p in points]
    out = []
    for tri in triangles:
        t = [past[i] for i in tri]
        kept = []
        for k in range(3):
            i, j = tri[k], tri[(k + 1) % 3]
            ti, tj = t[k], t[(k + 1) % 3]
            if ti <= 0:
                kept.append(i)
            if (ti <= 0) != (tj <= 0):
                f = ti / (ti - tj)
                points.append(tuple(np.add(points[i], f * np.subtract(points[j], points[i]))))
                kept.append(len(points) - 1)
        out += [(kept[0], kept[k], kept[k + 1]) for k in range(1, len(kept) - 1)]
    # Only the points the kept triangles use (the axes span what is drawn).
    used = sorted({i for t in out for i in t})
    number = {i: n for n, i in enumerate(used)}
    return (np.array([points[i] for i in used]).reshape(-1, 3),
            np.array([[number[i] for i in t] for t in out], dtype=int).reshape(-1, 3))


def surface_figure(run_dir, a, b, measure, title, file):
    """A solution surface from surface.vtu: its triangles in (a, b, measure), coloured by
    the index (blue where stable, orange where unstable), with its critical lines in black;
    where paths stopped on their step budget, cut where memstab's surface.svg cuts them."""
    import meshio

    surface = meshio.read(run_dir / "surface.vtu")
    report = json.loads((run_dir / "surface.json").read_text())
    axes = [Axes([run_dir], q) for q in (a, b, measure)]
    scale = np.array([axes[k].factor(run_dir) for k in range(3)])
    index = surface.point_data["index"]
    vertices = sum(len(p["vertices"]) for p in report["paths"])
    cut = budget_cut(report)
    past = np.zeros(len(surface.points))
    if cut:
        at, direction, past[:vertices], _ = cut
        # A critical point past the cut goes with its path: the vertex after it is cut away
        # and it lies beyond the cut in a.
        column = report["parameters"].index(report["a"])
        k = vertices
        for line in report["lines"]:
            for q in line["points"]:
                path = report["paths"][q["path"]]
                after = path["critical"][q["critical"]]["step"] + 1
                nxt = [path["first_vertex"] + i for i, v in enumerate(path["vertices"])
                       if v["step"] == after]
                if nxt and past[nxt[0]] > 0 and (q["parameters"][column] - at) * direction > 0:
                    past[k] = 1.0
                k += 1
    fig = plt.figure(figsize=(6.4, 5.0))
    ax = fig.add_subplot(projection="3d")
    for block in surface.cells:
        if block.type == "triangle":
            tri = block.data
            stable = index[tri].max(axis=1) == 0
            for mask, colour, label in ((stable, "C0", "stable (index 0)"),
                                        (~stable, "C1", "unstable (index > 0)")):
                if mask.any():
                    pts, tris = clipped(surface.points, tri[mask], past)
                    if len(tris) == 0:
                        continue
                    x, y, z = (pts[:, k] * scale[k] for k in range(3))
                    ax.plot_trisurf(x, y, z, triangles=tris, color=colour, alpha=0.55,
                                    linewidth=0.1, edgecolor="k", label=label)
        elif block.type == "line":
            x, y, z = (surface.points[:, k] * scale[k] for k in range(3))
            for p, q in block.data:
                if past[p] > 0 or past[q] > 0:
                    continue
                ax.plot([x[p], x[q]], [y[p], y[q]], [z[p], z[q]], "-", color="k", lw=1.8)
    ax.plot([], [], "-", color="k", lw=1.8, label="fold lines")
    if cut:
        ax.plot([], [], " ", label=f"{cut[3]} of {len(report['paths'])} paths cut at "
                                   f"{a} = {cut[0]:.5g} (step budget)")
    ax.set_xlabel(axes[0].title, fontsize=8)
    ax.set_ylabel(axes[1].title, fontsize=8)
    ax.set_zlabel(axes[2].title, fontsize=8)
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


def self_check():
    """The label check itself: it passes labels apart and refuses labels that overlap, one on
    the legend, and one on an inset (a check that cannot fail checks nothing)."""

    def figure(texts, legend=False, inset=False):
        fig, ax = plt.subplots(figsize=(4, 3))
        ax.plot([0, 1], [0, 1], label="line")
        for x, y, t in texts:
            ax.annotate(t, (x, y), xytext=(x, y), textcoords="data", fontsize=8)
        if legend:
            ax.legend(loc="upper left")
        if inset:
            ax.inset_axes((0.55, 0.05, 0.4, 0.4))
        return fig

    cases = [
        (figure([(0.1, 0.5, "apart"), (0.6, 0.9, "labels")]), None),
        (figure([(0.4, 0.5, "overlapping"), (0.42, 0.5, "labels")]), "overlap"),
        (figure([(0.02, 0.95, "on the legend")], legend=True), "legend"),
        (figure([(0.6, 0.2, "on the inset")], inset=True), "inset"),
    ]
    for fig, expected in cases:
        try:
            check_labels(fig, None)
            refused = None
        except Refused as e:
            refused = str(e)
        plt.close(fig)
        if (refused is None) != (expected is None) or (expected and expected not in refused):
            sys.exit(f"the label check is broken: expected {expected!r}, got {refused!r}")


def main(memstab, out, figures):
    self_check()
    out.mkdir(parents=True, exist_ok=True)
    figures.mkdir(parents=True, exist_ok=True)

    below = run(memstab, "scenes/disc_fluid_below.toml", out / "disc_fluid_below", "--refine")
    path_figure([(below, "C7v")], "max_displacement", "h",
                "Paper 1: the C7v disc pushed up by fluid from below (k = 0)",
                figures / "paper1_disc_below_path.png")
    mode_figure(below, "Paper 1: critical modes of the disc from below (normal component)",
                figures / "paper1_disc_below_modes.png")

    irregular = run(memstab, "scenes/thesis/paper1_disc_irregular.toml", out / "disc_irregular")
    path_figure([(below, "C7v, 1 792 triangles"), (irregular, "irregular, 1 800 triangles")],
                "max_displacement", "h",
                "Paper 1: the disc from below on a symmetric and an irregular mesh",
                figures / "paper1_disc_irregular_path.png")

    scene = "scenes/thesis/paper1_disc_limit_curve_k.toml"
    limit = run(memstab, scene, out / "disc_curve_k_limit")
    double = run(memstab, variant(scene, out, "disc_curve_k_e1", ('from = "limit"', 'from = "E1"')),
                 out / "disc_curve_k_e1")
    curve_figure([limit, double], "k", "h",
                 "Paper 1: the disc's limit point and first double point followed in k",
                 figures / "paper1_disc_limit_curve_k.png")

    # The thesis's own mesh sizes, unless QUICK=1 (CI's form): the disc's 1 792 triangles, the
    # f = 16 icosphere, and 26 divisions (5 408 triangles) for the caps of Papers 3 and 4.
    quick = os.environ.get("QUICK") == "1"

    scene = "scenes/thesis/paper1_disc_swallowtail.toml"
    if quick:
        swallowtail, disc = run(memstab, scene, out / "paper1_swallowtail"), "448"
    else:
        scene = variant(scene, out, "paper1_swallowtail_1792", DISC_1792)
        swallowtail, disc = run(memstab, scene, out / "paper1_swallowtail_1792"), "1 792"
    meridian = run(memstab, "scenes/axisymmetric/paper1_disc_swallowtail.toml",
                   out / "paper1_swallowtail_meridian")
    cusp_figure([(swallowtail, f"C7v, {disc} triangles"), (meridian, "meridian, 32 elements")],
                "Paper 1: the disc's cusps in (k, h) as the density varies",
                figures / "paper1_disc_swallowtail.png")

    fold_scene = ("scenes/thesis/paper2_gas_pressure_fold_f8.toml" if quick
                  else "scenes/thesis/paper2_gas_pressure_fold.toml")
    fold = run(memstab, fold_scene, out / "paper2_fold")
    curve_figure([fold], "V", "p",
                 "Paper 2: the gas pressure's maximum followed in the fluid volume",
                 figures / "paper2_gas_pressure_fold.png")

    surface_scene = ("scenes/thesis/paper2_solution_surface_f8.toml" if quick
                     else "scenes/thesis/paper2_solution_surface.toml")
    surface = run(memstab, surface_scene, out / "paper2_surface")
    surface_figure(surface, "p", "V", "stretch",
                   "Paper 2: the solution surface of the sphere on a plane",
                   figures / "paper2_solution_surface.png")

    # Paper 3 on the 1 152-triangle mesh, where the linear law's penalty-induced points lie in
    # the range; and (unless QUICK=1) on the thesis's 5 408 triangles, where they have moved out.
    names = [("paper3_gas_fluid_squeeze", "cubic"), ("paper3_gas_fluid_squeeze_linear", "linear")]
    laws = [(run(memstab, f"scenes/thesis/{name}.toml", out / f"paper3_{law}"),
             f"{law} penalty, κ = 1e3") for name, law in names]
    path_figure(laws, "volume", "d",
                "Paper 3: gas above fluid squeezed between two planes x = ±a",
                figures / "paper3_penalty_laws.png")
    if not quick:
        laws = [(run(memstab, variant(f"scenes/thesis/{name}.toml", out, f"paper3_{law}_5408",
                                      CAP_5408), out / f"paper3_{law}_5408"),
                 f"{law} penalty, κ = 1e3") for name, law in names]
        path_figure(laws, "volume", "d",
                    "Paper 3: the same on the thesis's mesh size (5 408 triangles)",
                    figures / "paper3_penalty_laws_5408.png")

    scene = "scenes/thesis/paper4_spinning_cap.toml"
    if quick:
        cap, cap_mesh = run(memstab, scene, out / "paper4_c8v"), "C8v, 1 152 triangles"
    else:
        scene = variant(scene, out, "paper4_c8v_5408", CAP_5408)
        cap, cap_mesh = run(memstab, scene, out / "paper4_c8v_5408"), "C8v, 5 408 triangles"
    path_figure([(cap, cap_mesh)], "max_displacement", "w2",
                f"Paper 4: the filled cap spinning on the floor ({cap_mesh})",
                figures / "paper4_spinning_cap_path.png")
    mode_figure(cap, "Paper 4: critical modes of the spinning cap (normal component)",
                figures / "paper4_spinning_cap_modes.png")

    # The hilltop on 1 152 triangles at every size: on 5 408 the limit curve, a fold of the
    # floor's penalty contact, zig-zags through pairs of cusps and needs hundreds more steps to
    # reach the m = 4 curves (docs/thesis.md, Paper 4).
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


# Scene lines replaced for the thesis's mesh sizes.
DISC_1792 = ("divisions = 8              # 448 triangles", "divisions = 16             # 1792 triangles")
CAP_5408 = ("divisions = 12             # 1152 triangles", "divisions = 26             # 5408 triangles")


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    try:
        main(sys.argv[1], Path(sys.argv[2]), Path(sys.argv[3]))
    except Refused as e:
        sys.exit(str(e))
