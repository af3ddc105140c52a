//! Helpers shared by the commands: loading a scene and building its study with the exit
//! codes of `memstab run`, the `--at NAME=VALUE` overrides, and number formatting.

use super::CliError;
use memstab::scene::Scene;
use memstab::study::mesh::{MeshStudy, StudyError};
use std::path::Path;

/// Loads and validates a scene file; any problem is bad input (exit 2).
pub(super) fn load_scene(path: &Path) -> Result<Scene, CliError> {
    Scene::load(path).map_err(|e| CliError::Input(one_line(&e.to_string())))
}

/// Builds the study (mesh, the scene's group, effects, model); a scene that cannot be built is
/// bad input (exit 2), as in `memstab run`.
pub(super) fn build_study(scene: Scene) -> Result<MeshStudy, CliError> {
    MeshStudy::build(scene).map_err(|e| match e {
        StudyError::Scene(_) | StudyError::Unsupported(_) | StudyError::Limit(_) => {
            CliError::Input(one_line(&e.to_string()))
        }
    })
}

/// The start the study's scene asks for ([`memstab::analysis::restart::start_of`]): a
/// `[start] from` or a critical curve's `from-run` that cannot be read or does not fit is
/// bad input (the message names the scene file and the key).
pub(super) fn start_of(study: &MeshStudy) -> Result<memstab::study::Start, CliError> {
    memstab::analysis::restart::start_of(study)
        .map_err(|e| CliError::Input(one_line(&format!("{}: {e}", study.scene.origin))))
}

/// A saved path point of a finished run, as `spectrum` and `export-matrix` analyse it with
/// `--point`: the run read back, its scene rebuilt (`scene`, else the file recorded in
/// `path.json`) and checked against it, and point `n`'s displacement and parameters from
/// `path.states`. Anything missing or not matching is bad input (exit 2).
pub(super) struct SavedPoint {
    pub study: MeshStudy,
    pub run: memstab::output::FinishedRun,
    pub u: Vec<f64>,
    pub params: Vec<f64>,
}

pub(super) fn saved_point(
    run_dir: &Path,
    scene: Option<&Path>,
    n: usize,
) -> Result<SavedPoint, CliError> {
    let input = |e: memstab::output::ReopenError| CliError::Input(one_line(&e.to_string()));
    if !run_dir.is_dir() {
        return Err(CliError::Input(format!(
            "--point {n}: '{}' is not a directory; --point takes the output directory of memstab run",
            run_dir.display()
        )));
    }
    let run = memstab::output::FinishedRun::read(run_dir).map_err(input)?;
    let file = scene.map_or_else(|| Path::new(&run.origin).to_path_buf(), Path::to_path_buf);
    if scene.is_none() && !file.is_file() {
        return Err(CliError::Input(format!(
            "--point {n}: the run's scene file '{}' (recorded in {}) is not found from here; \
             give it with --scene FILE",
            file.display(),
            run_dir.join("path.json").display()
        )));
    }
    let study = build_study(load_scene(&file)?)?;
    memstab::analysis::restart::check_model(&run, &study).map_err(input)?;
    let (u, params) = memstab::analysis::restart::point(&run, &study, n).map_err(input)?;
    Ok(SavedPoint {
        study,
        run,
        u,
        params,
    })
}

/// Parses the `--at` list against the parameter names: (index, value) pairs.
pub(super) fn parse_at(at: &[String], names: &[String]) -> Result<Vec<(usize, f64)>, CliError> {
    let mut out = Vec::new();
    for item in at {
        let Some((name, value)) = item.split_once('=') else {
            return Err(CliError::Input(format!(
                "--at '{item}': expected NAME=VALUE, e.g. --at p=1.3"
            )));
        };
        let (name, value) = (name.trim(), value.trim());
        let Some(i) = names.iter().position(|n| n == name) else {
            let known = if names.is_empty() {
                "the scene has no parameters".to_string()
            } else {
                format!("the scene's parameters: {}", names.join(", "))
            };
            return Err(CliError::Input(format!(
                "--at '{item}': unknown parameter '{name}' ({known})"
            )));
        };
        let v: f64 = match value.parse::<f64>() {
            Ok(v) if v.is_finite() => v,
            _ => {
                return Err(CliError::Input(format!(
                    "--at '{item}': the value '{value}' of '{name}' is not a finite number"
                )))
            }
        };
        out.push((i, v));
    }
    Ok(out)
}

/// Checks a file to be written by `flag` before any work: its directory must exist, and the
/// file must not exist as anything but a regular file (a directory, a device, a FIFO, a
/// symbolic link — never replaced). Bad input otherwise (exit 2).
pub(super) fn check_out_file(flag: &str, path: &Path) -> Result<(), CliError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(CliError::Input(format!(
            "{flag} '{}': the directory '{}' does not exist",
            path.display(),
            dir.display()
        )));
    }
    memstab::output::check_target(path).map_err(|e| match e {
        memstab::output::OutputError::NotRegular { what, .. } => CliError::Input(format!(
            "{flag} '{}': it exists and is {what}, not a regular file; nothing was written",
            path.display()
        )),
        other => CliError::Input(one_line(&other.to_string())),
    })
}

pub(super) use memstab::text::{one_line, sci, sig_digits};

