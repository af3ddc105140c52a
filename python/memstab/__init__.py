"""memstab from Python: scenes, runs and the finite-element model.

    import memstab
    scene = memstab.Scene.load("scenes/balloon.toml").with_({"mesh.frequency": 4})
    result = memstab.run(scene)            # a temporary directory; or out="DIR"
    result.path                            # pandas DataFrame: path.csv
    result.critical                        # kind, irrep, multiplicity, isotropy, m, value, ...
    result.state(0)                        # meshio.Mesh of a saved path state
    result.spectrum(5)                     # the tangent's eigenvalues by irrep at path point 5
    model = scene.model()
    u, params = model.start()
    F = model.residual(u, params)          # numpy array
    K = model.tangent(u, params)           # scipy.sparse matrix

Every error is a ``memstab.MemstabError`` carrying the command line's one-line message.
A run does not hold the GIL while it computes, shows a progress bar (tqdm, when installed),
and stops at Ctrl-C as the command line does: what it found is written, and
``KeyboardInterrupt`` is raised.
"""

from __future__ import annotations

import copy
import json
import os
import re
import tempfile
from pathlib import Path
from typing import Any, Mapping

from . import _memstab
from ._memstab import MemstabError

__all__ = [
    "MemstabError",
    "Scene",
    "Result",
    "Branch",
    "Model",
    "Comparison",
    "Group",
    "Collected",
    "run",
    "compare",
    "mesh",
    "group",
    "collect",
    "__version__",
]
__version__ = _memstab.__version__

_INDEX = re.compile(r"^([A-Za-z0-9_-]+)((?:\[\d+\])*)$")


def _set_key(doc: dict, key: str, value: Any) -> None:
    """Sets the dotted scene key ``key`` (``material.k``, ``effect[0].density``) in ``doc``."""
    parts = key.split(".")
    at: Any = doc
    for n, part in enumerate(parts):
        m = _INDEX.match(part)
        if not m:
            raise MemstabError(
                f"'{key}' is not a scene key (dotted names such as material.k or effect[0].density)"
            )
        name, indices = m.group(1), [int(i) for i in re.findall(r"\[(\d+)\]", m.group(2))]
        last = n + 1 == len(parts)
        if not isinstance(at, dict):
            raise MemstabError(f"'{key}': '{name}' is not inside a table")
        if not indices:
            if last:
                at[name] = value
                return
            at = at.setdefault(name, {})
            continue
        if name not in at or not isinstance(at[name], list):
            raise MemstabError(f"'{key}': the scene has no list '{name}' to index")
        for j, i in enumerate(indices):
            if not isinstance(at, (dict, list)):
                raise MemstabError(f"'{key}': '{name}' is not a list")
            seq = at[name] if j == 0 else at
            if i >= len(seq):
                raise MemstabError(
                    f"'{key}': the scene's '{name}' has {len(seq)} entries (indices from 0)"
                )
            if last and j + 1 == len(indices):
                seq[i] = value
                return
            at = seq[i]


class Scene:
    """A validated scene (docs/scenes.md), held as its TOML text."""

    def __init__(self, text: str, origin: str = "scene"):
        self._text = _memstab.scene_check(text, origin)
        self.origin = origin

    @classmethod
    def load(cls, path: str | os.PathLike) -> "Scene":
        """Reads and validates a scene file (its mesh built)."""
        text, origin = _memstab.scene_load(os.fspath(path))
        scene = cls.__new__(cls)
        scene._text, scene.origin = text, origin
        return scene

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], origin: str = "scene") -> "Scene":
        """A scene from the nested dict of its TOML tables (as ``to_dict`` gives)."""
        return cls(_memstab.json_to_toml(json.dumps(data)), origin)

    def to_dict(self) -> dict:
        """The scene's tables as nested dicts and lists."""
        return json.loads(_memstab.toml_to_json(self._text))

    def to_toml(self) -> str:
        return self._text

    @property
    def name(self) -> str:
        return self.to_dict().get("scene", {}).get("name", "")

    def with_(self, changes: Mapping[str, Any] | None = None, /, **keys: Any) -> "Scene":
        """A copy with scene keys changed: ``with_({"material.k": 0.05})``, or as keywords
        with ``__`` for the dots, ``with_(material__k=0.05, mesh__divisions=8)``. The new
        scene is validated; a bad key or value raises MemstabError naming it."""
        doc = copy.deepcopy(self.to_dict())
        items = dict(changes or {})
        items.update({k.replace("__", "."): v for k, v in keys.items()})
        for key, value in items.items():
            _set_key(doc, key, value)
        return Scene.from_dict(doc, self.origin)

    def model(self) -> "Model":
        """The scene's finite-element model (3-D meshes)."""
        return Model(_memstab.Model(self._text, self.origin))

    def __repr__(self) -> str:
        return f"Scene({self.name!r} from {self.origin})"


