//! The scripts that hand a prepared sweep's tasks to a scheduler: a Slurm job array and a
//! Snakefile. Both run the same tasks with the memstab binary (`memstab sweep DIR --task N`),
//! which skips a finished task and records a failed one, as a local sweep does.

use super::{Expanded, SweepError, SUMMARY_JSON, TASKS_TSV, TASK_SCENE};
use std::path::{Path, PathBuf};

/// The Slurm script's name in a sweep's directory.
pub const SLURM_SCRIPT: &str = "sweep.slurm";
/// The Snakefile's name in a sweep's directory.
pub const SNAKEFILE: &str = "Snakefile";

/// `text` as one shell word (single quotes, inner ones escaped).
fn shell_word(text: &str) -> String {
    format!("'{}'", text.replace('\'', "'\\''"))
}

/// `text` as a Python string literal.
fn python_string(text: &str) -> String {
    serde_json::Value::String(text.to_string()).to_string()
}

fn absolute(path: &Path) -> Result<String, SweepError> {
    let abs = std::path::absolute(path)
        .map_err(|e| SweepError::Failure(format!("{}: {e}", path.display())))?;
    abs.to_str().map(str::to_string).ok_or_else(|| {
        SweepError::Input(format!(
            "'{}' is not valid UTF-8: a script cannot name it",
            abs.display()
        ))
    })
}

/// Writes `dir/sweep.slurm`, a job array of one array task per grid point (array index = task
/// number, as in `tasks.tsv`), each running `memstab sweep DIR --task N` with the binary
/// `memstab` (or `$MEMSTAB`), its log in `dir/logs/`. Returns the files written.
pub fn emit_slurm(
    expanded: &Expanded,
    dir: &Path,
    memstab: &Path,
) -> Result<Vec<PathBuf>, SweepError> {
    let sweep = absolute(dir)?;
    let binary = absolute(memstab)?;
    let logs = dir.join("logs");
    if !logs.is_dir() {
        std::fs::create_dir(&logs)
            .map_err(|e| SweepError::Failure(format!("cannot create {}: {e}", logs.display())))?;
    }
    let name: String = expanded
        .name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let n = expanded.tasks.len();
    let script = format!(
        "#!/bin/bash\n\
         # Slurm job array of the memstab sweep '{title}': {n} tasks, one per grid point; the task\n\
         # table is {tsv} (array index = task). Submit with `sbatch {script}` (Slurm's\n\
         # MaxArraySize, often 1001, bounds --array), then `memstab collect {sweep}`.\n\
         # A finished task is skipped (its manifest is checked); resubmitting runs the rest.\n\
         #SBATCH --job-name=memstab-{name}\n\
         #SBATCH --array=1-{n}\n\
         #SBATCH --ntasks=1\n\
         #SBATCH --cpus-per-task=1\n\
         #SBATCH --output={logs}/task_%a.log\n\
         set -euo pipefail\n\
         MEMSTAB=\"${{MEMSTAB:-{binary}}}\"\n\
         exec \"$MEMSTAB\" sweep {sweep_word} --task \"$SLURM_ARRAY_TASK_ID\" --quiet\n",
        title = expanded.name.replace('\n', " "),
        tsv = dir.join(TASKS_TSV).display(),
        script = dir.join(SLURM_SCRIPT).display(),
        logs = absolute(&logs)?,
        binary = binary.replace(['"', '$', '`', '\\'], "_"),
        sweep_word = shell_word(&sweep),
    );
    let path = dir.join(SLURM_SCRIPT);
    super::write_text(&path, &script)?;
    Ok(vec![path])
}

/// Writes `dir/Snakefile`: a rule per task directory whose output is the task's
/// `summary.json`, run by `memstab sweep DIR --task N` with the binary `memstab` (or the
/// config value `memstab`). Returns the files written.
pub fn emit_snakemake(
    expanded: &Expanded,
    dir: &Path,
    memstab: &Path,
) -> Result<Vec<PathBuf>, SweepError> {
    let sweep = absolute(dir)?;
    let binary = absolute(memstab)?;
    let tasks: Vec<String> = expanded
        .tasks
        .iter()
        .map(|t| format!("    {}: {},", python_string(&t.dir), t.id))
        .collect();
    let file = format!(
        "# Snakefile of the memstab sweep {title}: {n} tasks, one per grid point (the task table\n\
         # is tasks.tsv). Run with `snakemake --snakefile {snakefile} --cores 2` (on a\n\
         # cluster, with your executor), then `memstab collect {sweep}`. memstab skips a task\n\
         # whose run is finished (its manifest is checked) and records a failed one.\n\
         MEMSTAB = config.get(\"memstab\", {binary})\n\
         SWEEP = {sweep_literal}\n\
         TASKS = {{\n{tasks}\n}}\n\
         \n\
         workdir: SWEEP\n\
         \n\
         \n\
         rule all:\n    \
             input:\n        \
                 expand(\"{{run}}/{summary}\", run=TASKS),\n\
         \n\
         \n\
         rule task:\n    \
             input:\n        \
                 \"{{run}}/{scene}\",\n    \
             output:\n        \
                 \"{{run}}/{summary}\",\n    \
             wildcard_constraints:\n        \
                 run=\"run_[0-9]+\",\n    \
             params:\n        \
                 memstab=MEMSTAB,\n        \
                 sweep=SWEEP,\n        \
                 task=lambda w: TASKS[w.run],\n    \
             shell:\n        \
                 '\"{{params.memstab}}\" sweep \"{{params.sweep}}\" --task {{params.task}} --quiet'\n",
        title = python_string(&expanded.name),
        n = expanded.tasks.len(),
        snakefile = dir.join(SNAKEFILE).display(),
        binary = python_string(&binary),
        sweep_literal = python_string(&sweep),
        tasks = tasks.join("\n"),
        summary = SUMMARY_JSON,
        scene = TASK_SCENE,
    );
    let path = dir.join(SNAKEFILE);
    super::write_text(&path, &file)?;
    Ok(vec![path])
}
