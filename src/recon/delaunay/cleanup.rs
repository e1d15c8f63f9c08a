//! Paper 4 section 2.3: deleting incompatible triangles from the union of
//! the fans. An edge is incompatible when two of its triangles make an
//! acute dihedral angle, and those triangles are incompatible. Of them,
//! only two types are deleted: (type 1) a triangle
//! with an interior vertex through which one of its edges has order 1
//! (order: triangles on the edge); (type 2) a triangle whose three vertices
//! are boundary points, with one edge of order 1 and, at each of its other
//! two edges, a triangle at an acute angle to it. When none is left and
//! incompatible edges remain, one such edge keeps one of its mutually acute
//! triangles and loses the others (the forced choice), and the two types
//! are deleted again.
//!
//! Deviations, so that the result is a function of a bounded neighbourhood
//! (tiles then agree with the whole cloud exactly) and not of the order
//! edges are visited:
//! - Rounds: every deletable triangle of a round goes at once.
//! - The forced choice is made in the same round, at every incompatible
//!   edge that is the smallest incompatible edge among those sharing a
//!   triangle with it and has no deletable triangle within two edges; the
//!   kept triangle is the one with the largest angle opposite the edge (the
//!   paper's largest-angle rule; ties by corners).
//! - At most [`MAX_ROUNDS`] rounds.
//!
//! Exactness in tiles: a vertex is *doubtful* when a fan it depends on was
//! not proven; each round can carry a difference to the triangles that may
//! go near it ([`Cleanup::spread`]), so after the rounds a triangle with no
//! doubtful corner is decided as in the whole cloud.

use glam::DVec3;

/// Rounds of deletion (each may carry doubt a ring further in tiles).
pub const MAX_ROUNDS: usize = 12;

/// Triangles with their edges indexed.
pub struct Cleanup<'a> {
    points: &'a [DVec3],
    pub tris: Vec<[u32; 3]>,
    pub alive: Vec<bool>,
    /// Edge index of each triangle's sides `(0,1), (1,2), (0,2)`.
    sides: Vec<[u32; 3]>,
    edges: Vec<(u32, u32)>,
    /// Triangles on edge `e`: `on_edge[start[e]..start[e + 1]]`.
    start: Vec<u32>,
    on_edge: Vec<u32>,
}

/// What the rounds did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CleanupReport {
    pub type1: u64,
    pub type2: u64,
    pub forced: u64,
    pub rounds: usize,
    /// Incompatible edges left after the last round.
    pub incompatible_left: u64,
}

impl<'a> Cleanup<'a> {
    /// `tris` sorted, unique, corners sorted.
    pub fn new(points: &'a [DVec3], tris: Vec<[u32; 3]>) -> Self {
        let mut keyed: Vec<(u64, u32)> = Vec::with_capacity(tris.len() * 3);
        for (t, c) in tris.iter().enumerate() {
            for (a, b) in [(c[0], c[1]), (c[1], c[2]), (c[0], c[2])] {
                keyed.push(((a as u64) << 32 | b as u64, t as u32));
            }
        }
        keyed.sort_unstable();
        let mut sides = vec![[0u32; 3]; tris.len()];
        let (mut edges, mut start, mut on_edge) = (Vec::new(), Vec::new(), Vec::new());
        for (k, &(key, t)) in keyed.iter().enumerate() {
            if k == 0 || keyed[k - 1].0 != key {
                start.push(on_edge.len() as u32);
                edges.push(((key >> 32) as u32, key as u32));
            }
            let e = edges.len() as u32 - 1;
            let c = tris[t as usize];
            let (a, b) = ((key >> 32) as u32, key as u32);
            let side = if (a, b) == (c[0], c[1]) {
                0
            } else if (a, b) == (c[1], c[2]) {
                1
            } else {
                2
            };
            sides[t as usize][side] = e;
            on_edge.push(t);
        }
        start.push(on_edge.len() as u32);
        Cleanup {
            points,
            alive: vec![true; tris.len()],
            tris,
            sides,
            edges,
            start,
            on_edge,
        }
    }

