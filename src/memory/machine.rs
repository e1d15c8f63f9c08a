//! What this machine can run: its cores, and a memory promise or a thread
//! count it cannot keep, said before any work starts (a plan sized for
//! memory that is not there fails hours in; `--threads 100000` once spent
//! minutes spawning threads).

use super::MachineMemory;
use crate::units::human_bytes;

/// Threads beyond this many per core only take turns.
pub const MAX_THREADS_PER_CORE: usize = 8;

/// The cores this process may use.
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// A request this machine cannot keep. Its text is the value and why;
/// the caller names the option it came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum BeyondMachine {
    /// More threads than [`MAX_THREADS_PER_CORE`] per core.
    #[error("{threads} is more than {MAX_THREADS_PER_CORE} x the {cores} cores here: give at most {most}", most = MAX_THREADS_PER_CORE * cores)]
    Threads {
        /// The threads asked for.
        threads: usize,
        /// The cores here.
        cores: usize,
    },
    /// More memory than the RAM or the control group's limit.
    #[error("{} is more than this machine can give (RAM {}, cgroup limit {}): give at most {}MiB", human_bytes(*mem), ram.map_or("unknown".into(), human_bytes), cgroup.map_or("none".into(), human_bytes), limit >> 20)]
    Memory {
        /// The memory promised, in bytes.
        mem: u64,
        /// The machine's RAM, if known.
        ram: Option<u64>,
        /// The control group's limit, if any.
        cgroup: Option<u64>,
        /// The smaller of the two: the most the process can hold.
        limit: u64,
    },
}

/// Why `threads` is too many for this machine, if it is.
pub fn too_many_threads(threads: usize) -> Option<BeyondMachine> {
    let cores = cores();
    (threads > MAX_THREADS_PER_CORE * cores).then_some(BeyondMachine::Threads { threads, cores })
}

/// Why `mem` is more than this machine can give, if it is.
pub fn too_much_memory(mem: u64) -> Option<BeyondMachine> {
    let machine = MachineMemory::of_this_process();
    let limit = machine.limit().filter(|&l| mem > l)?;
    Some(BeyondMachine::Memory {
        mem,
        ram: machine.ram,
        cgroup: machine.cgroup,
        limit,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_text_says_the_value_and_the_most_this_machine_takes() {
        let t = BeyondMachine::Threads {
            threads: 100,
            cores: 2,
        };
        assert_eq!(
            t.to_string(),
            "100 is more than 8 x the 2 cores here: give at most 16"
        );
        let m = BeyondMachine::Memory {
            mem: 64 << 30,
            ram: Some(24 << 30),
            cgroup: None,
            limit: 24 << 30,
        };
        assert_eq!(
            m.to_string(),
            "64.0GiB is more than this machine can give (RAM 24.0GiB, cgroup limit none): give at most 24576MiB"
        );
        assert!(too_many_threads(1).is_none());
        assert!(too_much_memory(1).is_none());
    }
}