class Model:
    """The residual F(u, Λ) = ∂Π/∂u and the tangent K = ∂F/∂u of a scene's model."""

    def __init__(self, native):
        self._m = native

    @property
    def unknowns(self) -> int:
        return self._m.unknowns

    @property
    def parameters(self) -> list[str]:
        return self._m.parameters

    @property
    def start_values(self):
        import numpy as np

        return np.array(self._m.start_values)

    def start(self):
        """The start state as a run solves it: (u, parameters) as numpy arrays."""
        import numpy as np

        u, p = self._m.start()
        return np.array(u), np.array(p)

    def _args(self, u, params):
        import numpy as np

        return (
            np.asarray(u, dtype=float).ravel().tolist(),
            np.asarray(params, dtype=float).ravel().tolist(),
        )

    def residual(self, u, params):
        """F(u, Λ), a numpy array of ``unknowns`` values."""
        import numpy as np

        return np.array(self._m.residual(*self._args(u, params)))

    def loads(self, u, params):
        """∂F/∂Λ, a numpy array of shape (unknowns, parameters)."""
        import numpy as np

        return np.array(self._m.loads(*self._args(u, params))).T

    def tangent(self, u, params, rank_one: bool = True):
        """K(u, Λ) as a scipy.sparse CSC matrix. With ``rank_one`` (a gas of fixed amount
        adds c a aᵀ terms, which are dense) they are added; else only the sparse part S."""
        import numpy as np
        import scipy.sparse as sp

        values, rows, cols, terms = self._m.tangent(*self._args(u, params))
        n = self.unknowns
        k = sp.csc_matrix((np.array(values), np.array(rows), np.array(cols)), shape=(n, n))
        if rank_one and terms:
            k = k + sum(c * sp.csc_matrix(np.outer(a, a)) for c, a in terms)
        return k

    def fixed_point_basis(self):
        """The fixed-point basis of the scene's group: a scipy.sparse CSC matrix of shape
        (unknowns, m) with orthonormal columns spanning the displacements every symmetry of
        the group leaves unchanged (the trivial irrep's block; the space a symmetric path
        lies in)."""
        return _csc(self._m.fixed_point(), self.unknowns)

    def adapted_bases(self) -> dict:
        """The symmetry-adapted basis by irrep: ``{name: B}`` with B a scipy.sparse CSC
        matrix of shape (unknowns, m) whose orthonormal columns are the first partner of the
        irrep (the trivial irrep first, in the group's order)."""
        return {name: _csc(columns, self.unknowns) for name, _, _, columns in self._adapted()}

    def irreps(self):
        """The irreps of the scene's group as the model's blocks see them: a DataFrame with
        ``irrep``, ``dim`` (d: each eigenvalue of the block is d-fold in K), ``complex``
        (a complex-type block holds the whole isotypic component, its eigenvalues in pairs)
        and ``size`` (the block's columns m)."""
        import pandas as pd

        return pd.DataFrame(
            [
                {"irrep": name, "dim": d, "complex": c, "size": cols[3]}
                for name, d, c, cols in self._adapted()
            ],
            columns=["irrep", "dim", "complex", "size"],
        )

    def blocks(self, u, params, rank_one: bool = True) -> dict:
        """The symmetry-adapted blocks of K(u, Λ) at a symmetric state: ``{irrep: B_μᵀ K
        B_μ}`` as scipy.sparse matrices. Their eigenvalues, each counted d_μ times, are K's
        (docs/theory.md §10.5); a complex-type block spans its irrep's whole component, so
        its eigenvalues, which come in pairs, count once."""
        k = self.tangent(u, params, rank_one=rank_one).tocsc()
        return {
            name: (b.T @ k @ b).tocsc() for name, b in self.adapted_bases().items()
        }

    def _adapted(self):
        if not hasattr(self, "_adapted_cache"):
            self._adapted_cache = self._m.adapted()
        return self._adapted_cache

    def positions(self, u, params):
        """The nodes' current positions X + u, shape (nodes, 3)."""
        import numpy as np

        return np.array(self._m.positions(*self._args(u, params))).reshape(-1, 3)


