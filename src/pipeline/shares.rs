//! Memory shares of the tiles in flight: the plan's memory for tiles, cut
//! into shares of the bytes of its largest tile with the planned margin
//! (ARCHITECTURE.md, "Memory model"); each tile in flight takes one, and
//! tiles forced smaller than the budget allows leave more shares than
//! tiles in flight (`RunOptions::shares`). A kernel whose margin grows on
//! reload (the Delaunay surface's doubt) can load several times that; it
//! then waits until it can take as many shares as it needs, so the tiles
//! running at once never hold more than the plan. A tile that needs more
//! shares than there are is an error: no run could keep the promise.

use std::sync::{Condvar, Mutex};

/// The shares of one run.
pub(crate) struct Shares {
    /// Bytes of one share.
    bytes: u64,
    total: usize,
    state: Mutex<State>,
    freed: Condvar,
}

struct State {
    free: usize,
    /// Requests of more than one share waiting: single shares wait for
    /// them, so a large tile is not starved by a stream of small ones.
    large_waiting: usize,
}

/// Shares taken, given back when dropped.
pub(crate) struct Taken<'a> {
    shares: &'a Shares,
    count: usize,
}

impl Shares {
    pub fn new(bytes: u64, total: usize) -> Self {
        Shares {
            bytes: bytes.max(1),
            total: total.max(1),
            state: Mutex::new(State {
                free: total.max(1),
                large_waiting: 0,
            }),
            freed: Condvar::new(),
        }
    }

    /// Shares a tile of `bytes` needs (at least one).
    pub fn needed(&self, bytes: u64) -> usize {
        bytes.div_ceil(self.bytes).max(1) as usize
    }

    /// Takes `count` shares, waiting for them; `None` when there are
    /// fewer in all.
    pub fn take(&self, count: usize) -> Option<Taken<'_>> {
        if count > self.total {
            return None;
        }
        let large = count > 1;
        let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        if large {
            s.large_waiting += 1;
        }
        while s.free < count || (!large && s.large_waiting > 0) {
            s = self.freed.wait(s).unwrap_or_else(|e| e.into_inner());
        }
        s.free -= count;
        if large {
            s.large_waiting -= 1;
        }
        Some(Taken {
            shares: self,
            count,
        })
    }
}

impl Drop for Taken<'_> {
    fn drop(&mut self) {
        let mut s = self.shares.state.lock().unwrap_or_else(|e| e.into_inner());
        s.free += self.count;
        self.shares.freed.notify_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    #[test]
    fn tiles_never_hold_more_shares_than_there_are() {
        let shares = Shares::new(100, 3);
        assert_eq!(shares.needed(1), 1);
        assert_eq!(shares.needed(250), 3);
        assert!(shares.take(4).is_none());
        let held = AtomicUsize::new(0);
        let most = AtomicUsize::new(0);
        std::thread::scope(|s| {
            for w in 0..4 {
                let (shares, held, most) = (&shares, &held, &most);
                s.spawn(move || {
                    for k in 0..50 {
                        let count = if (w + k) % 7 == 0 { 3 } else { 1 };
                        let _t = shares.take(count).expect("fits");
                        let now = held.fetch_add(count, Ordering::SeqCst) + count;
                        most.fetch_max(now, Ordering::SeqCst);
                        std::thread::yield_now();
                        held.fetch_sub(count, Ordering::SeqCst);
                    }
                });
            }
        });
        assert!(most.load(Ordering::SeqCst) <= 3);
        assert_eq!(held.load(Ordering::SeqCst), 0);
    }
}
