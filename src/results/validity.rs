//! Whether a critical or turning point is a result of the model as it stands (docs/theory.md
//! §8.10), and of the mesh (§8.11, with `--refine`): a small set of typed flags, each with its
//! measure. A point with no flag is *valid*; a path row carries the flags of its state
//! (`wrinkled`, `stretch`) by name, as `path.csv`'s `flags` column.

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
        /// Σ |φ_n|²); none for a turning point, which has no mode.
        #[serde(skip_serializing_if = "Option::is_none")]
        mode: Option<f64>,
    },
    /// The critical eigenvalue was not brought to round-off: the point is where the
    /// localisation stopped, not a zero of the block.
    NotLocalised {
        /// |eigenvalue| / ‖K‖ at the point.
        residual: f64,
        /// The width of the localisation's last bracket, as a share of the step (none for a
        /// point read back from a finished run).
        #[serde(skip_serializing_if = "Option::is_none")]
        bracket: Option<f64>,
    },
    /// The contact set (the nodes in contact with a penalty plane) changed within the
    /// localisation's last bracket: the eigenvalue's zero lies where a node enters or leaves
    /// contact, where the penalty's stiffness jumps (linear) or starts (cubic), and may be
    /// that of the node-wise contact rather than of the membrane.
    ContactJump {
        /// The nodes whose contact changed between the bracket's ends.
        nodes: usize,
        /// The deepest penetration ⟨−δ⟩ at the point over the mean edge length there.
        penetration: f64,
        /// The bracket's width, as a share of the step.
        bracket: f64,
    },
    /// A principal stretch beyond the range the material states (`material.max-stretch`):
    /// the constitutive law is used where it was not meant to hold.
    Stretch {
        /// The largest principal stretch of the state's triangles.
        stretch: f64,
        /// The material's stated largest stretch.
        max: f64,
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
            } => {
                write!(
                    f,
                    "wrinkled, {triangles} of {of} elements with a negative principal tension"
                )?;
                match mode {
                    Some(mode) => write!(f, ", {:.0} % of the mode there", 100.0 * mode),
                    None => Ok(()),
                }
            }
            Flag::NotLocalised { residual, bracket } => {
                write!(
                    f,
                    "not localised, |eigenvalue|/|K| = {residual:.0e} > {LOCALISED:.0e}"
                )?;
                match bracket {
                    Some(w) => write!(f, " in a bracket of {w:.0e} of the step"),
                    None => Ok(()),
                }
            }
            Flag::ContactJump {
                nodes,
                penetration,
                bracket,
            } => write!(
                f,
                "contact jump, {nodes} nodes entered or left contact within the bracket of \
                 {bracket:.0e} of the step (deepest penetration {penetration:.1e} of the \
                 element size)"
            ),
            Flag::Stretch { stretch, max } => write!(
                f,
                "stretch {stretch:.4} beyond the material's range (max-stretch = {max})"
            ),
            Flag::NotMeshConverged { finer } => {
                write!(f, "not mesh-converged, no counterpart on {finer}")
            }
        }
    }
}

/// What a study measured of a run's states for their validity (docs/theory.md §8.10), as
/// plain data: every path row's, turning point's and critical point's state.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Checks {
    /// The material's largest principal stretch (`material.max-stretch`), if it states one.
    pub max_stretch: Option<f64>,
    /// The mesh's triangles.
    pub triangles: usize,
    /// Whether the membrane has the relaxed energy, which describes wrinkled states.
    pub relaxed: bool,
    /// Every path row's state, in the order of `rows`.
    pub rows: Vec<StateCheck>,
    /// Every turning point's, in the order of `turning_points`.
    pub turning: Vec<StateCheck>,
    /// Every critical point's, in the order of `critical`.
    pub critical: Vec<StateCheck>,
}

/// What was measured of one state (`None`: not measured by the model).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StateCheck {
    /// Triangles with a negative principal tension.
    pub wrinkled: Option<usize>,
    /// The largest principal stretch of its triangles.
    pub stretch: Option<f64>,
    /// A critical point's contact: how the contact set changed within its localisation
    /// bracket (with a contact effect and a bracket); a turning point's within the bracket
    /// of the corner it turns at.
    pub contact: Option<ContactChange>,
}

/// How the contact set changed within a critical point's localisation bracket.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ContactChange {
    /// The nodes in contact at one end of the bracket and not at the other.
    pub changed: usize,
    /// The deepest penetration at the point over the mean edge length there.
    pub penetration: f64,
    /// The bracket's width, as a share of the step.
    pub bracket: f64,
}

