//! Whether a process the run log names still runs. The log names a pid,
//! but a pid is a number on one machine: a job of an emitted script may
//! run on another node, and a pid is reused once its process has ended. So
//! each process working in a run directory records where it runs
//! (`procs/PID-MACHINE.json`: host name, machine, start time in clock
//! ticks since boot) and removes the record when it ends normally (its
//! [`ProcessRecord`] is dropped); a record left behind is a process that was
//! killed. `status` asks `/proc` only about processes of its own machine,
//! and takes a pid for the process it names only when the start times
//! agree.

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The directory of the process records in a run directory.
pub(super) const PROCS_DIR: &str = "procs";

/// Where one process works.
#[derive(Debug, PartialEq, Serialize, Deserialize)]
struct Record {
    pid: u32,
    host: String,
    /// The machine and pid namespace a pid is a number in.
    machine: String,
    /// `/proc/PID/stat` field 22: when the process started.
    start_ticks: u64,
}

/// This process's record in a run directory while it works there: the
/// record is removed when this is dropped (the process ends normally, and
/// its log line says how), and stays when the process is killed.
#[derive(Debug)]
#[must_use = "the record is removed when this is dropped"]
pub struct ProcessRecord {
    path: Option<PathBuf>,
}

impl ProcessRecord {
    /// Records in `run_dir` that this process works there (best effort:
    /// without a record, `status` falls back to the pid alone).
    pub fn record(run_dir: &Path) -> ProcessRecord {
        ProcessRecord {
            path: write_record(run_dir),
        }
    }
}

impl Drop for ProcessRecord {
    fn drop(&mut self) {
        if let Some(path) = self.path.take() {
            let _ = std::fs::remove_file(path);
        }
    }
}

/// Writes this process's record; its path, when it was written.
fn write_record(run_dir: &Path) -> Option<PathBuf> {
    let pid = std::process::id();
    let record = Record {
        pid,
        host: host(),
        machine: this_machine()?,
        start_ticks: start_ticks(pid)?,
    };
    let dir = run_dir.join(PROCS_DIR);
    let path = dir.join(file_name(pid, &record.machine));
    let tmp = path.with_extension("tmp");
    let written = serde_json::to_vec(&record)
        .map_err(std::io::Error::from)
        .and_then(|json| {
            std::fs::create_dir_all(&dir)?;
            std::fs::write(&tmp, json)?;
            std::fs::rename(&tmp, &path)
        });
    match written {
        Ok(()) => Some(path),
        Err(_) => {
            let _ = std::fs::remove_file(&tmp);
            None
        }
    }
}

/// What became of a process the log names.
#[derive(Debug, PartialEq)]
pub enum Liveness {
    /// It runs on this machine.
    Alive,
    /// It runs, or ran, on the machine named: not checked from here.
    Elsewhere(String),
    /// No such process runs any more.
    Gone,
}

/// Whether process `pid`, which worked in `run_dir`, still runs.
pub(super) fn check(run_dir: &Path, pid: u32) -> Liveness {
    let records = records(run_dir, pid);
    let here = this_machine();
    if let Some(r) = records.iter().find(|r| Some(&r.machine) == here.as_ref()) {
        return match start_ticks(pid) {
            Some(t) if t == r.start_ticks => Liveness::Alive,
            _ => Liveness::Gone,
        };
    }
    if let Some(r) = records.first() {
        return Liveness::Elsewhere(r.host.clone());
    }
    // No record (killed before it wrote one): the pid alone, whose reuse
    // by another process cannot be told.
    match start_ticks(pid) {
        Some(_) => Liveness::Alive,
        None => Liveness::Gone,
    }
}

fn records(run_dir: &Path, pid: u32) -> Vec<Record> {
    let prefix = format!("{pid}-");
    let Ok(entries) = std::fs::read_dir(run_dir.join(PROCS_DIR)) else {
        return Vec::new();
    };
    entries
        .flatten()
        .filter(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            name.starts_with(&prefix) && name.ends_with(".json")
        })
        .filter_map(|e| serde_json::from_slice::<Record>(&std::fs::read(e.path()).ok()?).ok())
        .filter(|r| r.pid == pid)
        .collect()
}

/// `PID-HASH.json`, the hash of the machine: pids of two nodes may agree.
fn file_name(pid: u32, machine: &str) -> String {
    let hash = machine.bytes().fold(0xcbf2_9ce4_8422_2325_u64, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    });
    format!("{pid}-{hash:016x}.json")
}

/// This boot of this machine and this pid namespace (two containers on
/// one machine number their processes apart).
fn this_machine() -> Option<String> {
    let boot = std::fs::read_to_string("/proc/sys/kernel/random/boot_id").ok()?;
    let ns = std::fs::read_link("/proc/self/ns/pid").ok()?;
    Some(format!("{}/{}", boot.trim(), ns.display()))
}

fn host() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|h| h.trim().to_string())
        .unwrap_or_else(|_| "another machine".to_string())
}

/// When process `pid` started (clock ticks since boot), if it runs and is
/// not a zombie.
fn start_ticks(pid: u32) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    stat_start_ticks(&stat)
}

/// Field 22 of a `/proc/PID/stat` line; the command name (field 2, in
/// parentheses) may hold spaces and parentheses, so fields count from the
/// last `)`.
fn stat_start_ticks(stat: &str) -> Option<u64> {
    let rest = &stat[stat.rfind(')')? + 1..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    if fields.first() == Some(&"Z") {
        return None;
    }
    fields.get(19)?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn start_time_follows_odd_command_names() {
        let stat =
            "4242 (a) b (c) S 1 4242 4242 0 -1 4194560 95 0 0 0 0 0 0 0 20 0 1 0 987654 1 2 3";
        assert_eq!(stat_start_ticks(stat), Some(987_654));
        let zombie = "4242 (x) Z 1 4242 4242 0 -1 4194560 95 0 0 0 0 0 0 0 20 0 1 0 987654 1 2";
        assert_eq!(stat_start_ticks(zombie), None);
    }

    #[test]
    fn a_recorded_process_is_alive_until_it_ends() {
        let dir = tempfile::tempdir().expect("tmp");
        let record = ProcessRecord::record(dir.path());
        let me = std::process::id();
        assert_eq!(check(dir.path(), me), Liveness::Alive);
        // The same pid started at another time: a reused pid.
        let path = record.path.clone().expect("recorded");
        let mut r: Record =
            serde_json::from_slice(&std::fs::read(&path).expect("read")).expect("json");
        r.start_ticks += 1;
        std::fs::write(&path, serde_json::to_vec(&r).expect("json")).expect("write");
        assert_eq!(check(dir.path(), me), Liveness::Gone);
        // Recorded on another machine: not judged from here.
        r.machine = "another boot/pid:[1]".into();
        r.host = "node7".into();
        std::fs::remove_file(&path).expect("rm");
        let other = dir.path().join(PROCS_DIR).join(file_name(me, &r.machine));
        std::fs::write(&other, serde_json::to_vec(&r).expect("json")).expect("write");
        assert_eq!(check(dir.path(), me), Liveness::Elsewhere("node7".into()));
        drop(record);
    }

    #[test]
    fn the_record_goes_when_the_process_ends_normally() {
        let dir = tempfile::tempdir().expect("tmp");
        let record = ProcessRecord::record(dir.path());
        let path = record.path.clone();
        drop(record);
        assert!(path.is_none_or(|p| !p.exists()));
    }
}
