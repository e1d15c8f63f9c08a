//! `--emit parallel|slurm`: a run directory's work as a job script for an
//! existing scheduler. The single-machine steps (ingest, the global passes
//! between tile stages, the final write) are single jobs; each tile stage
//! is `--tasks` jobs, each a share of the stage's tiles (a share, not a
//! range: the tile count is known only after ingest, when Slurm already
//! has the array). Every job is `scanmesh run-job DIR ...`, stateless and
//! idempotent: rerun after a failure, it finds the finished tiles and
//! writes the same files.

use super::rundir::RunDir;
use super::Settings;
use clap::ValueEnum;
use scanmesh::store::Checkpoints;
use std::fmt::Write;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Scheduler {
    /// A shell script running each tile stage with GNU parallel.
    Parallel,
    /// A bash script submitting the jobs with sbatch: single jobs and
    /// array jobs chained by `afterok` dependencies.
    Slurm,
}

/// The job script for `stages` of the run in `run`.
pub fn script(kind: Scheduler, run: &RunDir, stages: &[&str], tasks: u32, s: &Settings) -> String {
    let steps = steps(stages, tasks);
    match kind {
        Scheduler::Parallel => parallel(run, &steps),
        Scheduler::Slurm => slurm(run, &steps, s),
    }
}

/// One step of the script: a single job, or an array of `tasks` jobs
/// where `{i}` stands for the task index.
enum Step {
    Single(String),
    Array { args: String, tasks: u32 },
}

fn steps(stages: &[&str], tasks: u32) -> Vec<Step> {
    let mut steps = Vec::new();
    for stage in stages {
        let stage = Checkpoints::slug(stage);
        steps.push(Step::Single(format!("--until {stage}")));
        steps.push(Step::Array {
            args: format!("--stage {stage} --share {{i}}/{tasks}"),
            tasks,
        });
    }
    steps.push(Step::Single(String::new()));
    steps
}

fn header(run: &RunDir, shell: &str) -> String {
    let mut out = format!("#!/bin/{shell}\n");
    let _ = writeln!(
        out,
        "# scanmesh jobs for the run in {} (`scanmesh status` follows it).",
        run.dir.display()
    );
    if let Ok(Some(id)) = run.identity() {
        let _ = writeln!(out, "# Run: scanmesh {}", id.args.join(" "));
    }
    out += "# Every job is idempotent: rerun this script after a failure.\n";
    out += "set -eu\n";
    out += "SCANMESH=${SCANMESH:-scanmesh}\n";
    let _ = writeln!(out, "DIR={}", quote(&run.dir.to_string_lossy()));
    out
}

fn parallel(run: &RunDir, steps: &[Step]) -> String {
    let mut out = header(run, "sh");
    out += "JOBS=${JOBS:-4}\n";
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
                    "seq 0 {} | parallel --halt now,fail=1 -j \"$JOBS\" \"$SCANMESH\" run-job \"$DIR\" {args}",
                    tasks - 1
                );
            }
        }
    }
    out
}

fn slurm(run: &RunDir, steps: &[Step], s: &Settings) -> String {
    let mut out = header(run, "bash");
    // The promise plus room for the binary and the kernel's page tables.
    let mem_mb = s.mem / (1 << 20) + 64;
    let _ = writeln!(
        out,
        "OPTS=\"--job-name=scanmesh --cpus-per-task={} --mem={mem_mb}M --output=$DIR/slurm-%A_%a.out ${{SBATCH_EXTRA:-}}\"",
        s.threads
    );
    out += "after=\"\"\n";
    out += "submit() { sbatch --parsable $OPTS ${after:+--dependency=afterok:$after} \"$@\" | cut -d';' -f1; }\n";
    for step in steps {
        match step {
            Step::Single(args) => {
                let job = format!("$SCANMESH run-job $DIR --threads {} {args}", s.threads);
                let _ = writeln!(out, "after=$(submit --wrap=\"{}\")", job.trim_end());
            }
            Step::Array { args, tasks } => {
                let args = args.replace("{i}", "\\$SLURM_ARRAY_TASK_ID");
                let _ = writeln!(
                    out,
                    "after=$(submit --array=0-{} --wrap=\"$SCANMESH run-job $DIR --threads {} {args}\")",
                    tasks - 1,
                    s.threads
                );
            }
        }
    }
    out += "echo \"$after\"\n";
    out
}

/// `text` as one word for sh.
fn quote(text: &str) -> String {
    format!("'{}'", text.replace('\'', "'\\''"))
}
