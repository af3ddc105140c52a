//! Numbers and messages as the toolkit writes them in its reports and one-line errors.

/// Joins the lines of a message into one.
pub fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// `x` with `digits` significant digits, plain for moderate sizes (`1.35511`, `0.000123457`),
/// else in exponent form (`1.23457e7`).
pub fn sig_digits(x: f64, digits: usize) -> String {
    let a = x.abs();
    if a == 0.0 || !a.is_finite() {
        return format!("{x}");
    }
    let e = a.log10().floor() as i32;
    let digits = digits.max(1) as i32;
    if (-4..6).contains(&e) {
        let decimals = (digits - 1 - e).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        let decimals = (digits - 1) as usize;
        format!("{x:.decimals$e}")
    }
}

/// A short scientific form for eigenvalues and gaps: `1.234e-3`, `-5.000e0`, `0`.
pub fn sci(x: f64) -> String {
    if x == 0.0 {
        "0".to_string()
    } else {
        format!("{x:.3e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats() {
        assert_eq!(sig_digits(1.3551069, 6), "1.35511");
        assert_eq!(sig_digits(0.000123456789, 6), "0.000123457");
        assert_eq!(sig_digits(12345678.0, 6), "1.23457e7");
        assert_eq!(sci(0.0), "0");
        assert_eq!(sci(-5.0), "-5.000e0");
        assert_eq!(one_line("a\n  b\tc"), "a b c");
    }
}
