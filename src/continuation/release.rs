//! The start homotopy of a free body resting on a plane (docs/theory.md §7.8), for any
//! [`Problem`]: the mean translation along a direction held by a uniform force, then released
//! along an auxiliary path until that force vanishes. The start solves of the 3-D mesh and of
//! the meridian (`[start] hold-translation`) share it.

use super::events::locate;
use super::{point_at, solve_at, Continuation, Linearization, PathOptions, Problem, SolveError};

/// A problem with the mean translation along a direction held (docs/theory.md §7.8): its
/// unknowns are the inner problem's q, the held mean displacement ζ (the control), the
/// parameters the inner problem's constraints free (μ) and the uniform force R that holds
/// it, with
///
/// ```text
///   R_held(q, ζ, μ, R) = R_inner(q, μ) − R w,   g_inner(q, μ) = 0,   wᵀ q / |w|² − ζ = 0,
/// ```
///
/// w the translation field in the problem's unknowns (in 3-D w = Bᵀ e, the restricted field
/// e_i = d; on a meridian the rings' area-weighted heights). The inner problem's control
/// stays at the value given; its constraints, if any, hold along the release (a fluid volume
/// held keeps the weight the plane must take).
struct HeldTranslation<'p, P: Problem> {
    inner: &'p mut P,
    control: f64,
    w: nalgebra::DVector<f64>,
}

impl<P: Problem> HeldTranslation<'_, P> {
    /// The inner problem's free parameters (its control and the μ).
    fn inner_free(&self) -> usize {
        self.inner.free_parameters()
    }
}

impl<P: Problem> Problem for HeldTranslation<'_, P> {
    fn dim(&self) -> usize {
        self.inner.dim()
    }

    fn free_parameters(&self) -> usize {
        self.inner_free() + 1
    }

    fn evaluate(
        &mut self,
        q: &nalgebra::DVector<f64>,
        lambda: &nalgebra::DVector<f64>,
    ) -> Result<Linearization, crate::model::ModelError> {
        let f = self.inner_free();
        let mut inner_lambda = lambda.rows(0, f).into_owned();
        inner_lambda[0] = self.control;
        let lin = self.inner.evaluate(q, &inner_lambda)?;
        let m = q.len();
        let c = lin.constraints.len();
        let w2 = self.w.norm_squared();
        let mut loads = nalgebra::DMatrix::zeros(m, f + 1);
        for j in 1..f {
            loads.set_column(j, &lin.loads.column(j));
        }
        loads.set_column(f, &(-&self.w));
        let mut constraints = nalgebra::DVector::zeros(c + 1);
        constraints.rows_mut(0, c).copy_from(&lin.constraints);
        constraints[c] = self.w.dot(q) / w2 - lambda[0];
        let mut constraint_q = nalgebra::DMatrix::zeros(c + 1, m);
        constraint_q.rows_mut(0, c).copy_from(&lin.constraint_q);
        constraint_q.set_row(c, &(&self.w / w2).transpose());
        let mut constraint_lambda = nalgebra::DMatrix::zeros(c + 1, f + 1);
        for j in 1..f {
            constraint_lambda
                .view_mut((0, j), (c, 1))
                .copy_from(&lin.constraint_lambda.column(j));
        }
        constraint_lambda[(c, 0)] = -1.0;
        Ok(Linearization {
            residual: lin.residual - &self.w * lambda[f],
            tangent: lin.tangent,
            loads,
            constraints,
            constraint_q,
            constraint_lambda,
        })
    }
}

/// The start homotopy of `[start] hold-translation` (docs/theory.md §7.8): from `q0`, solve
/// with the mean translation along `w` held at its start value; then move the held position
/// along an auxiliary path until the holding force vanishes, and return that state and the
/// inner problem's free parameters there (the control as given; the caller solves the free
/// problem from it). A free body resting on a plane has a singular
/// tangent until it touches the plane; held, it has none.
pub fn released<P: Problem>(
    problem: &mut P,
    q0: &nalgebra::DVector<f64>,
    lambda: &nalgebra::DVector<f64>,
    w: nalgebra::DVector<f64>,
    opts: &PathOptions,
) -> Result<(nalgebra::DVector<f64>, nalgebra::DVector<f64>), SolveError> {
    if w.norm() == 0.0 {
        return Err(SolveError::Model(crate::model::ModelError::Global {
            effect: "start".into(),
            what: "start.hold-translation: the scene's group moves that direction, so the \
                   symmetric states cannot translate along it"
                .into(),
        }));
    }
    let zeta = w.dot(q0) / w.norm_squared();
    let mut held = HeldTranslation {
        inner: problem,
        control: lambda[0],
        w,
    };
    let f = held.inner_free();
    let mut start = nalgebra::DVector::zeros(f + 1);
    start.rows_mut(0, f).copy_from(lambda);
    start[0] = zeta;
    let (q, l, _) = solve_at(&mut held, q0, &start, opts)?;
    let force = move |l: &nalgebra::DVector<f64>| l[f];
    let scale = held.w.norm() * opts.state_scale;
    let mut point = point_at(&mut held, q, l, 0, opts, None)?;
    let inner = move |l: &nalgebra::DVector<f64>| {
        let mut v = l.rows(0, f).into_owned();
        v[0] = lambda[0];
        v
    };
    if force(&point.lambda) == 0.0 {
        return Ok((point.q, inner(&point.lambda)));
    }
    // Move ζ the way that reduces |R|.
    if point.tangent[point.q.len() + f] * force(&point.lambda) > 0.0 {
        point.tangent = -point.tangent;
    }
    let release_opts = PathOptions {
        bounds: (f64::NEG_INFINITY, f64::INFINITY),
        ..opts.clone()
    };
    let mut driver = Continuation::new(held, point, release_opts);
    for _ in 0..RELEASE_STEPS {
        if super::interrupt::requested() {
            return Err(SolveError::Interrupted);
        }
        let Ok(step) = driver.step() else { break };
        let (f0, f1) = (force(&step.from.lambda), force(&driver.point().lambda));
        if f0.signum() == f1.signum() {
            continue;
        }
        let s1 = driver.point().arclength - step.from.arclength;
        let from = step.from.clone();
        let tol = 1e-12 * (f0.abs().max(f1.abs())).max(scale * 1e-300);
        let (s, _) = locate(
            |s| driver.step_from(&from, s).ok().map(|p| force(&p.lambda)),
            f0,
            s1,
            f1,
            tol,
        )
        .ok_or_else(|| interrupted_or(SolveError::SingularTangent))?;
        return driver
            .step_from(&from, s)
            .map(|p| (p.q, inner(&p.lambda)))
            .map_err(|_| interrupted_or(SolveError::SingularTangent));
    }
    if super::interrupt::requested() {
        return Err(SolveError::Interrupted);
    }
    Err(SolveError::NotReleased {
        steps: RELEASE_STEPS,
        force: force(&driver.point().lambda),
    })
}

/// [`SolveError::Interrupted`] when a signal asked to stop (a failed step may be its doing),
/// else `error`.
fn interrupted_or(error: SolveError) -> SolveError {
    if super::interrupt::requested() {
        SolveError::Interrupted
    } else {
        error
    }
}

/// Steps the release of a held translation may take.
const RELEASE_STEPS: usize = 400;