def _csc(parts, rows: int):
    import numpy as np
    import scipy.sparse as sp

    values, indices, pointers, columns = parts
    m = sp.csc_matrix(
        (np.array(values, dtype=float), np.array(indices, dtype=np.int64), np.array(pointers)),
        shape=(rows, columns),
    )
    m.sort_indices()
    return m


def _flags(item) -> list:
    return [f["flag"] for f in item.get("flags", [])]


_CRITICAL_COLUMNS = ["kind", "irrep", "multiplicity", "isotropy", "m", "value", "step", "valid", "flags"]


def _read_mesh(file: Path, pyvista: bool):
    if pyvista:
        try:
            import pyvista as pv
        except ImportError as e:
            raise ImportError("state(..., pyvista=True) needs pyvista: pip install pyvista") from e
        return pv.read(file)
    import meshio

    return meshio.read(file)


class _Directory:
    """What a run writes into a directory (a run's, or a branch's ``branch_NN/``): the path,
    its critical and turning points, its saved states."""

    dir: Path

    @property
    def path(self):
        """path.csv as a pandas DataFrame."""
        import pandas as pd

        return pd.read_csv(self.dir / "path.csv")

    def _path_json(self) -> dict:
        if not hasattr(self, "_path_cache"):
            self._path_cache = json.loads((self.dir / "path.json").read_text())
        return self._path_cache

    @property
    def control(self) -> str:
        return self._path_json()["control"]

    @property
    def critical(self):
        """The critical points (critical.json): kind, irrep, multiplicity, isotropy, m,
        value (the control), step, valid, flags (their names)."""
        import pandas as pd

        control = self.control
        rows = [
            {
                "kind": c["kind"],
                "irrep": c["irrep"],
                "multiplicity": c["multiplicity"],
                "isotropy": c["isotropy"],
                "m": c.get("m"),
                "value": c["parameters"][control],
                "step": c["step"],
                "valid": c.get("valid", True),
                "flags": _flags(c),
            }
            for c in json.loads((self.dir / "critical.json").read_text())
            if "irrep" in c
        ]
        return pd.DataFrame(rows, columns=_CRITICAL_COLUMNS)

    @property
    def turning(self):
        """The turning points of the control (path.json): kind, value, step, valid, flags."""
        import pandas as pd

        control = self.control
        rows = [
            {
                "kind": t["kind"],
                "value": t["parameters"][control],
                "step": t["step"],
                "valid": t.get("valid", True),
                "flags": _flags(t),
            }
            for t in self._path_json().get("turning_points", [])
        ]
        return pd.DataFrame(rows, columns=["kind", "value", "step", "valid", "flags"])

    @property
    def states(self) -> list[int]:
        """The path steps whose states were saved (``state(i)`` reads them)."""
        return sorted(int(p.stem.split("_")[1]) for p in self.dir.glob("state_*.vtu"))

    def state(self, i: int, pyvista: bool = False):
        """The saved state at path step ``i`` as a meshio.Mesh (the displaced mesh with its
        fields, docs/scenes.md "Output files"), or with ``pyvista=True`` as a pyvista mesh."""
        file = self.dir / f"state_{i:04d}.vtu"
        if not file.is_file():
            raise KeyError(f"no saved state at step {i}; the saved steps: {self.states}")
        return _read_mesh(file, pyvista)

    def critical_state(self, n: int, pyvista: bool = False):
        """Critical point ``n`` (from 1, as in critical.json) as a meshio.Mesh with its mode
        ``critical_mode`` (a pyvista mesh with ``pyvista=True``)."""
        file = self.dir / f"critical_{n:02d}.vtu"
        if not file.is_file():
            count = len(self._path_json().get("critical", []))
            raise KeyError(f"no critical state {n}: the run has {count} (numbered from 1)")
        return _read_mesh(file, pyvista)

    def _branches_json(self) -> dict:
        file = self.dir / "branches.json"
        return json.loads(file.read_text()) if file.is_file() else {"branches": []}

    @property
    def branches(self):
        """The branches switched onto at the critical points ([analysis.branches]):
        one row per branch with its ``id``, ``directory``, the critical point it leaves
        (``on``, the path or a branch, and ``from``, its node), ``irrep``, ``isotropy``,
        ``half``, ``bifurcation``, ``points``, ``critical`` (its own critical points) and
        ``stop``. ``branch(n)`` reads branch n (from 1, in this order)."""
        import pandas as pd

        columns = ["id", "directory", "on", "from", "irrep", "isotropy", "half",
                   "bifurcation", "points", "critical", "stop"]
        rows = [{k: b.get(k) for k in columns} for b in self._branches_json()["branches"]]
        return pd.DataFrame(rows, columns=columns)

    def branch(self, n: int) -> "Branch":
        """Branch ``n`` (from 1, the rows of ``branches``): its path, critical and turning
        points and states, read from its directory."""
        found = self._root()._branches_json()["branches"]
        if not 1 <= n <= len(found):
            raise KeyError(f"no branch {n}: the run has {len(found)} (numbered from 1)")
        info = found[n - 1]
        return Branch(self._root(), self._root().dir / info["directory"], info)

    def _root(self):
        return self


