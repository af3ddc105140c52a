//! `.memstab.lock`: the lock a run takes in its output directory before its analysis starts,
//! so that a second run into the same directory is refused up front instead of the two
//! overwriting each other's files (and one sweeping the other's temporary files). The file
//! holds the owner's process id; it is removed when the run ends. A lock whose process is
//! gone (killed with SIGKILL, a second signal) is stale and taken over.

use std::io::Write;
use std::path::{Path, PathBuf};

/// The lock file's name in a run's directory.
pub const LOCK: &str = ".memstab.lock";

/// Why the lock could not be taken.
#[derive(Debug, thiserror::Error)]
pub enum LockError {
    /// Another process holds it (bad input: the directory is in use).
    #[error(
        "'{}' is in use by another memstab run (process {pid}, lock file {}); wait for it to \
         end or give another directory (remove the lock file if no run is going on)",
        .dir.display(),
        .file.display()
    )]
    Busy {
        /// The directory.
        dir: PathBuf,
        /// The lock file.
        file: PathBuf,
        /// The process that holds it.
        pid: u32,
    },
    /// The lock file could not be made or read.
    #[error("cannot take the lock {}: {source}", .file.display())]
    Io {
        /// The lock file.
        file: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
}

/// A held lock; dropping it removes the file.
#[derive(Debug)]
pub struct RunLock {
    file: PathBuf,
}

/// Whether process `pid` is running (where this cannot be told, it is taken to be).
fn alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    let proc = Path::new("/proc");
    if proc.join("self").exists() {
        proc.join(pid.to_string()).exists()
    } else {
        true
    }
}

impl RunLock {
    /// Takes the lock of `dir` (an existing directory) for this process.
    ///
    /// # Errors
    /// [`LockError::Busy`] when a running process holds it, [`LockError::Io`] when the file
    /// cannot be made.
    pub fn acquire(dir: &Path) -> Result<Self, LockError> {
        let file = dir.join(LOCK);
        let io = |source| LockError::Io {
            file: file.clone(),
            source,
        };
        for _ in 0..3 {
            match std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&file)
            {
                Ok(mut f) => {
                    writeln!(f, "{}", std::process::id()).map_err(io)?;
                    return Ok(Self { file });
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    // The holder writes its id right after creating the file: an empty
                    // file is a lock being taken.
                    let text = std::fs::read_to_string(&file).unwrap_or_default();
                    match text.trim().parse::<u32>() {
                        Ok(pid) if !alive(pid) => {
                            // Stale: its process is gone.
                            let _ = std::fs::remove_file(&file);
                        }
                        Ok(pid) => {
                            return Err(LockError::Busy {
                                dir: dir.to_path_buf(),
                                file,
                                pid,
                            })
                        }
                        Err(_) => std::thread::sleep(std::time::Duration::from_millis(50)),
                    }
                }
                Err(e) => return Err(io(e)),
            }
        }
        let text = std::fs::read_to_string(&file).unwrap_or_default();
        Err(LockError::Busy {
            dir: dir.to_path_buf(),
            file,
            pid: text.trim().parse().unwrap_or(0),
        })
    }
}

impl Drop for RunLock {
    fn drop(&mut self) {
        // Only this process' own lock.
        let ours = std::fs::read_to_string(&self.file)
            .is_ok_and(|t| t.trim() == std::process::id().to_string());
        if ours {
            let _ = std::fs::remove_file(&self.file);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_lock_is_refused_and_a_stale_one_taken_over() {
        let dir = tempfile::tempdir().unwrap();
        let lock = RunLock::acquire(dir.path()).unwrap();
        let again = RunLock::acquire(dir.path()).unwrap_err();
        assert!(matches!(again, LockError::Busy { pid, .. } if pid == std::process::id()));
        assert!(again.to_string().contains(LOCK));
        drop(lock);
        assert!(!dir.path().join(LOCK).exists());
        // A lock of a process that is gone (no process has id u32::MAX - 1 on Linux).
        std::fs::write(dir.path().join(LOCK), format!("{}\n", u32::MAX - 1)).unwrap();
        if Path::new("/proc/self").exists() {
            let lock = RunLock::acquire(dir.path()).unwrap();
            drop(lock);
            assert!(!dir.path().join(LOCK).exists());
        }
    }
}