    fn on(&self, e: u32) -> impl Iterator<Item = u32> + '_ {
        let (s, t) = (self.start[e as usize], self.start[e as usize + 1]);
        self.on_edge[s as usize..t as usize]
            .iter()
            .copied()
            .filter(|&t| self.alive[t as usize])
    }

    fn order(&self, e: u32) -> usize {
        self.on(e).count()
    }

    /// The corner of `t` off edge `e`.
    fn apex(&self, t: u32, e: u32) -> u32 {
        let (a, b) = self.edges[e as usize];
        let c = self.tris[t as usize];
        c.into_iter().find(|&v| v != a && v != b).unwrap_or(a)
    }

    /// Whether triangles `s` and `t` on edge `e` make an acute dihedral angle.
    pub fn acute(&self, e: u32, s: u32, t: u32) -> bool {
        let (a, b) = self.edges[e as usize];
        let p = |v: u32| self.points[v as usize];
        let side = |t: u32| across(p(a), p(b), p(self.apex(t, e)));
        side(s).dot(side(t)) > 0.0
    }

    /// An acute pair on `e`, or more than two triangles (deviation: paper
    /// 4 calls three triangles at obtuse angles to each other compatible,
    /// but the output must be a 2-manifold; a fin standing near square to
    /// the surface is such a triple).
    fn incompatible(&self, e: u32) -> bool {
        let (s, t) = (
            self.start[e as usize] as usize,
            self.start[e as usize + 1] as usize,
        );
        let on = &self.on_edge[s..t];
        let alive = |t: u32| self.alive[t as usize];
        on.iter().filter(|&&t| alive(t)).count() > 2
            || on.iter().enumerate().any(|(k, &s)| {
                alive(s) && on[k + 1..].iter().any(|&t| alive(t) && self.acute(e, s, t))
            })
    }

    /// Whether `t` makes an acute angle with another triangle on one of its
    /// edges (only such triangles are ever deleted).
    fn is_incompatible(&self, t: u32) -> bool {
        self.sides[t as usize]
            .iter()
            .any(|&e| self.order(e) > 2 || self.on(e).any(|o| o != t && self.acute(e, t, o)))
    }

    fn type1(&self, t: u32, interior: &[bool]) -> bool {
        let c = self.tris[t as usize];
        let s = self.sides[t as usize];
        // Side k joins corners (0,1), (1,2), (0,2).
        let through = [[0, 2], [0, 1], [1, 2]];
        (0..3).any(|v| interior[c[v] as usize] && through[v].iter().any(|&k| self.order(s[k]) == 1))
    }

    fn type2(&self, t: u32, interior: &[bool]) -> bool {
        let c = self.tris[t as usize];
        if c.iter().any(|&v| interior[v as usize]) {
            return false;
        }
        let s = self.sides[t as usize];
        let partner = |e: u32| self.on(e).any(|o| o != t && self.acute(e, t, o));
        (0..3).any(|k| self.order(s[k]) == 1 && (0..3).filter(|&j| j != k).all(|j| partner(s[j])))
    }

    /// Runs the rounds; `interior` per vertex; `doubt` per vertex, grown
    /// as the rounds go (see [`Cleanup::spread`]).
    pub fn run(&mut self, interior: &[bool], doubt: &mut [bool]) -> CleanupReport {
        let mut report = CleanupReport::default();
        // Deletions only shrink edges' triangle sets, so every edge that is
        // ever incompatible is one at the start: later rounds look at those.
        let mut suspects: Vec<u32> = (0..self.edges.len() as u32)
            .filter(|&e| self.incompatible(e))
            .collect();
        for round in 0..MAX_ROUNDS {
            suspects.retain(|&e| self.incompatible(e));
            if !doubt.is_empty() {
                // What this round may decide differently, from the state
                // before it.
                self.spread(&suspects, doubt);
            }
            let dead = self.round(&suspects, interior, &mut report);
            if dead == 0 {
                break;
            }
            report.rounds = round + 1;
        }
        if !doubt.is_empty() {
            // Rounds elsewhere may go on, and with them the rounds here in
            // the whole cloud.
            for _ in report.rounds + 1..MAX_ROUNDS {
                suspects.retain(|&e| self.incompatible(e));
                self.spread(&suspects, doubt);
            }
        }
        suspects.retain(|&e| self.incompatible(e));
        report.incompatible_left = suspects.len() as u64;
        report
    }

    /// One round's doubt, `doubt` closed before and after (a triangle
    /// whose state may differ from the whole cloud's has all corners
    /// doubtful). A round decides a triangle from the triangles within
    /// three edge steps of it (a forced choice reads the deletability of
    /// the triangles on its neighbours' edges), and a differing triangle
    /// three steps away leaves a doubtful vertex on one of the two
    /// triangles between, so within one ring over the live triangles of a
    /// corner. Only triangles that may go can change: the live ones on an
    /// incompatible edge here (`suspects`), or on an edge whose
    /// incompatibility may differ in the cloud. Whether an edge is
    /// incompatible depends only on the live triangles on it, and a
    /// triangle on it that may differ has both its ends doubtful: so only
    /// an edge with both ends doubtful may differ, and only a triangle with
    /// two doubtful corners may go in the cloud and not here. Each such
    /// triangle near doubt becomes doubtful in all its corners.
    ///
    /// This replaces two rings over every fan triangle per round, which
    /// carried doubt along long dead triangles and through settled
    /// surface (measured on the 327k noisy dragon: 65 spacings deep
    /// against about 25 now). Counting a triangle with one doubtful corner
    /// as one that may go took the doubt the rounds add on the 1M noisy
    /// dragon in 25 tiles from 31 to 18 spacings (median tile; deepest 40
    /// to 26), and the deepest final doubt from 78 to 65.
    fn spread(&self, suspects: &[u32], doubt: &mut [bool]) {
        let seeds = doubt.to_vec();
        let mut near = seeds.clone();
        for (c, _) in self.tris.iter().zip(&self.alive).filter(|(_, &a)| a) {
            if c.iter().any(|&v| seeds[v as usize]) {
                for &v in c {
                    near[v as usize] = true;
                }
            }
        }
        let mut may_go: Vec<u32> = suspects.iter().flat_map(|&e| self.on(e)).collect();
        for (t, c) in self.tris.iter().enumerate() {
            let doubtful = c.iter().filter(|&&v| seeds[v as usize]).count();
            if self.alive[t] && doubtful >= 2 {
                may_go.push(t as u32);
            }
        }
        for t in may_go {
            let c = self.tris[t as usize];
            if c.iter().any(|&v| near[v as usize]) {
                for &v in &c {
                    doubt[v as usize] = true;
                }
            }
        }
    }

    /// One round over the incompatible edges `suspects` (sorted); returns
    /// the triangles deleted.
    fn round(&mut self, suspects: &[u32], interior: &[bool], report: &mut CleanupReport) -> usize {
        let mut candidates: Vec<u32> = suspects.iter().flat_map(|&e| self.on(e)).collect();
        candidates.sort_unstable();
        candidates.dedup();
        let mut kind: Vec<(u32, u8)> = Vec::new();
        for &t in &candidates {
            if self.is_incompatible(t) {
                if self.type1(t, interior) {
                    kind.push((t, 1));
                } else if self.type2(t, interior) {
                    kind.push((t, 2));
                }
            }
        }
        let deletable = |t: u32| kind.binary_search_by_key(&t, |k| k.0).is_ok();
        let incompatible = |e: u32| suspects.binary_search(&e).is_ok();
        let mut forced = Vec::new();
        for &e in suspects {
            if self.forced_here(e, &incompatible, &deletable) {
                forced.extend(self.forced_losers(e));
            }
        }
        let mut dead = 0;
        for &(t, k) in &kind {
            if k == 1 {
                report.type1 += 1;
            } else {
                report.type2 += 1;
            }
            self.alive[t as usize] = false;
            dead += 1;
        }
        for t in forced {
            if self.alive[t as usize] {
                self.alive[t as usize] = false;
                report.forced += 1;
                dead += 1;
            }
        }
        dead
    }

    /// Whether incompatible edge `e` makes its forced choice this round:
    /// no smaller incompatible edge shares a triangle with it, and no
    /// triangle within two edges is deletable by the two types.
    fn forced_here(
        &self,
        e: u32,
        incompatible: &impl Fn(u32) -> bool,
        deletable: &impl Fn(u32) -> bool,
    ) -> bool {
        for t in self.on(e) {
            for &f in &self.sides[t as usize] {
                if f != e && f < e && incompatible(f) {
                    return false;
                }
                if self.on(f).any(deletable) {
                    return false;
                }
            }
        }
        true
    }

    /// The triangles the forced choice at `e` deletes: by decreasing angle
    /// opposite `e` (ties by corners), each triangle acute to one kept
    /// before it goes, so one of every mutually acute group stays.
    fn forced_losers(&self, e: u32) -> Vec<u32> {
        let (a, b) = self.edges[e as usize];
        let p = |v: u32| self.points[v as usize];
        let cosine = |t: u32| {
            let z = p(self.apex(t, e));
            let (u, v) = (p(a) - z, p(b) - z);
            u.dot(v) / (u.length() * v.length())
        };
        let mut on: Vec<(f64, u32)> = self.on(e).map(|t| (cosine(t), t)).collect();
        on.sort_by(|s, t| {
            s.0.total_cmp(&t.0)
                .then(self.tris[s.1 as usize].cmp(&self.tris[t.1 as usize]))
        });
        let (mut kept, mut losers) = (Vec::new(), Vec::new());
        for (_, t) in on {
            if kept.iter().any(|&k| self.acute(e, k, t)) {
                losers.push(t);
            } else {
                kept.push(t);
            }
        }
        if kept.len() > 2 {
            // No acute pair left but more than two: keep the flattest pair.
            let (s, t) = self.flattest_pair(e, &kept);
            losers.extend(kept.iter().copied().filter(|&k| k != s && k != t));
        }
        losers
    }

    /// The two of `on` (on edge `e`) whose dihedral angle is closest to
    /// 180 degrees (ties: the first found, in `on`'s order).
    fn flattest_pair(&self, e: u32, on: &[u32]) -> (u32, u32) {
        let (a, b) = self.edges[e as usize];
        let p = |v: u32| self.points[v as usize];
        let side = |t: u32| across(p(a), p(b), p(self.apex(t, e))).normalize_or_zero();
        let mut best = (f64::INFINITY, on[0], on[1]);
        for (k, &s) in on.iter().enumerate() {
            for &t in &on[k + 1..] {
                let c = side(s).dot(side(t));
                if c < best.0 {
                    best = (c, s, t);
                }
            }
        }
        (best.1, best.2)
    }

    /// The triangles still alive.
    pub fn alive_triangles(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        self.tris
            .iter()
            .zip(&self.alive)
            .filter(|(_, &a)| a)
            .map(|(t, _)| *t)
    }
}

/// The part of `q - a` square to the line through `a` and `b`: which side
/// of edge `ab` a triangle's apex lies on, seen along the edge (two
/// triangles on the edge make an acute dihedral angle when theirs point
/// the same way).
pub fn across(a: DVec3, b: DVec3, q: DVec3) -> DVec3 {
    let (axis, r) = (b - a, q - a);
    r - axis * (r.dot(axis) / axis.length_squared())
}

/// Spreads doubt one ring over `tris`: every corner of a triangle with a
/// doubtful corner becomes doubtful.
pub fn dilate(tris: &[[u32; 3]], doubt: &mut [bool]) {
    let seeds: Vec<bool> = doubt.to_vec();
    for c in tris {
        if c.iter().any(|&v| seeds[v as usize]) {
            for &v in c {
                doubt[v as usize] = true;
            }
        }
    }
}