class Branch(_Directory):
    """A branch of a run: the files of its directory (``path``, ``critical``, ``turning``,
    ``state(i)``) and ``info``, its entry of branches.json."""

    def __init__(self, run: "Result", directory: Path, info: dict):
        self.run = run
        self.dir = directory
        self.info = info

    def _root(self):
        return self.run

    @property
    def branches(self):
        """The branches that leave this branch's critical points (depth 2)."""
        table = self.run.branches
        return table[table["on"] == self.info["id"]]

    def __repr__(self) -> str:
        return (
            f"Branch({self.info['id']}: {self.info['irrep']} {self.info['isotropy']}"
            f"{self.info.get('half', '')}, {self.info['points']} points, in {self.dir})"
        )


class Result(_Directory):
    """A finished run: its directory and what it wrote."""

    def __init__(self, out: Path, stop: str, keep=None, scene: "Scene | None" = None):
        self.dir = out
        self.stop = stop
        self._keep = keep
        self.scene = scene
        self.summary = json.loads((out / "summary.json").read_text())

    @property
    def critical(self):
        """The critical points: kind, irrep, multiplicity, isotropy, m, value (the control),
        step, valid, flags (their names)."""
        import pandas as pd

        rows = [
            {
                "kind": c["kind"],
                "irrep": c["irrep"],
                "multiplicity": c["multiplicity"],
                "isotropy": c["isotropy"],
                "m": c.get("m"),
                "value": c["value"],
                "step": c["step"],
                "valid": c["valid"],
                "flags": _flags(c),
            }
            for c in self.summary["critical"]
        ]
        return pd.DataFrame(rows, columns=_CRITICAL_COLUMNS)

    @property
    def turning(self):
        """The turning points of the control: kind, value, step, valid, flags."""
        import pandas as pd

        rows = [
            {
                "kind": t["kind"],
                "value": t["value"],
                "step": t["step"],
                "valid": t["valid"],
                "flags": _flags(t),
            }
            for t in self.summary["turning_points"]
        ]
        return pd.DataFrame(rows, columns=["kind", "value", "step", "valid", "flags"])

    def spectrum(self, point: int | None = None, *, critical: int | None = None, count: int = 6):
        """The tangent's spectrum by irrep at path point ``point`` (the row ``step`` of
        ``path``) or at critical point ``critical`` (from 1), as ``memstab spectrum RUN_DIR
        --point N`` gives it: a DataFrame with one row per irrep — ``irrep``, ``dim`` d,
        ``size`` m (the block's columns), ``negative`` (its negative eigenvalues, each
        d-fold in K), ``zero_modes`` and ``held_motions`` (deflated), ``lowest`` (its
        ``count`` lowest eigenvalues in units of max |K_ij|) — and in ``.attrs`` the
        ``index`` Σ d·negative, the ``scale`` max |K_ij| and the ``parameters``."""
        import pandas as pd

        if (point is None) == (critical is None):
            raise TypeError("spectrum() takes a path point or critical=N, one of them")
        scene = self.scene if self.scene is not None else Scene.load(self.summary_origin())
        text = _memstab.spectrum(
            scene.to_toml(), scene.origin, os.fspath(self.dir), point, critical, count
        )
        data = json.loads(text)
        frame = pd.DataFrame(
            data["irreps"],
            columns=["irrep", "dim", "size", "negative", "zero_modes", "held_motions", "lowest"],
        )
        frame.attrs.update(
            index=data["index"], scale=data["scale"], parameters=data["parameters"],
            group=data["group"],
        )
        return frame

    def summary_origin(self) -> str:
        return self._path_json()["origin"]

    def __repr__(self) -> str:
        return (
            f"Result({self.summary['scene']!r}: {self.summary['points']} points, "
            f"{len(self.summary['critical'])} critical, stop: {self.stop}; in {self.dir})"
        )


