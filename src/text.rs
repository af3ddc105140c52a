//! Numbers and messages as the toolkit writes them in its reports and one-line errors.

/// Joins the lines of a message into one.
pub fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Longest message [`message`] keeps whole.
pub const MESSAGE_LENGTH: usize = 400;

/// A message as one line of at most [`MESSAGE_LENGTH`] characters: line breaks and runs of
/// white space become one space, and a longer message (a value echoed from a huge input)
/// keeps its start and its end around ` … `.
pub fn message(s: &str) -> String {
    let line = one_line(s);
    let n = line.chars().count();
    if n <= MESSAGE_LENGTH {
        return line;
    }
    let head: String = line.chars().take(MESSAGE_LENGTH - 100).collect();
    let tail: String = line.chars().skip(n - 80).collect();
    format!(
        "{head} … ({} characters) … {tail}",
        n - (MESSAGE_LENGTH - 100) - 80
    )
}

/// A number for a message: the shortest form that reads back to the same value, in
/// exponent form when that is shorter (`1e300`, not three hundred digits).
pub fn num(x: f64) -> String {
    let plain = format!("{x}");
    let exp = format!("{x:e}");
    if exp.len() < plain.len() {
        exp
    } else {
        plain
    }
}

/// A key's value as a scene error quotes it: plain when of moderate size, else in exponent
/// form.
pub fn key_value(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-4..1e7).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
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
        assert_eq!(num(1e300), "1e300");
        assert_eq!(num(0.25), "0.25");
        assert_eq!(num(1.5e-7), "1.5e-7");
        let long = format!("key = '{}' and more", "x".repeat(100_000));
        let m = message(&long);
        assert!(m.chars().count() < MESSAGE_LENGTH + 40, "{}", m.len());
        assert!(m.starts_with("key = 'xxx") && m.ends_with("and more"));
        assert_eq!(message("two\nlines"), "two lines");
    }
}
