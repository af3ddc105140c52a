//! What every per-triangle kernel of an effect returns: a value with its gradient (9) and
//! Hessian (9×9) in node-major order x1, y1, z1, x2, …, z3, which the [`super::Assembler`]
//! scatters into the residual and the tangent.

/// Value, gradient (9) and Hessian (9×9) of one triangle's contribution, node-major dofs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Local {
    /// The contribution itself.
    pub value: f64,
    /// ∂/∂(x1, y1, z1, x2, …, z3).
    pub grad: [f64; 9],
    /// ∂²/∂x∂x, symmetric.
    pub hess: [[f64; 9]; 9],
}

impl Local {
    /// Adds `s` times `other` (value, gradient and Hessian).
    pub fn add_scaled(&mut self, other: &Local, s: f64) {
        self.value += s * other.value;
        self.grad
            .iter_mut()
            .zip(other.grad)
            .for_each(|(a, b)| *a += s * b);
        self.hess
            .iter_mut()
            .flatten()
            .zip(other.hess.iter().flatten())
            .for_each(|(a, b)| *a += s * b);
    }

    /// `s` times value, gradient and Hessian.
    pub fn scaled(&self, s: f64) -> Local {
        let mut out = *self;
        out.value *= s;
        out.grad.iter_mut().for_each(|g| *g *= s);
        out.hess.iter_mut().flatten().for_each(|h| *h *= s);
        out
    }
}

impl Local {
    /// Zero value, gradient and Hessian.
    pub const ZERO: Local = Local {
        value: 0.0,
        grad: [0.0; 9],
        hess: [[0.0; 9]; 9],
    };

    /// Copies the upper triangle of the Hessian onto the lower one, so that it is symmetric to
    /// the last bit whatever order the kernel summed its terms in.
    pub fn mirror_upper(&mut self) {
        for a in 0..9 {
            for b in 0..a {
                self.hess[a][b] = self.hess[b][a];
            }
        }
    }
}

impl Default for Local {
    fn default() -> Self {
        Self::ZERO
    }
}
