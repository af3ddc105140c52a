//! The scaling study: balloon paths of a fixed number of points with the index by irrep at
//! every point, their time by phase and peak resident memory ([`memory`]), and the growth
//! exponents of time and memory against the unknowns ([`ScalingFits`]).

use super::balloon::{balloon_level_with, BalloonLevel, LevelOptions};

/// Resident memory of this process, from `/proc/self` (Linux; elsewhere every function says
/// it cannot).
pub mod memory {
    /// Resets the peak resident set size (`VmHWM`) to the current one by writing "5" to
    /// `/proc/self/clear_refs` (Linux ≥ 4.0). `false` where that is not possible.
    pub fn reset_peak() -> bool {
        std::fs::write("/proc/self/clear_refs", "5").is_ok()
    }

    /// A `kB` field of `/proc/self/status`, in KiB.
    fn status_kib(field: &str) -> Option<u64> {
        let status = std::fs::read_to_string("/proc/self/status").ok()?;
        status.lines().find_map(|l| {
            let rest = l.strip_prefix(field)?.strip_prefix(':')?;
            rest.split_whitespace().next()?.parse().ok()
        })
    }

    /// Peak resident set size since the start or the last [`reset_peak`] (`VmHWM`), KiB.
    pub fn peak_kib() -> Option<u64> {
        status_kib("VmHWM")
    }

    /// Current resident set size (`VmRSS`), KiB.
    pub fn current_kib() -> Option<u64> {
        status_kib("VmRSS")
    }
}

/// One level of the scaling study: a balloon path of a fixed number of points with the
/// spectrum by irrep at every point, and the memory it took.
#[derive(Debug, Clone)]
pub struct ScalingLevel {
    /// The path and its phase times ([`BalloonLevel::states`] not kept).
    pub level: BalloonLevel,
    /// Resident memory when the level started (after the previous level was dropped; the
    /// allocator may keep some of it), KiB.
    pub rss_start_kib: Option<u64>,
    /// Peak resident memory during the level (`VmHWM` after a reset at its start), KiB.
    pub peak_kib: Option<u64>,
}

/// A level of the scaling study: the balloon of `frequency` followed for `points` points
/// with full stability by irrep at every point ([`balloon_level_with`]), its peak resident
/// memory measured by resetting the high-water mark first ([`memory`]).
pub fn scaling_level(frequency: usize, points: usize) -> Result<ScalingLevel, String> {
    let reset = memory::reset_peak();
    let rss_start_kib = memory::current_kib();
    let options = LevelOptions {
        stability: true,
        keep_states: false,
        max_points: Some(points),
        index_only: true,
    };
    let (level, study) = balloon_level_with(frequency, &options)?;
    let peak_kib = if reset { memory::peak_kib() } else { None };
    drop(study);
    Ok(ScalingLevel {
        level,
        rss_start_kib,
        peak_kib,
    })
}

/// The exponent b of y ≈ a xᵇ by least squares on (ln x, ln y); `None` with fewer than two
/// distinct positive x or a non-positive value.
pub fn fit_exponent(points: &[(f64, f64)]) -> Option<f64> {
    if points
        .iter()
        .any(|&(x, y)| !(x > 0.0 && y > 0.0 && x.is_finite() && y.is_finite()))
    {
        return None;
    }
    let n = points.len() as f64;
    let lx: Vec<f64> = points.iter().map(|p| p.0.ln()).collect();
    let ly: Vec<f64> = points.iter().map(|p| p.1.ln()).collect();
    let mx = lx.iter().sum::<f64>() / n;
    let my = ly.iter().sum::<f64>() / n;
    let sxx: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    (points.len() >= 2 && sxx > 1e-12).then(|| sxy / sxx)
}

/// Growth exponents b of y ∝ unknowns^b over the scaling levels ([`fit_exponent`]); `None`
/// without two levels of different size (or, for memory, without a peak measured).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScalingFits {
    /// The total wall time of a level.
    pub total: Option<f64>,
    /// The path without stability ([`BalloonLevel::path_time`]).
    pub path: Option<f64>,
    /// Stability by irrep ([`BalloonLevel::stability_time`]).
    pub stability: Option<f64>,
    /// The peak resident memory.
    pub memory: Option<f64>,
}

impl ScalingFits {
    /// The exponents over `levels`.
    pub fn new(levels: &[ScalingLevel]) -> Self {
        let fit = |y: &dyn Fn(&ScalingLevel) -> Option<f64>| -> Option<f64> {
            let pts: Option<Vec<(f64, f64)>> = levels
                .iter()
                .map(|l| y(l).map(|v| (l.level.unknowns as f64, v)))
                .collect();
            fit_exponent(&pts?)
        };
        Self {
            total: fit(&|l| Some(l.level.total.as_secs_f64())),
            path: fit(&|l| Some(l.level.path_time().as_secs_f64())),
            stability: fit(&|l| Some(l.level.stability_time().as_secs_f64())),
            memory: fit(&|l| l.peak_kib.map(|k| k as f64 / 1024.0)),
        }
    }
}