impl Checks {
    /// The flags a state's measures raise: `wrinkled` (under the plain energy; `mode` the
    /// critical mode's share there, if any) and `stretch`.
    pub fn state_flags(&self, check: &StateCheck, mode: Option<f64>) -> Vec<Flag> {
        let mut flags = Vec::new();
        if let Some(n) = check.wrinkled.filter(|&n| n > 0 && !self.relaxed) {
            flags.push(Flag::Wrinkled {
                triangles: n,
                of: self.triangles,
                mode,
            });
        }
        if let (Some(max), Some(stretch)) = (self.max_stretch, check.stretch) {
            if stretch > max {
                flags.push(Flag::Stretch { stretch, max });
            }
        }
        flags
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
                    mode: Some(c.mode),
                });
            }
        }
        if cp.residual_eigenvalue > LOCALISED {
            flags.push(Flag::NotLocalised {
                residual: cp.residual_eigenvalue,
                bracket: cp.bracket.as_ref().map(|b| b.width),
            });
        }
        if let Some((checks, check)) = self
            .checks
            .as_ref()
            .and_then(|c| Some((c, c.critical.get(k)?)))
        {
            if let Some(c) = check.contact.filter(|c| c.changed > 0) {
                flags.push(Flag::ContactJump {
                    nodes: c.changed,
                    penetration: c.penetration,
                    bracket: c.bracket,
                });
            }
            // The wrinkled elements are counted above, with the mode's share, where the run
            // has a wrinkling record (a 3-D mesh); else (a meridian) from the point's state.
            let rest = StateCheck {
                wrinkled: check.wrinkled.filter(|_| self.wrinkling.is_none()),
                ..check.clone()
            };
            flags.extend(checks.state_flags(&rest, None));
        }
        if let Some(r) = &self.refinement {
            for p in r.critical.iter().filter(|p| p.points.contains(&(k + 1))) {
                if let super::refine::Estimate::NotMeshConverged { finer } = &p.series.estimate {
                    flags.push(Flag::NotMeshConverged {
                        finer: finer.clone(),
                    });
                }
            }
        }
        flags
    }

    /// The flags of turning point `t` (from 0, path order): `contact-jump` where the control
    /// turns at a corner of the path, a change of the contact set (docs/theory.md §8.9), its
    /// state's (`wrinkled`, `stretch`) and, with `--refine`, `not-mesh-converged`.
    pub fn turning_flags(&self, t: usize) -> Vec<Flag> {
        let mut flags = match self.checks.as_ref() {
            Some(c) => c.turning.get(t).map_or_else(Vec::new, |check| {
                let jump = check
                    .contact
                    .filter(|c| c.changed > 0)
                    .map(|c| Flag::ContactJump {
                        nodes: c.changed,
                        penetration: c.penetration,
                        bracket: c.bracket,
                    });
                jump.into_iter().chain(c.state_flags(check, None)).collect()
            }),
            None => Vec::new(),
        };
        if let Some(r) = &self.refinement {
            for p in r.turning.iter().filter(|p| p.points.contains(&(t + 1))) {
                if let super::refine::Estimate::NotMeshConverged { finer } = &p.series.estimate {
                    flags.push(Flag::NotMeshConverged {
                        finer: finer.clone(),
                    });
                }
            }
        }
        flags
    }

    /// The names of the flags of path row `i`'s state (`wrinkled`, `stretch`): empty where
    /// it is valid or not measured.
    pub fn row_flags(&self, i: usize) -> Vec<&'static str> {
        let Some(c) = self.checks.as_ref() else {
            return Vec::new();
        };
        c.rows.get(i).map_or_else(Vec::new, |check| {
            c.state_flags(check, None).iter().map(Flag::name).collect()
        })
    }
}

impl Flag {
    /// Its name, as `flag` in the files: `wrinkled`, `not-localised`, `contact-jump`,
    /// `stretch`, `not-mesh-converged`.
    pub fn name(&self) -> &'static str {
        match self {
            Flag::Wrinkled { .. } => "wrinkled",
            Flag::NotLocalised { .. } => "not-localised",
            Flag::ContactJump { .. } => "contact-jump",
            Flag::Stretch { .. } => "stretch",
            Flag::NotMeshConverged { .. } => "not-mesh-converged",
        }
    }
}

impl super::refine::Refinement {
    /// The flags it raises on a critical curve's event `number` (from 1, the curve's order):
    /// `not-mesh-converged` where a refined mesh has no counterpart of it.
    pub fn event_flags(&self, number: usize) -> Vec<Flag> {
        self.events
            .iter()
            .filter(|e| e.event == number)
            .filter_map(|e| match &e.control.estimate {
                super::refine::Estimate::NotMeshConverged { finer } => {
                    Some(Flag::NotMeshConverged {
                        finer: finer.clone(),
                    })
                }
                _ => None,
            })
            .collect()
    }
}

impl super::CurveReport {
    /// Adds the flags `refinement` raises to its events (`not-mesh-converged`).
    pub fn flag_refined(&mut self, refinement: &super::refine::Refinement) {
        for (k, e) in self.events.iter_mut().enumerate() {
            e.flags.extend(refinement.event_flags(k + 1));
        }
    }
}
