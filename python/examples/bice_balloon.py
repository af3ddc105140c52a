"""memstab's model of the balloon handed to another continuation package, bice (from PyPI:
``pip install bice``), and the two pressure maxima compared.

The balloon (``scenes/balloon.toml``, here on an icosphere of frequency 4) is a free closed
membrane: its tangent K has the six rigid-body modes in its null space, so a plain Newton
iteration on all unknowns fails. The inflated sphere is invariant under the icosahedral group
Ih, and so is the whole inflation branch: restricted to the fixed-point space of Ih — the
basis B from ``model.fixed_point_basis()``, a handful of columns — the residual
F_r(y, p) = Bᵀ F(B y, p) and the tangent K_r = Bᵀ K B have no rigid modes (translations and
rotations are not Ih-invariant), and bice's pseudo-arclength continuation follows the branch
through its pressure maximum. bice writes a problem as du/dt = rhs(u): rhs = −F_r, its
Jacobian −K_r.

Run from the repository's root: ``python python/examples/bice_balloon.py``. Prints both
maxima and their relative difference, and exits non-zero when they differ by more than
``TOLERANCE``.
"""

from __future__ import annotations

import sys

import numpy as np

import bice
import memstab

#: The largest relative difference accepted between the two maxima (memstab locates its
#: turning point; bice's is the vertex of a parabola through three short steps around it).
TOLERANCE = 1e-8


class Inflation(bice.Equation):
    """The balloon's equilibrium in the fixed-point space of Ih, for bice."""

    def __init__(self, model: memstab.Model, u0, p0: float):
        self.model = model
        self.basis = model.fixed_point_basis()
        super().__init__(shape=(self.basis.shape[1],))
        self.u = self.basis.T @ u0  # the start state's coordinates: u0 lies in the space
        self.p = p0

    def rhs(self, y):
        return -(self.basis.T @ self.model.residual(self.basis @ y, [self.p]))

    def jacobian(self, y):
        k = self.model.tangent(self.basis @ y, [self.p])
        return -(self.basis.T @ k @ self.basis).toarray()


class Balloon(bice.Problem):
    def __init__(self, model, u0, p0):
        super().__init__()
        self.inflation = Inflation(model, u0, p0)
        self.add_equation(self.inflation)
        self.continuation_parameter = (self.inflation, "p")


def follow(problem: Balloon, ds: float, past: float, steps: int) -> np.ndarray:
    """bice's continuation steps from the problem's state with steps up to `ds`, until p
    lies `past` below its largest value (or `steps` are taken): every point as (y, p)."""
    stepper = problem.continuation_stepper
    stepper.ds = stepper.ds_max = ds
    problem.history.clear()
    points = [np.append(problem.u, problem.inflation.p)]
    for _ in range(steps):
        problem.continuation_step()
        points.append(np.append(problem.u, problem.inflation.p))
        p = [q[-1] for q in points]
        if p[-1] < max(p) - past:
            break
    return np.array(points)


def bice_maximum(scene: memstab.Scene) -> tuple[float, int]:
    """The pressure maximum along bice's branch from the scene's start state, and the number
    of bice's steps taken: the branch followed in long steps past the maximum, then again
    from the point before it in short ones, and the vertex of the parabola p(s) through the
    three short-step points around the largest p (s the arclength in (y, p))."""
    model = scene.model()
    u0, params = model.start()
    problem = Balloon(model, u0, float(params[0]))
    problem.settings.neigs = 0  # no eigenvalues: only the branch
    problem.continuation_stepper.convergence_tolerance = 1e-12
    coarse = follow(problem, ds=0.5, past=0.02, steps=200)
    i = int(np.argmax(coarse[:, -1]))
    problem.u, problem.inflation.p = coarse[i - 1, :-1].copy(), coarse[i - 1, -1]
    fine = follow(problem, ds=0.005, past=1e-4, steps=2000)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(fine, axis=0), axis=1))])
    p = fine[:, -1]
    j = int(np.argmax(p))
    a, b, c = np.polyfit(s[j - 1 : j + 2] - s[j], p[j - 1 : j + 2], 2)
    return c - b * b / (4 * a), len(coarse) + len(fine) - 2


def main() -> int:
    scene = memstab.Scene.load("scenes/balloon.toml").with_(mesh__frequency=4)
    result = memstab.run(scene, progress=False)
    turning = result.turning
    ours = float(turning[turning["kind"] == "maximum"]["value"].iloc[0])
    theirs, steps = bice_maximum(scene)
    difference = abs(theirs - ours) / ours
    print(f"pressure maximum p R/(mu H): memstab {ours:.8f}, bice {theirs:.8f} "
          f"({steps} steps in the fixed-point space of Ih, "
          f"{scene.model().fixed_point_basis().shape[1]} unknowns); "
          f"relative difference {difference:.1e}")
    return 0 if difference < TOLERANCE else 1


if __name__ == "__main__":
    sys.exit(main())
