//! Which processes of a run directory's log still work in it: those that
//! logged a start and no end, each judged alive, elsewhere or gone by its
//! record (`liveness`); one that is gone counts as stopped unless a later
//! process took its work over.

use super::liveness::{self, Liveness};
use std::path::Path;

/// A line of the run log: `SECS pid PID start|done|failed WHAT...`.
struct Event<'a> {
    pid: u32,
    verb: &'a str,
    what: &'a str,
}

fn event(line: &str) -> Option<Event<'_>> {
    let mut fields = line.splitn(5, ' ');
    let (_secs, pid_word) = (fields.next()?, fields.next()?);
    if pid_word != "pid" {
        return None;
    }
    let pid = fields.next()?.parse().ok()?;
    let verb = fields.next()?;
    let what = fields.next().unwrap_or("");
    Some(Event { pid, verb, what })
}

/// A process that works in the run directory now.
#[derive(Clone, Debug, PartialEq)]
pub struct Running {
    /// Its pid.
    pub pid: u32,
    /// The host it runs on, when that is another machine (not checked
    /// from here).
    pub elsewhere: Option<String>,
}

/// The processes that started in the run directory and never said they
/// ended, with what became of each.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Processes {
    /// Those still running (or on another machine).
    pub running: Vec<Running>,
    /// Those gone whose work no later process took over.
    pub gone: Vec<u32>,
}

impl Processes {
    /// The processes of `log` that started and never logged their end.
    /// One that is gone counts as stopped unless a later process took its
    /// work over: the same job again, or a job that starts the run over
    /// (the whole run, or the script's first job, `--until`).
    pub(super) fn of(dir: &Path, log: &[String]) -> Processes {
        let mut working = Processes::default();
        for (pid, taken_over) in open(log) {
            match liveness::check(dir, pid) {
                // Elsewhere and taken over: most likely killed with its node.
                Liveness::Gone | Liveness::Elsewhere(_) if taken_over => {}
                Liveness::Gone => working.gone.push(pid),
                Liveness::Alive => working.running.push(Running {
                    pid,
                    elsewhere: None,
                }),
                Liveness::Elsewhere(host) => working.running.push(Running {
                    pid,
                    elsewhere: Some(host),
                }),
            }
        }
        working
    }

    /// Whether a process works in the run directory now.
    pub fn any_running(&self) -> bool {
        !self.running.is_empty()
    }

    /// "running (process 812)", "stopped (process 812 is gone)", ...
    pub(super) fn describe(&self, finished: bool) -> String {
        let pids = |v: &[u32]| v.iter().map(u32::to_string).collect::<Vec<_>>().join(", ");
        let gone = match self.gone.as_slice() {
            [] => None,
            [pid] => Some(format!("process {pid} is gone")),
            many => Some(format!("processes {} are gone", pids(many))),
        };
        if self.running.is_empty() {
            return match gone {
                Some(gone) => {
                    format!("stopped ({gone}); the same command (or job script) again resumes")
                }
                None if finished => "finished".to_string(),
                None => "no process works in it now".to_string(),
            };
        }
        let running: Vec<String> = self
            .running
            .iter()
            .map(|r| match &r.elsewhere {
                Some(host) => format!("{} on {host}, not checked from here", r.pid),
                None => r.pid.to_string(),
            })
            .collect();
        let noun = if running.len() == 1 {
            "process"
        } else {
            "processes"
        };
        let mut text = format!("running ({noun} {})", running.join("; "));
        if let Some(gone) = gone {
            text += &format!("; stopped: {gone}");
        }
        text
    }
}

/// The pids that started and never logged their end, in order of their
/// start, each with whether a later process took its work over.
fn open(log: &[String]) -> Vec<(u32, bool)> {
    // (pid, job, taken over)
    let mut open: Vec<(u32, &str, bool)> = Vec::new();
    for e in log.iter().filter_map(|l| event(l)) {
        match e.verb {
            "start" => {
                let starts_over = e.what == "run" || e.what.starts_with("job --until ");
                open.retain(|&(pid, ..)| pid != e.pid);
                for (_, what, taken) in &mut open {
                    *taken |= starts_over || *what == e.what;
                }
                open.push((e.pid, e.what, false));
            }
            "done" | "failed" => open.retain(|&(pid, ..)| pid != e.pid),
            _ => {}
        }
    }
    open.into_iter().map(|(pid, _, t)| (pid, t)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_later_job_takes_a_dead_ones_work_over() {
        let log: Vec<String> = [
            "1 pid 10 start job --stage normals --share 0/2",
            "2 pid 11 start job --stage normals --share 1/2",
            "3 pid 11 done job --stage normals --share 1/2, peak 1 MiB",
            "4 pid 12 start job --stage normals --share 0/2",
            "not a log line",
        ]
        .map(String::from)
        .to_vec();
        assert_eq!(open(&log), vec![(10, true), (12, false)]);
    }
}
