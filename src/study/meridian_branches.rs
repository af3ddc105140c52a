//! Branch switching on the meridian (docs/theory.md §14, §15): a critical point of wave number
//! m ≥ 1 leaves the axisymmetric states, which the meridian cannot follow; one of m = 0 is a
//! bifurcation inside them.

use super::meridian::MeridianStudy;
use super::BranchOptions;
use crate::axisym::blocks::wave_number;
use crate::results::{Branches, CriticalPoint};

/// The branches of the meridian's critical points `critical` that `options` asks for.
pub fn switch(
    _study: &MeridianStudy,
    critical: &[CriticalPoint],
    options: BranchOptions,
) -> Result<Branches, String> {
    for (k, cp) in critical.iter().enumerate() {
        let requested = options.points.as_ref().is_none_or(|p| p.contains(&(k + 1)));
        let m = wave_number(&cp.irrep).unwrap_or(0);
        if requested && m >= 1 {
            return Err(refusal(k + 1, m));
        }
    }
    Err("branch switching at an m = 0 point of the meridian is not implemented yet".into())
}

/// Why a branch of wave number m ≥ 1 is not followed on the meridian, and where it is.
pub fn refusal(number: usize, m: usize) -> String {
    format!(
        "critical point {number} (m = {m}): its branches leave the axisymmetric states, which \
         the meridian cannot follow; run the scene on a 3-D mesh whose group keeps the mode's \
         isotropy C{m}v (a disc or truncated sphere with group C{}v, for instance)",
        if m == 1 { 8 } else { 4 * m }
    )
}