def _tqdm():
    """tqdm's class when tqdm is installed, else None."""
    try:
        from tqdm.auto import tqdm
    except ImportError:
        return None
    return tqdm


class _Bar:
    """The run's progress as the command line's bar shows it (the control's share of its
    range, the message ``p = 1.35510 in [0, 2], 120 points``), drawn by tqdm; made at the
    first point, so that a run that fails at its start draws nothing."""

    TICKS = 1000

    def __init__(self, tqdm, desc: str):
        self._tqdm = tqdm
        self._desc = desc
        self._bar = None

    def __call__(self, points: int, fraction, message: str) -> None:
        if self._bar is None:
            if fraction is not None:
                total, shape = self.TICKS, "{desc}: {percentage:3.0f}%|{bar}| [{elapsed}] {postfix}"
            else:
                total, shape = None, "{desc}: [{elapsed}] {postfix}"
            self._bar = self._tqdm(total=total, desc=self._desc, leave=True, bar_format=shape)
        if fraction is not None:
            self._bar.n = round(fraction * self.TICKS)
        else:
            self._bar.n = points
        self._bar.set_postfix_str(message, refresh=False)
        self._bar.refresh()

    def close(self, why: str | None = None) -> None:
        if self._bar is not None:
            if why:
                self._bar.set_postfix_str(why, refresh=False)
            self._bar.close()


def _progress(progress, desc: str):
    if progress is None:
        # As the command line: a bar where someone watches (a terminal, a notebook), none
        # in a log.
        import sys

        progress = sys.stderr.isatty() or "ipykernel" in sys.modules
    if progress is False:
        return None
    if callable(progress) and progress is not True:
        return progress
    tqdm = _tqdm()
    return _Bar(tqdm, desc) if tqdm is not None else None


def run(scene: Scene, out: str | os.PathLike | None = None, progress=None) -> Result:
    """Runs ``scene`` as ``memstab run`` does into ``out`` (made if missing), or into a
    temporary directory that lives as long as the result. The GIL is released meanwhile.

    ``progress``: True draws the command line's bar with tqdm when tqdm is installed
    (nothing without it), False draws none, None (the default) draws it where stderr is a
    terminal or in a notebook; a callable is called as ``progress(points, fraction,
    message)`` at every converged point. Ctrl-C stops the run at its next point; what it found is written (into
    ``out``) and ``KeyboardInterrupt`` is raised."""
    if not isinstance(scene, Scene):
        raise TypeError("run() takes a memstab.Scene")
    keep = None
    if out is None:
        keep = tempfile.TemporaryDirectory(prefix="memstab-")
        out = keep.name
    out = Path(out)
    bar = _progress(progress, scene.name or "memstab")
    try:
        stop = _memstab.run(scene.to_toml(), scene.origin, os.fspath(out), bar)
    except BaseException as e:
        if isinstance(bar, _Bar):
            bar.close("interrupted" if isinstance(e, KeyboardInterrupt) else "failed")
        raise
    if isinstance(bar, _Bar):
        bar.close(f"stopped: {stop}")
    return Result(out, stop, keep, scene)


