//! The greedy growth (paper 2 sections 2.3-2.9): seeds in input-id order,
//! each grown to exhaustion through a first-in first-out front of FRINGE
//! vertices; processing a vertex triangulates its visible region
//! (`star.rs`, `fan.rs`) and sets its state to COMPLETED (its triangles
//! close around it) or BOUNDARY.
//!
//! Deviation: a BOUNDARY vertex that gains triangles later, from a
//! neighbour's fan, is queued again (at most [`MAX_VISITS`] times in all).
//! The paper marks it done for good; but where two fronts meet, the vertex
//! processed first saw only one of them, and re-processing it once the
//! other has arrived closes the small holes such meetings leave.
//!
//! Deterministic: seeds by input id, the front in insertion order, every
//! tie by id; nothing depends on threads.

use super::cloud::{Cloud, Neighbourhoods};
use super::fan::Fan;
use super::holes::close_three_edge_holes;
use super::params::ProjectionParams;
use super::star::{Limits, Star};
use super::surface::{State, Surface};
use std::collections::VecDeque;

/// Times a vertex may be processed.
pub const MAX_VISITS: u8 = 3;

/// The growth's state besides the surface: reused buffers and the front.
pub struct Grower {
    lim: Limits,
    star: Star,
    fan: Fan,
    queue: VecDeque<u32>,
    visits: Vec<u8>,
    /// Vertices processed, for the report.
    pub processed: u64,
}

impl Grower {
    pub fn new(params: &ProjectionParams, n: usize) -> Self {
        Grower {
            lim: Limits {
                max_edge: params.max_edge,
                tan_elevation: params.max_elevation_deg.to_radians().tan(),
                cos_max_angle: params.max_angle_deg.to_radians().cos(),
            },
            star: Star::default(),
            fan: Fan::default(),
            queue: VecDeque::new(),
            visits: vec![0; n],
            processed: 0,
        }
    }

    /// Queues `v` (a FRINGE vertex handed in, e.g. on a fixed mesh's edge).
    pub fn enqueue(&mut self, v: u32) {
        self.queue.push_back(v);
    }

    /// Grows from the queued front, then from each seed of `seeds` (in the
    /// order given: input-id order) still FREE.
    pub fn grow<H: Neighbourhoods>(&mut self, cloud: &Cloud<H>, s: &mut Surface, seeds: &[u32]) {
        self.drain(cloud, s);
        for &seed in seeds {
            if s.state[seed as usize] == State::Free
                && cloud.centre[seed as usize]
                && !inside_mesh(seed, cloud, s)
            {
                self.process(seed, cloud, s);
                self.drain(cloud, s);
            }
        }
        close_three_edge_holes(&mut self.star, cloud, s);
    }

    fn drain<H: Neighbourhoods>(&mut self, cloud: &Cloud<H>, s: &mut Surface) {
        while let Some(v) = self.queue.pop_front() {
            if s.state[v as usize] != State::Fringe {
                continue;
            }
            if !cloud.centre[v as usize] {
                s.state[v as usize] = State::Boundary;
                continue;
            }
            self.process(v, cloud, s);
        }
    }

    /// One vertex: triangulate its visible region, then update the states
    /// of everything the new triangles touch.
    fn process<H: Neighbourhoods>(&mut self, v: u32, cloud: &Cloud<H>, s: &mut Surface) {
        self.processed += 1;
        self.visits[v as usize] += 1;
        s.state[v as usize] = State::Boundary;
        if !self.star.build(v, cloud, s, &self.lim) {
            return;
        }
        self.fan.triangulate(&mut self.star, cloud, s, &self.lim);
        if s.is_closed(v) {
            s.state[v as usize] = State::Completed;
        }
        for i in 0..self.fan.added.len() {
            for x in self.fan.added[i] {
                if x != v {
                    self.touched(x, s);
                }
            }
        }
    }

    /// A vertex that just gained a triangle.
    fn touched(&mut self, x: u32, s: &mut Surface) {
        let state = s.state[x as usize];
        if state == State::Completed || state == State::Unused {
            return;
        }
        if s.is_closed(x) {
            s.state[x as usize] = State::Completed;
            return;
        }
        let requeue = state == State::Free
            || (state == State::Boundary && self.visits[x as usize] < MAX_VISITS);
        if requeue {
            s.state[x as usize] = State::Fringe;
            self.queue.push_back(x);
        }
    }
}

/// A free point with a completed neighbour lies among finished triangles
/// (left over by them, e.g. a noisy point off their plane): seeding there
/// would lay a triangle over them.
fn inside_mesh<H: Neighbourhoods>(v: u32, cloud: &Cloud<H>, s: &Surface) -> bool {
    cloud
        .hoods
        .get(v)
        .iter()
        .any(|&u| s.state[u as usize] == State::Completed)
}
