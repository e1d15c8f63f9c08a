//! `--emit parallel|slurm`: a run directory's work as a job script for an
//! existing scheduler. The single-machine steps (ingest, the global passes
//! between tile stages, the final write) are single jobs; each tile stage
//! is `--tasks` jobs, each a share of the stage's tiles (a share, not a
//! range: the tile count is known only after ingest, when Slurm already
//! has the array). Every job is `scanmesh run-job DIR ...`, stateless and
//! idempotent: rerun after a failure, it finds the finished tiles and
//! writes the same files. The jobs run the binary the caller names (the
//! CLI: itself, by its absolute path), unless `SCANMESH` names another;
//! every path is quoted for sh wherever it appears (Slurm's `--wrap` text is parsed by
//! sh once more, on the node); a failed submission stops the Slurm script.

use super::{RunDir, StageId};
use crate::memory::MemoryBudget;
use std::fmt::Write;

/// The scheduler a job script is for (the CLI's `--emit`, its variants'
/// text the values' help).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Scheduler {
    /// A shell script running each tile stage with GNU parallel.
    Parallel,
    /// A bash script submitting the jobs with sbatch: single jobs and
    /// array jobs chained by `afterok` dependencies.
    Slurm,
}

/// The absolute path of this process's binary, which the jobs run unless
/// `SCANMESH` says otherwise (`scanmesh` when it cannot be told).
pub fn this_binary() -> String {
    let Ok(exe) = std::env::current_exe() else {
        return "scanmesh".to_string();
    };
    let text = exe.to_string_lossy().into_owned();
    // Linux names a binary replaced since it started (a rebuild) so; the
    // path itself then holds the new one.
    match text.strip_suffix(" (deleted)") {
        Some(path) if !exe.exists() => path.to_string(),
        _ => text,
    }
}

/// The job script for `stages` of the run in `run`, each tile stage as
/// `tasks` jobs, each job running `binary` (`run-job`) with `budget`'s
/// threads (Slurm: its memory too).
pub fn job_script(
    kind: Scheduler,
    run: &RunDir,
    stages: &[StageId],
    tasks: u32,
    budget: MemoryBudget,
    binary: &str,
) -> String {
    let steps = steps(stages, tasks);
    match kind {
        Scheduler::Parallel => parallel(run, &steps, binary),
        Scheduler::Slurm => slurm(run, &steps, budget, binary),
    }
}

/// One step of the script: a single job, or an array of `tasks` jobs
/// where `{i}` stands for the task index.
enum Step {
    Single(String),
    Array { args: String, tasks: u32 },
}

fn steps(stages: &[StageId], tasks: u32) -> Vec<Step> {
    let mut steps = Vec::new();
    for stage in stages {
        let stage = stage.slug();
        steps.push(Step::Single(format!("--until {stage}")));
        steps.push(Step::Array {
            args: format!("--stage {stage} --share {{i}}/{tasks}"),
            tasks,
        });
    }
    steps.push(Step::Single(String::new()));
    steps
}

fn header(run: &RunDir, shell: &str, strict: &str, binary: &str) -> String {
    let mut out = format!("#!/bin/{shell}\n");
    let _ = writeln!(
        out,
        "# scanmesh jobs for the run in {} (`scanmesh status` follows it).",
        comment(&run.dir().to_string_lossy())
    );
    if let Ok(Some(id)) = run.identity() {
        let args: Vec<String> = id.args.iter().map(|a| word(a)).collect();
        let _ = writeln!(out, "# Run: scanmesh {}", comment(&args.join(" ")));
    }
    out += "# Every job is idempotent: rerun this script after a failure.\n";
    out += "# SCANMESH=/path/to/scanmesh runs another binary than the one that\n";
    out += "# wrote the script (a compute node's PATH rarely has scanmesh).\n";
    let _ = writeln!(out, "{strict}");
    let _ = writeln!(out, "SCANMESH=${{SCANMESH:-{}}}", quote(binary));
    let _ = writeln!(out, "DIR={}", quote(&run.dir().to_string_lossy()));
    out
}

