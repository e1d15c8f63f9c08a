//! Running a command in its run directory (`--run-dir`): start or resume
//! the run there, print its job script (`--emit`), or say nothing is left
//! to do; the log says what each process did. This driver stands above
//! the directory (`rundir.rs`: its files, identity and sealing) and the job
//! scripts (`emit.rs`), so neither of those needs the other.

use super::rundir::{fingerprint, stable_args, RunDir, RunIdentity};
use super::Command;
use anyhow::{anyhow, Context, Result};
use scanmesh::store::{Checkpoints, Job};
use std::path::PathBuf;

/// The checkpoints of this process's store: where the job says it stopped.
static WATCHED: std::sync::Mutex<Option<Checkpoints>> = std::sync::Mutex::new(None);

/// Remembers `c` so [`run_in_dir`] learns whether the job stopped as asked.
pub fn watch(c: &Checkpoints) {
    if let Ok(mut w) = WATCHED.lock() {
        *w = Some(c.clone());
    }
}

fn stopped_at() -> Option<String> {
    let w = WATCHED.lock().ok()?;
    w.as_ref()?.stopped_at().map(str::to_string)
}

/// The tile files the job found damaged (and recomputed).
fn damaged_tiles() -> Vec<PathBuf> {
    let Ok(w) = WATCHED.lock() else {
        return Vec::new();
    };
    w.as_ref().map(|c| c.damaged()).unwrap_or_default()
}

/// Runs `command` (given as `args`), in its run directory when it has one:
/// starts or resumes the run there, or prints its job script (`--emit`),
/// or says there is nothing left to do.
pub fn run_in_dir(command: Command, args: Vec<String>) -> Result<()> {
    let (Some(common), Some(run_args)) = (command.common(), command.run_args()) else {
        return super::dispatch(command);
    };
    let Some(dir) = run_args.run_dir.clone() else {
        return super::dispatch(command);
    };
    let (input, output) = command
        .paths()
        .map(|(i, o)| (i.to_path_buf(), o.to_path_buf()))
        .ok_or_else(|| {
            anyhow!("--run-dir: this command has no input and output to keep a run of")
        })?;
    // Before the directory is made: a missing input leaves nothing behind.
    std::fs::metadata(&input).with_context(|| format!("reading {}", input.display()))?;
    let run = RunDir::create(&dir)?;
    let job = run_args.job.clone();
    if job == Job::Whole {
        let id = RunIdentity {
            scanmesh_version: env!("CARGO_PKG_VERSION").to_string(),
            args: stable_args(&args),
            cwd: std::env::current_dir()?,
            input: fingerprint(&input)?,
        };
        run.begin(&id, run_args.restart)?;
        if let Some(kind) = run_args.emit {
            let stages = command.tile_stages()?;
            let settings = common.settings_in(run_args)?;
            let script = super::emit::script(kind, &run, &stages, run_args.tasks, &settings);
            return super::stdout::write(format_args!("{script}"));
        }
        if let Some(summary) = run.finished(&output, &input)? {
            super::report::summary(format!(
                "nothing to do: {} is complete ({})",
                output.display(),
                run.dir.display()
            ));
            if !summary.is_empty() && !common.quiet {
                super::stdout::outln!("  {summary}")?;
            }
            return Ok(());
        }
    }
    let what = job_text(&job);
    run.log(&format!("start {what}"));
    let outcome = super::dispatch(command);
    for tile in damaged_tiles() {
        let line = format!(
            "damaged tile file {} removed, its tile recomputed",
            tile.display()
        );
        eprintln!("{line}");
        run.log(&line);
    }
    let outcome = match (outcome, stopped_at(), &job) {
        (Err(_), Some(stage), _) => {
            run.log(&format!("done {what} (stopped at {stage}), peak {}", super::peak()));
            return Ok(());
        }
        (Ok(()), None, Job::Tiles { stage, .. }) => Err(anyhow!(
            "run-job --stage {stage}: the run has no tile stage of that name (see `scanmesh status {}`)",
            run.dir.display()
        )),
        (outcome, ..) => outcome,
    };
    match &outcome {
        Ok(()) => {
            // An `--until` job that found no stage to stop at ran it all.
            if !matches!(job, Job::Tiles { .. }) {
                run.finish(&output, super::report::last_summary())?;
            }
            run.log(&format!("done {what}, peak {}", super::peak()));
        }
        Err(e) => run.log(&format!("failed {what}: {e:#}")),
    }
    outcome
}

/// A job in words, for the log.
pub fn job_text(job: &Job) -> String {
    match job {
        Job::Whole => "run".to_string(),
        Job::Until(s) => format!("job --until {s}"),
        Job::Tiles { stage, tiles } => format!("job --stage {stage} {tiles}"),
    }
}
