//! Running a command in its run directory (`--run-dir`): start or resume
//! the run there, print its job script (`--emit`), or say nothing is left
//! to do. The directory itself (its files, identity, sealing, the job's
//! store and checkpoints, the log of what each process did) is the
//! library's (`scanmesh::rundir`); what identifies a run's command line
//! (the options that do not change its result) is this file's.

use super::Command;
use anyhow::{anyhow, Context, Result};
use scanmesh::rundir::{job_script, this_binary, RunDir, RunIdentity, Session};
use scanmesh::store::Job;

/// Options that vary between the processes of one run without changing
/// its result, with whether each takes a value: left out of the
/// comparison of command lines.
const VOLATILE: [(&str, bool); 9] = [
    ("--quiet", false),
    ("-q", false),
    ("--threads", true),
    ("--report", true),
    ("--restart", false),
    ("--emit", true),
    ("--tasks", true),
    ("--run-dir", true),
    ("--scratch", true),
];

/// The parts of `args` that decide a run's result.
pub fn stable_args(args: &[String]) -> Vec<String> {
    let mut out = Vec::new();
    let mut skip_value = false;
    for a in args {
        if std::mem::take(&mut skip_value) {
            continue;
        }
        let name = a.split('=').next().unwrap_or(a);
        match VOLATILE.iter().find(|(v, _)| *v == name) {
            Some((_, takes)) => skip_value = *takes && !a.contains('='),
            None => out.push(a.clone()),
        }
    }
    out
}

/// Runs `command` (given as `args`), in its run directory when it has one:
/// starts or resumes the run there, or prints its job script (`--emit`),
/// or says there is nothing left to do.
pub fn run_in_dir(mut command: Command, args: Vec<String>) -> Result<()> {
    let (Some(common), Some(run_args)) = (command.args().common(), command.args().run_dir()) else {
        return command.dispatch();
    };
    let Some(dir) = run_args.run_dir.clone() else {
        return command.dispatch();
    };
    let (input, output) = command
        .args()
        .paths()
        .map(|(i, o)| (i.to_path_buf(), o.to_path_buf()))
        .ok_or_else(|| {
            anyhow!("--run-dir: this command has no input and output to keep a run of")
        })?;
    // Before the directory is made: a missing input leaves nothing behind.
    std::fs::metadata(&input).with_context(|| format!("reading {}", input.display()))?;
    let run = RunDir::create(&dir)?;
    let log = common.log.clone();
    let job = run_args.job.clone();
    if job == Job::Whole {
        let id = RunIdentity::new(stable_args(&args), std::env::current_dir()?, &input)?;
        run.begin(&id, run_args.restart)?;
        if let Some(kind) = run_args.emit {
            let stages = command.args().tile_stages()?;
            let budget = common.settings_in(run_args)?.lib.budget;
            let binary = this_binary();
            let script = job_script(kind, &run, &stages, run_args.tasks, budget, &binary);
            return super::stdout::write(format_args!("{script}"));
        }
        if let Some(summary) = run.finished(&output, &input)? {
            super::report::summary(
                &log,
                format!(
                    "nothing to do: {} is complete ({})",
                    output.display(),
                    run.dir().display()
                ),
            );
            if !summary.is_empty() && !common.quiet {
                super::stdout::outln!("  {summary}")?;
            }
            return Ok(());
        }
    }
    // This process's record, removed when this function returns.
    let (session, _record) = Session::start(run, job);
    if let Some(r) = command.args_mut().run_dir_mut() {
        r.session = Some(session.clone());
    }
    let outcome = command.dispatch();
    for line in session.log_damaged_tiles() {
        eprintln!("{line}");
    }
    let summary = log.with(|l| l.last_summary().map(String::from));
    session.finish(outcome, &output, summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn volatile_options_do_not_change_a_run() {
        let args = |s: &str| s.split(' ').map(String::from).collect::<Vec<_>>();
        let a = stable_args(&args(
            "normals in.ply -o out.ply --threads 2 -q --run-dir d --k 9",
        ));
        let b = stable_args(&args(
            "normals in.ply -o out.ply --run-dir=d --report r.json --k 9",
        ));
        assert_eq!(a, b);
        assert_eq!(a, args("normals in.ply -o out.ply --k 9"));
    }
}
