//! [`SceneError`]: everything that can be wrong with a scene file, as one line.

use std::path::PathBuf;

/// A scene file that cannot be used. Every variant is an error in the user's input (the CLI
/// maps all of them to exit code 2) and displays as one line that names the file, the key
/// path (`effect[1].pressure`, indices from 0) and the offending value.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("{}: cannot read the scene file: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The path names no regular file (a FIFO, a device, a directory): refused before it is
    /// opened, since opening a FIFO waits for a writer.
    #[error("{}: the scene file is {what}, not a regular file; give the path of a scene's TOML file", path.display())]
    NotRegular {
        /// The path.
        path: PathBuf,
        /// What it is (`a FIFO`, `a directory` …).
        what: &'static str,
    },
    /// The file is larger than a scene may be (`MEMSTAB_MAX_SCENE_BYTES`).
    #[error("{}: the scene file is larger than {} (MEMSTAB_MAX_SCENE_BYTES); a scene is a short text", path.display(), crate::limits::bytes(*limit))]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// The limit, bytes.
        limit: u64,
    },
    /// A limit in the environment does not parse.
    #[error("{0}")]
    Limit(#[from] crate::limits::LimitError),
    /// The text is not valid TOML.
    #[error("{}{line}:{column}: TOML syntax error: {message}", prefix(origin, ":"))]
    Syntax {
        /// Where the text came from (a file name), possibly empty.
        origin: String,
        /// 1-based line of the error.
        line: usize,
        /// 1-based column (in characters) of the error.
        column: usize,
        /// What the TOML parser said (one line).
        message: String,
    },
    /// The TOML is valid but the scene is not: an unknown key, a missing field, a value of
    /// the wrong type, a non-physical value, a reference to something that does not exist.
    #[error("{}{message}", prefix(origin, ": "))]
    Invalid {
        /// Where the text came from (a file name), possibly empty.
        origin: String,
        /// The key path of the offending value, e.g. `material.mu` or `effect[1].pressure`
        /// (empty for the document as a whole).
        key: String,
        /// The complete message, which names `key` and the value.
        message: String,
    },
}

fn prefix(origin: &str, sep: &str) -> String {
    if origin.is_empty() {
        String::new()
    } else {
        format!("{origin}{sep}")
    }
}

impl SceneError {
    /// The key path of an [`SceneError::Invalid`] error (`None` for the other variants).
    pub fn key(&self) -> Option<&str> {
        match self {
            SceneError::Invalid { key, .. } => Some(key),
            _ => None,
        }
    }

    /// The same error attributed to `origin` (a file name), if it has none yet.
    pub fn with_origin(mut self, new: &str) -> Self {
        match &mut self {
            SceneError::Syntax { origin, .. } | SceneError::Invalid { origin, .. }
                if origin.is_empty() =>
            {
                *origin = new.to_string();
            }
            _ => {}
        }
        self
    }
}

/// An [`SceneError::Invalid`] before it knows its origin: what a check of a scene's keys
/// returns.
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    /// The key path of the offending value.
    pub key: String,
    /// The complete message, which names `key` and the value.
    pub message: String,
}

impl Problem {
    /// `'<key>' <what>`, e.g. `Problem::at("material.mu", "must be > 0, got 0")`.
    pub fn at(key: &str, what: impl std::fmt::Display) -> Self {
        Problem {
            key: key.to_string(),
            message: format!("'{key}' {what}"),
        }
    }

    /// A free-form message that must itself name `key`.
    pub fn new(key: &str, message: impl Into<String>) -> Self {
        Problem {
            key: key.to_string(),
            message: message.into(),
        }
    }

    pub fn into_error(self, origin: &str) -> SceneError {
        SceneError::Invalid {
            origin: origin.to_string(),
            key: self.key,
            message: self.message,
        }
    }
}

impl From<Problem> for SceneError {
    fn from(p: Problem) -> Self {
        p.into_error("")
    }
}

pub(crate) use crate::text::key_value as num;