fn parallel(run: &RunDir, steps: &[Step], binary: &str) -> String {
    // sh has no pipefail: the one pipeline ends in the command whose
    // status counts (parallel's).
    let mut out = header(run, "sh", "set -eu", binary);
    out += "JOBS=${JOBS:-4}\n";
    // The jobs parallel starts take the paths from the environment: on
    // parallel's command line a path is split at blanks and its `{}`
    // replaced by the task.
    out += "export SCANMESH DIR\n";
    for step in steps {
        match step {
            Step::Single(args) => {
                let _ = writeln!(
                    out,
                    "{}",
                    format!("\"$SCANMESH\" run-job \"$DIR\" {args}").trim_end()
                );
            }
            Step::Array { args, tasks } => {
                let args = args.replace("{i}", "{}");
                let _ = writeln!(
                    out,
                    "seq 0 {} | parallel --halt now,fail=1 -j \"$JOBS\" '\"$SCANMESH\" run-job \"$DIR\" {args}'",
                    tasks - 1
                );
            }
        }
    }
    out
}

fn slurm(run: &RunDir, steps: &[Step], budget: MemoryBudget, binary: &str) -> String {
    let mut out = header(run, "bash", "set -euo pipefail", binary);
    // Slurm runs --wrap's text with sh on the node: every word in it is
    // quoted for sh again, here, since SCANMESH may come from the
    // environment.
    out += r#"q() { local s=${1//\'/\'\\\'\'}; printf "'%s'" "$s"; }"#;
    out += "\n";
    let _ = writeln!(
        out,
        "JOB=\"$(q \"$SCANMESH\") run-job $(q \"$DIR\") --threads {}\"",
        budget.threads
    );
    out += "# SBATCH_EXTRA: more sbatch options, split at blanks.\n";
    out += "read -r -a EXTRA <<< \"${SBATCH_EXTRA:-}\"\n";
    // The promise plus room for the binary and the kernel's page tables.
    let mem_mb = budget.bytes / (1 << 20) + 64;
    // Slurm expands `%` in --output's path: `%%` is a `%` of the path.
    let _ = writeln!(
        out,
        "OPTS=(--job-name=scanmesh --cpus-per-task={} --mem={mem_mb}M \"--output=${{DIR//%/%%}}/slurm-%A_%a.out\")",
        budget.threads
    );
    out += "after=\"\"\n";
    out += SUBMIT;
    for step in steps {
        match step {
            Step::Single(args) => {
                let job = format!("$JOB {args}");
                let _ = writeln!(out, "submit --wrap=\"{}\"", job.trim_end());
            }
            Step::Array { args, tasks } => {
                let args = args.replace("{i}", "\\$SLURM_ARRAY_TASK_ID");
                let _ = writeln!(out, "submit --array=0-{} --wrap=\"$JOB {args}\"", tasks - 1);
            }
        }
    }
    out += "echo \"$after\"\n";
    out
}

/// Submits one job after the one before (`$after`) and keeps its id; a
/// failed submission, or one that gives no job id, stops the script (the
/// jobs after it would otherwise run without the work they need).
const SUBMIT: &str = r#"submit() {
  local out id
  out=$(sbatch --parsable "${OPTS[@]}" ${EXTRA[@]+"${EXTRA[@]}"} ${after:+"--dependency=afterok:$after"} "$@") || {
    echo "scanmesh job script: sbatch failed, submitting: $*" >&2
    exit 1
  }
  id=${out%%;*}
  case $id in
    '' | *[!0-9]*)
      echo "scanmesh job script: sbatch gave no job id (it said: $out), submitting: $*" >&2
      exit 1
      ;;
  esac
  after=$id
}
"#;

/// `text` as one word for sh.
fn quote(text: &str) -> String {
    format!("'{}'", text.replace('\'', "'\\''"))
}

/// `arg` as a word of a command line to copy: quoted when it needs it.
fn word(arg: &str) -> String {
    let plain = !arg.is_empty()
        && arg
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./=:,+@%".contains(c));
    if plain {
        arg.to_string()
    } else {
        quote(arg)
    }
}

/// `text` on one comment line: a line break in a path would end the
/// comment and run the rest.
fn comment(text: &str) -> String {
    text.replace('\n', "\\n").replace('\r', "\\r")
}