/// Fails unless a file can be made in the directory `dir` (a probe file, created and removed
/// at once): an `--out` that cannot be written is bad input found before any work, not a
/// failure after it.
pub(super) fn check_writable(flag: &str, out: &Path, dir: &Path) -> Result<(), CliError> {
    let probe = dir.join(format!(".memstab-probe-{}", std::process::id()));
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(CliError::Input(format!(
            "{flag} '{}': cannot write into '{}' ({}); nothing was written",
            out.display(),
            dir.display(),
            e
        ))),
    }
}

/// `--out` must be a directory that can be written or not exist yet, and its parent must
/// exist and be writable.
pub(super) fn check_out(out: &Path) -> Result<(), CliError> {
    if out.exists() {
        if out.is_dir() {
            for name in memstab::output::RUN_FILES {
                check_out_file("--out", &out.join(name))?;
            }
            return check_writable("--out", out, out);
        }
        return Err(CliError::Input(format!(
            "--out '{}' exists and is not a directory",
            out.display()
        )));
    }
    if std::fs::symlink_metadata(out).is_ok() {
        return Err(CliError::Input(format!(
            "--out '{}' is a symbolic link to nothing; give a directory",
            out.display()
        )));
    }
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !parent.is_dir() {
        return Err(CliError::Input(format!(
            "--out '{}': the parent directory '{}' does not exist",
            out.display(),
            parent.display()
        )));
    }
    check_writable("--out", out, parent)
}

/// A run's output directory, made by [`OutDir::create`] if it was missing and locked for this
/// run ([`memstab::output::RunLock`]) until it is dropped: a run that fails before writing
/// removes it again with [`OutDir::failed`], so nothing is left behind.
pub(super) struct OutDir<'a> {
    path: &'a Path,
    created: bool,
    lock: Option<memstab::output::RunLock>,
}

/// The lock of a run's output directory `dir`: another run writing into it is bad input
/// (exit 2, naming the directory and the process).
pub(super) fn lock(dir: &Path) -> Result<memstab::output::RunLock, CliError> {
    memstab::output::RunLock::acquire(dir).map_err(|e| match e {
        memstab::output::LockError::Busy { .. } => {
            CliError::Input(format!("{e}; nothing was written"))
        }
        memstab::output::LockError::Io { .. } => CliError::Failure(e.to_string()),
    })
}

impl<'a> OutDir<'a> {
    /// Creates `path` if it does not exist (its parent must: see [`check_out`]) and takes its
    /// lock; a directory another run holds is refused (exit 2), nothing written.
    pub(super) fn create(path: &'a Path) -> Result<Self, CliError> {
        let created = match std::fs::create_dir(path) {
            Ok(()) => true,
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && path.is_dir() => false,
            Err(e) => {
                return Err(CliError::Failure(format!(
                    "cannot create the output directory '{}': {e}",
                    path.display()
                )))
            }
        };
        match lock(path) {
            Ok(lock) => Ok(Self {
                path,
                created,
                lock: Some(lock),
            }),
            Err(e) => {
                if created {
                    let _ = std::fs::remove_dir(path);
                }
                Err(e)
            }
        }
    }

    /// The failure of a run that wrote nothing: `error` with "; nothing was written", after
    /// removing the directory if this run made it (it is still empty).
    pub(super) fn failed(mut self, error: &str) -> CliError {
        drop(self.lock.take());
        let removed = self.created && std::fs::remove_dir(self.path).is_ok();
        let left = if self.created && !removed {
            format!("; '{}' was created and is left empty", self.path.display())
        } else {
            String::new()
        };
        CliError::Failure(format!("{}; nothing was written{left}", one_line(error)))
    }
}

/// A finished run in `run_dir` read back, and the directory to write into (`out`, default
/// `run_dir`; it must exist).
pub(crate) fn finished_run(
    run_dir: &std::path::Path,
    out: Option<&std::path::Path>,
) -> Result<(memstab::output::FinishedRun, std::path::PathBuf), CliError> {
    let finished = memstab::output::FinishedRun::read(run_dir)
        .map_err(|e| CliError::Input(one_line(&e.to_string())))?;
    let out = out.unwrap_or(run_dir).to_path_buf();
    if !out.is_dir() {
        return Err(CliError::Input(format!(
            "--out '{}' is not an existing directory",
            out.display()
        )));
    }
    Ok((finished, out))
}

/// The flags `memstab branch` and `memstab diagram` share: the scene, and what they change of
/// its branch settings.
#[derive(Debug, clap::Args)]
pub(crate) struct BranchFlags {
    /// The scene file (default: the one recorded in RUN_DIR/path.json).
    #[arg(long)]
    pub scene: Option<std::path::PathBuf>,
    /// Levels of branches: 1, the branches of the point (or the path); 2, also those of their
    /// critical points; at most 3 (default: the scene's, else 1 for `branch`, 2 for `diagram`).
    #[arg(long)]
    pub depth: Option<usize>,
    /// Points of each branch (default: the scene's, else 40).
    #[arg(long)]
    pub steps: Option<usize>,
    /// Largest arclength step along a branch (default: the scene's, else its path's).
    #[arg(long)]
    pub max_step: Option<f64>,
}

impl BranchFlags {
    /// The scene file: `--scene`, else the one the run recorded.
    pub(crate) fn scene_file(&self, recorded: &str) -> std::path::PathBuf {
        self.scene
            .clone()
            .unwrap_or_else(|| std::path::PathBuf::from(recorded))
    }

    /// What they change of the scene's branch settings.
    pub(crate) fn overrides(&self) -> memstab::analysis::branch::Overrides {
        memstab::analysis::branch::Overrides {
            depth: self.depth,
            steps: self.steps,
            max_step: self.max_step,
        }
    }
}