class Comparison:
    """``memstab compare``'s result: the same scene on meshes of different symmetry.

    ``meshes``: a row per mesh and refinement level (label, mesh, group, order, nodes,
    unknowns, critical, seconds, stop). ``critical``: every critical point of every mesh
    (label, level, kind, irrep, multiplicity, m, value, isotropy, flagged). ``rungs``: the
    matched critical points, a row per rung, mesh and level (rung, m, mesh, irreps, values,
    gap, piece_gap, verdict, distances). ``unmatched``: points without a counterpart on the reference
    mesh. ``data``: what ``memstab compare --json`` prints."""

    def __init__(self, data: dict):
        import pandas as pd

        self.data = data
        self.control = data["control"]
        meshes, critical, rungs = [], [], []
        for m in data["meshes"]:
            for level, lv in enumerate(m["levels"]):
                meshes.append({
                    "label": m["label"], "level": level, "mesh": lv["mesh"],
                    "group": lv["group"], "order": lv["order"], "nodes": lv["nodes"],
                    "unknowns": lv["unknowns"], "critical": len(lv.get("critical", [])),
                    "seconds": lv["seconds"], "stop": lv["stop"],
                })
                for flagged, points in [(False, lv.get("critical", [])), (True, lv.get("flagged", []))]:
                    for p in points:
                        critical.append({
                            "label": m["label"], "level": level, "kind": p["kind"],
                            "irrep": p["irrep"], "multiplicity": p["multiplicity"],
                            "m": p.get("m"), "value": p["value"], "isotropy": p["isotropy"],
                            "flagged": flagged,
                        })
        for n, r in enumerate(data["rungs"], start=1):
            for im in r["images"]:
                for level, lv in enumerate(im["levels"]):
                    rungs.append({
                        "rung": n, "m": r.get("m"), "mesh": im["mesh"], "level": level,
                        "irreps": " + ".join(lv["irreps"]), "values": lv["values"],
                        "gap": lv.get("gap"), "piece_gap": lv.get("piece_gap"),
                        "verdict": lv["verdict"].get("kind") if isinstance(lv["verdict"], dict) else lv["verdict"],
                        "distances": lv.get("distances", []),
                    })
        self.meshes = pd.DataFrame(meshes)
        self.critical = pd.DataFrame(critical)
        self.rungs = pd.DataFrame(rungs)
        self.unmatched = pd.DataFrame(data.get("unmatched", []))

    def __repr__(self) -> str:
        return (
            f"Comparison({self.data['scene']!r} on {len(self.data['meshes'])} meshes, "
            f"{len(self.data['rungs'])} rungs)"
        )


def compare(
    scene: Scene,
    meshes,
    *,
    refine: bool = False,
    max: float | None = None,
    divisions: int | None = None,
    samples: int | None = None,
    include_flagged: bool = False,
    progress: bool | None = None,
) -> Comparison:
    """``memstab compare SCENE --meshes A,B,…``: ``scene`` on each of ``meshes`` (a list,
    or one comma-separated string: group names such as ``"C8v"`` for the scene's generator
    with that group, full overrides ``"disc:sectors=8,divisions=12,group=C2v"``, or
    ``"axisymmetric"``; the first is the reference), the critical points matched across
    them. Keywords as the command's flags. Progress lines go to tqdm's ``write`` (or to
    stderr) where stderr is a terminal or in a notebook (``progress=True``: always, False:
    never); Ctrl-C stops it and raises ``KeyboardInterrupt``."""
    if not isinstance(scene, Scene):
        raise TypeError("compare() takes a memstab.Scene")
    meshes = [meshes] if isinstance(meshes, str) else [str(m) for m in meshes]
    report = None
    import sys

    if progress is None:
        progress = sys.stderr.isatty() or "ipykernel" in sys.modules
    if progress:
        tqdm = _tqdm()
        write = tqdm.write if tqdm is not None else (lambda s: print(s, file=sys.stderr))
        report = lambda _points, _fraction, line: write(f"compare: {line}")  # noqa: E731
    text = _memstab.compare(
        scene.to_toml(), scene.origin, meshes, refine, max, divisions, samples,
        include_flagged, report,
    )
    return Comparison(json.loads(text))


