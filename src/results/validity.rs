//! Whether a critical point is a result of the model as it stands (docs/theory.md §8.10), and
//! of the mesh (§8.11, with `--refine`): a small set of typed flags, each with its measure. A
//! point with no flag is *valid*.

use super::PathReport;
use serde::Serialize;

/// The largest |eigenvalue|/‖K‖ of a localised critical point: every localised crossing of
/// the bundled scenes ends below 1e-10; a larger residual means the localisation stopped
/// short of the zero (the eigenvalue jumped, or the bracket could not be narrowed).
pub const LOCALISED: f64 = 1e-8;

/// Why a critical point may not be a result of the model.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "flag", rename_all = "kebab-case")]
pub enum Flag {
    /// Triangles of its state have a negative principal tension: they would wrinkle, and the
    /// plain membrane energy does not describe them (the relaxed energy does, and raises no
    /// flag).
    Wrinkled {
        /// The wrinkled triangles.
        triangles: usize,
        /// The mesh's triangles.
        of: usize,
        /// The critical mode's share on the wrinkled triangles' nodes (Σ |φ_n|² there over
        /// Σ |φ_n|²).
        mode: f64,
    },
    /// The critical eigenvalue was not brought to round-off: the point is where the
    /// localisation stopped, not a zero of the block.
    NotLocalised {
        /// |eigenvalue| / ‖K‖ at the point.
        residual: f64,
    },
    /// A refined mesh has no counterpart of the point (matched by irrep, wave number and
    /// value as `memstab compare` matches): the point is not mesh-converged.
    NotMeshConverged {
        /// That mesh, as one line (e.g. `icosphere frequency=8`).
        finer: String,
    },
}

impl std::fmt::Display for Flag {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Flag::Wrinkled {
                triangles,
                of,
                mode,
            } => write!(
                f,
                "wrinkled, {triangles} of {of} triangles with a negative principal tension, \
                 {:.0} % of the mode there",
                100.0 * mode
            ),
            Flag::NotLocalised { residual } => write!(
                f,
                "not localised, |eigenvalue|/|K| = {residual:.0e} > {LOCALISED:.0e}"
            ),
            Flag::NotMeshConverged { finer } => {
                write!(f, "not mesh-converged, no counterpart on {finer}")
            }
        }
    }
}

impl PathReport {
    /// The flags of critical point `k` (from 0, the order of `critical`): empty for a valid
    /// point.
    pub fn flags(&self, k: usize) -> Vec<Flag> {
        let mut flags = Vec::new();
        let Some(cp) = self.critical.get(k) else {
            return flags;
        };
        if let Some(w) = self.wrinkling.as_ref().filter(|w| !w.relaxed) {
            if let Some(c) = w.critical.iter().find(|c| c.critical == k + 1) {
                flags.push(Flag::Wrinkled {
                    triangles: c.wrinkled,
                    of: w.triangles,
                    mode: c.mode,
                });
            }
        }
        if cp.residual_eigenvalue > LOCALISED {
            flags.push(Flag::NotLocalised {
                residual: cp.residual_eigenvalue,
            });
        }
        if let Some(r) = &self.refinement {
            for p in r.critical.iter().filter(|p| p.points.contains(&(k + 1))) {
                if let super::refine::Estimate::NotMeshConverged { finer } = &p.estimate {
                    flags.push(Flag::NotMeshConverged {
                        finer: finer.clone(),
                    });
                }
            }
        }
        flags
    }
}
