//! Limits on what one request may cost, checked before anything is allocated: the memory a
//! run is estimated to need, the order of a symmetry group, the size of a scene file. A
//! request over a limit is refused with its estimate and the limit (exit code 2), never
//! started and left to exhaust the machine.
//!
//! The limits come from the environment: `MEMSTAB_MAX_MEMORY` (bytes, or with a suffix
//! `K`, `M`, `G`: `12G`; default three quarters of the physical memory, 8 GiB where that is
//! unknown), `MEMSTAB_MAX_GROUP_ORDER` (default 720: C360v is built in about 2 s, the cost
//! grows as the cube of the order) and `MEMSTAB_MAX_SCENE_BYTES` (default 16 MiB).

/// The limits of one process.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Bytes a request may be estimated to need.
    pub memory: u64,
    /// Largest order of a point group.
    pub group_order: usize,
    /// Largest scene file, in bytes.
    pub scene_bytes: u64,
}

/// A request over a limit.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LimitError {
    /// The estimated memory exceeds the limit.
    #[error("{what} would need about {} of memory, more than the limit of {} (MEMSTAB_MAX_MEMORY)", bytes(*.estimate), bytes(*.limit))]
    Memory {
        /// What was asked for.
        what: String,
        /// The estimate, bytes.
        estimate: u64,
        /// The limit, bytes.
        limit: u64,
    },
    /// A group's order exceeds the limit.
    #[error(
        "group {name} has order {order}, more than the limit of {limit} (MEMSTAB_MAX_GROUP_ORDER)"
    )]
    GroupOrder {
        /// Its name.
        name: String,
        /// Its order.
        order: usize,
        /// The limit.
        limit: usize,
    },
    /// A limit in the environment does not parse.
    #[error("{variable} = '{value}': expected a positive whole number{}", if *.bytes { " of bytes, with an optional suffix K, M or G" } else { "" })]
    Environment {
        /// The variable.
        variable: &'static str,
        /// Its value (cut to 80 characters).
        value: String,
        /// Whether it is a size in bytes.
        bytes: bool,
    },
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            memory: physical_memory().map_or(8 << 30, |m| m / 4 * 3),
            group_order: 720,
            scene_bytes: 16 << 20,
        }
    }
}

impl Limits {
    /// The defaults with the environment's overrides.
    pub fn from_env() -> Result<Self, LimitError> {
        let mut limits = Self::default();
        if let Some(v) = read_env("MEMSTAB_MAX_MEMORY", true)? {
            limits.memory = v;
        }
        if let Some(v) = read_env("MEMSTAB_MAX_GROUP_ORDER", false)? {
            limits.group_order = usize::try_from(v).unwrap_or(usize::MAX);
        }
        if let Some(v) = read_env("MEMSTAB_MAX_SCENE_BYTES", true)? {
            limits.scene_bytes = v;
        }
        Ok(limits)
    }

    /// Refuses an estimate of `estimate` bytes for `what` above the memory limit.
    pub fn check_memory(&self, what: impl Into<String>, estimate: u64) -> Result<(), LimitError> {
        if estimate > self.memory {
            return Err(LimitError::Memory {
                what: what.into(),
                estimate,
                limit: self.memory,
            });
        }
        Ok(())
    }

    /// Refuses the group `name` when its order (known from the name, without building it)
    /// exceeds the limit.
    pub fn check_group(&self, name: &str) -> Result<(), LimitError> {
        match symmetry::Group::order_of(name) {
            Some(order) if order > self.group_order => Err(LimitError::GroupOrder {
                name: name.to_string(),
                order,
                limit: self.group_order,
            }),
            _ => Ok(()),
        }
    }
}

/// `n` bytes for a message: `4.8 GB`, `512 KB`, `12 B`.
pub fn bytes(n: u64) -> String {
    let units = [("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("KB", 1e3)];
    units.iter().find(|(_, u)| n as f64 >= *u).map_or_else(
        || format!("{n} B"),
        |(name, u)| format!("{:.1} {name}", n as f64 / u),
    )
}

fn read_env(variable: &'static str, bytes: bool) -> Result<Option<u64>, LimitError> {
    let Ok(value) = std::env::var(variable) else {
        return Ok(None);
    };
    parse_size(value.trim(), bytes)
        .map(Some)
        .ok_or_else(|| LimitError::Environment {
            variable,
            value: value.chars().take(80).collect(),
            bytes,
        })
}

/// A positive whole number, with a K/M/G suffix (powers of 1024) when `bytes`.
fn parse_size(text: &str, bytes: bool) -> Option<u64> {
    let (digits, scale) = match text.char_indices().last()? {
        (i, 'K' | 'k') if bytes => (&text[..i], 1u64 << 10),
        (i, 'M' | 'm') if bytes => (&text[..i], 1 << 20),
        (i, 'G' | 'g') if bytes => (&text[..i], 1 << 30),
        _ => (text, 1),
    };
    let n: u64 = digits.parse().ok()?;
    (n > 0).then(|| n.checked_mul(scale)).flatten()
}

/// MemTotal of `/proc/meminfo` in bytes (Linux).
fn physical_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let kib: u64 = info
        .lines()
        .find_map(|l| l.strip_prefix("MemTotal:"))?
        .split_whitespace()
        .next()?
        .parse()
        .ok()?;
    Some(kib * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_and_print() {
        assert_eq!(parse_size("12G", true), Some(12 << 30));
        assert_eq!(parse_size("800m", true), Some(800 << 20));
        assert_eq!(parse_size("4096", true), Some(4096));
        assert_eq!(parse_size("12G", false), None);
        assert_eq!(parse_size("0", true), None);
        assert_eq!(parse_size("-5", true), None);
        assert_eq!(parse_size("99999999999999999999G", true), None);
        assert_eq!(bytes(4_800_000_000), "4.8 GB");
        assert_eq!(bytes(12), "12 B");
    }

    #[test]
    fn limits_refuse_with_the_estimate() {
        let l = Limits {
            memory: 1 << 30,
            group_order: 720,
            scene_bytes: 1 << 20,
        };
        assert!(l.check_memory("x", 1 << 29).is_ok());
        let e = l.check_memory("the mesh", 5 << 30).unwrap_err().to_string();
        assert!(e.contains("5.4 GB") && e.contains("1.1 GB"), "{e}");
        assert!(l.check_group("C360v").is_ok());
        let e = l.check_group("C800v").unwrap_err().to_string();
        assert!(e.contains("1600") && e.contains("720"), "{e}");
    }
}