def mesh(generator: str, **options):
    """``memstab mesh``: a symmetric mesh from a generator and its options as in a scene's
    ``[mesh]`` (``mesh("disc", sectors=8, divisions=6, group="C4v")``,
    ``mesh("icosphere", frequency=4)``, ``mesh("truncated-sphere", pattern="C2v")``), its
    group action verified. Returns ``(meshio.Mesh, group name)``; the mesh carries the
    ``node_orbit`` and ``triangle_orbit`` numbers."""
    import meshio

    doc = {"generator": generator}
    doc.update({k.replace("_", "-"): v for k, v in options.items()})
    table = _memstab.json_to_toml(json.dumps(doc))
    with tempfile.TemporaryDirectory(prefix="memstab-mesh-") as tmp:
        file = Path(tmp) / "mesh.vtu"
        group_name, *_ = _memstab.mesh(table, os.fspath(file))
        return meshio.read(file), group_name


class Group:
    """A point group (``memstab group NAME``): ``name``, ``order``, ``classes`` (the element
    numbers of each conjugacy class), ``irreps`` (a DataFrame: name, dim, kind) and
    ``characters`` (a DataFrame: one row per irrep, one column per class, headed
    ``size x representative`` as the command prints them)."""

    def __init__(self, data: dict):
        import pandas as pd

        self.data = data
        self.name = data["name"]
        self.order = data["order"]
        self.classes = data["classes"]
        self.irreps = pd.DataFrame(
            [{k: r[k] for k in ("name", "dim", "kind")} for r in data["irreps"]]
        )
        columns = [f"{len(c)}x{c[0]}" for c in self.classes]
        self.characters = pd.DataFrame(
            [[round(r["characters"][c[0]], 12) + 0.0 for c in self.classes] for r in data["irreps"]],
            index=[r["name"] for r in data["irreps"]],
            columns=columns,
        )

    def __repr__(self) -> str:
        return f"Group({self.name}: order {self.order}, {len(self.irreps)} irreps)"


def group(name: str) -> Group:
    """The point group ``name`` (C<n>, C<n>v, I, Ih): its order, irreps and characters."""
    return Group(json.loads(_memstab.group(name)))


class Collected:
    """A sweep collected (``memstab collect DIR``): ``points`` (collected.csv: every
    finished run's critical and turning points, a row each, with the swept values),
    ``runs`` (a row per task: its status — finished, failed, cut short, not run — and why),
    ``files`` (what was written: the CSV, the figure, and ``collected.parquet`` when pyarrow
    is installed), ``table`` (the collected table as the command's ``--json`` gives it)."""

    def __init__(self, table: dict, files: list, points, runs):
        self.table = table
        self.files = files
        self.points = points
        self.runs = runs

    def __repr__(self) -> str:
        return f"Collected({self.table['name']!r}: {len(self.runs)} runs, {len(self.points)} points)"


def collect(dir: str | os.PathLike, x: str | None = None, parquet: bool | None = None) -> Collected:
    """``memstab collect DIR [--x KEY]``: merges the finished runs of the sweep in ``dir``
    into ``collected.csv`` and its figure, and returns them as DataFrames. With pyarrow
    installed (or ``parquet=True``, which then needs it) the table is also written as
    ``collected.parquet``; ``parquet=False`` never writes it."""
    import pandas as pd

    dir = Path(dir)
    text, files = _memstab.collect(os.fspath(dir), x)
    table = json.loads(text)
    csv = dir / "collected.csv"
    points = pd.read_csv(csv, keep_default_na=False, na_values=[""]) if csv.is_file() else pd.DataFrame()
    keys = table["keys"]
    runs = pd.DataFrame(
        [
            {
                "task": r["task"],
                "dir": r["dir"],
                **{k: v["text"] for k, v in zip(keys, r["values"])},
                "status": r["status"],
                "message": r.get("message"),
            }
            for r in table["runs"]
        ]
    )
    if parquet is None:
        try:
            import pyarrow  # noqa: F401

            parquet = True
        except ImportError:
            parquet = False
    if parquet:
        file = dir / "collected.parquet"
        points.to_parquet(file, index=False)
        files = list(files) + [os.fspath(file)]
    return Collected(table, list(files), points, runs)
