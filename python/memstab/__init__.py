"""memstab from Python: scenes, runs and the finite-element model.

    import memstab
    scene = memstab.Scene.load("scenes/balloon.toml").with_({"mesh.frequency": 4})
    result = memstab.run(scene)            # a temporary directory; or out="DIR"
    result.path                            # pandas DataFrame: path.csv
    result.critical                        # kind, irrep, multiplicity, isotropy, m, value, ...
    result.state(0)                        # meshio.Mesh of a saved path state
    model = scene.model()
    u, params = model.start()
    F = model.residual(u, params)          # numpy array
    K = model.tangent(u, params)           # scipy.sparse matrix

Every error is a ``memstab.MemstabError`` carrying the command line's one-line message.
A run does not hold the GIL while it computes.
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

__all__ = ["MemstabError", "Scene", "Result", "Model", "run", "__version__"]
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

    def positions(self, u, params):
        """The nodes' current positions X + u, shape (nodes, 3)."""
        import numpy as np

        return np.array(self._m.positions(*self._args(u, params))).reshape(-1, 3)


class Result:
    """A finished run: its directory and what it wrote."""

    def __init__(self, out: Path, stop: str, keep=None):
        self.dir = out
        self.stop = stop
        self._keep = keep
        self.summary = json.loads((out / "summary.json").read_text())

    @property
    def path(self):
        """path.csv as a pandas DataFrame."""
        import pandas as pd

        return pd.read_csv(self.dir / "path.csv")

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
                "flags": [f["flag"] for f in c["flags"]],
            }
            for c in self.summary["critical"]
        ]
        columns = ["kind", "irrep", "multiplicity", "isotropy", "m", "value", "step", "valid", "flags"]
        return pd.DataFrame(rows, columns=columns)

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
                "flags": [f["flag"] for f in t["flags"]],
            }
            for t in self.summary["turning_points"]
        ]
        return pd.DataFrame(rows, columns=["kind", "value", "step", "valid", "flags"])

    @property
    def states(self) -> list[int]:
        """The path steps whose states were saved (``state(i)`` reads them)."""
        return sorted(int(p.stem.split("_")[1]) for p in self.dir.glob("state_*.vtu"))

    def state(self, i: int):
        """The saved state at path step ``i`` as a meshio.Mesh (the displaced mesh with its
        fields, docs/scenes.md "Output files")."""
        import meshio

        file = self.dir / f"state_{i:04d}.vtu"
        if not file.is_file():
            raise KeyError(f"no saved state at step {i}; the saved steps: {self.states}")
        return meshio.read(file)

    def critical_state(self, n: int):
        """Critical point ``n`` (from 1, as in critical.json) as a meshio.Mesh with its mode."""
        import meshio

        file = self.dir / f"critical_{n:02d}.vtu"
        if not file.is_file():
            raise KeyError(f"no critical state {n}: the run has {len(self.summary['critical'])}")
        return meshio.read(file)

    def __repr__(self) -> str:
        return (
            f"Result({self.summary['scene']!r}: {self.summary['points']} points, "
            f"{len(self.summary['critical'])} critical, stop: {self.stop}; in {self.dir})"
        )


def run(scene: Scene, out: str | os.PathLike | None = None) -> Result:
    """Runs ``scene`` as ``memstab run`` does into ``out`` (made if missing), or into a
    temporary directory that lives as long as the result. The GIL is released meanwhile."""
    if not isinstance(scene, Scene):
        raise TypeError("run() takes a memstab.Scene")
    keep = None
    if out is None:
        keep = tempfile.TemporaryDirectory(prefix="memstab-")
        out = keep.name
    out = Path(out)
    stop = _memstab.run(scene.to_toml(), scene.origin, os.fspath(out))
    return Result(out, stop, keep)
