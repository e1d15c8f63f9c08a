//! Memory of the tiles in flight: the plan's room for tiles (its free
//! memory, ARCHITECTURE.md, "Memory model"), taken by each tile before it
//! is loaded for the bytes its counted points hold
//! (`TileKernel::bytes_to_load`), grown without waiting to what it says it
//! needs once loaded (`TileKernel::bytes_for`), and given back when it is
//! done, so the tiles running at once never hold more than the plan. A
//! kernel whose need varies by tile (the Delaunay surface's reloads, the
//! marching cubes' bands in sparse regions) then waits until the room has
//! its bytes. A tile that needs more than the whole room is an error: no
//! run could keep the promise.
//!
//! The room is counted in bytes, not in tiles of the plan's size: a store
//! tiled for a larger budget leaves room for one planned tile and most of
//! another, which a tile needing 1.5 planned tiles may use.

use std::sync::{Condvar, Mutex};

/// The room of one run.
pub(crate) struct Shares {
    /// Bytes of one planned tile: a tile needing more waits ahead of the
    /// others, so it is not starved by a stream of small ones.
    tile: u64,
    room: u64,
    state: Mutex<State>,
    freed: Condvar,
}

struct State {
    free: u64,
    /// Requests of more than a planned tile waiting.
    large_waiting: usize,
}

/// Bytes taken, given back when dropped.
pub(crate) struct Taken<'a> {
    shares: &'a Shares,
    bytes: u64,
}

impl Shares {
    /// A room of `room` bytes for tiles planned at `tile` bytes each.
    pub fn new(tile: u64, room: u64) -> Self {
        let tile = tile.max(1);
        let room = room.max(tile);
        Shares {
            tile,
            room,
            state: Mutex::new(State {
                free: room,
                large_waiting: 0,
            }),
            freed: Condvar::new(),
        }
    }

    /// The room, in bytes.
    pub fn room(&self) -> u64 {
        self.room
    }

    /// Takes `bytes` of the room, waiting for them; `None` when the room
    /// is smaller.
    pub fn take(&self, bytes: u64) -> Option<Taken<'_>> {
        if bytes > self.room {
            return None;
        }
        let large = bytes > self.tile;
        let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        if large {
            s.large_waiting += 1;
        }
        while s.free < bytes || (!large && s.large_waiting > 0) {
            s = self.freed.wait(s).unwrap_or_else(|e| e.into_inner());
        }
        s.free -= bytes;
        if large {
            s.large_waiting -= 1;
        }
        Some(Taken {
            shares: self,
            bytes,
        })
    }
}

impl Taken<'_> {
    /// Grows what is taken to `bytes` if the room has the rest free now,
    /// without waiting: a worker never waits while holding bytes, so two
    /// growing tiles cannot each wait for the other's.
    pub fn try_grow_to(&mut self, bytes: u64) -> bool {
        if bytes <= self.bytes {
            return true;
        }
        let mut s = self.shares.state.lock().unwrap_or_else(|e| e.into_inner());
        let more = bytes - self.bytes;
        if s.free < more || s.large_waiting > 0 {
            return false;
        }
        s.free -= more;
        self.bytes = bytes;
        true
    }
}

impl Drop for Taken<'_> {
    fn drop(&mut self) {
        let mut s = self.shares.state.lock().unwrap_or_else(|e| e.into_inner());
        s.free += self.bytes;
        self.shares.freed.notify_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicU64, Ordering};

    #[test]
    fn tiles_never_hold_more_than_the_room() {
        let shares = Shares::new(100, 250);
        assert!(shares.take(251).is_none());
        assert!(shares.take(250).is_some());
        let held = AtomicU64::new(0);
        let most = AtomicU64::new(0);
        std::thread::scope(|s| {
            for w in 0..4u64 {
                let (shares, held, most) = (&shares, &held, &most);
                s.spawn(move || {
                    for k in 0..50 {
                        let bytes = if (w + k) % 7 == 0 { 180 } else { 30 + 10 * w };
                        let _t = shares.take(bytes).expect("fits");
                        let now = held.fetch_add(bytes, Ordering::SeqCst) + bytes;
                        most.fetch_max(now, Ordering::SeqCst);
                        std::thread::yield_now();
                        held.fetch_sub(bytes, Ordering::SeqCst);
                    }
                });
            }
        });
        assert!(most.load(Ordering::SeqCst) <= 250);
        assert_eq!(held.load(Ordering::SeqCst), 0);
    }

    #[test]
    fn a_grow_takes_only_what_is_free_and_gives_all_back() {
        let shares = Shares::new(100, 250);
        let mut a = shares.take(100).expect("fits");
        let b = shares.take(100).expect("fits");
        assert!(!a.try_grow_to(151), "only 50 bytes are free");
        assert!(a.try_grow_to(150));
        drop(b);
        assert!(a.try_grow_to(250));
        drop(a);
        assert!(shares.take(250).is_some());
    }
}
