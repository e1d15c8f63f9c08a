//! The tiles' exactness, tested at its source: paper 4's selection on a
//! part of a cloud (the points in a box, in a shuffled order) against the
//! selection on the whole cloud. Every triangle the part is sure of (one
//! corner not doubtful, see `select::Selection::doubtful`) must be the
//! whole cloud's, and every whole-cloud triangle with such a corner in the
//! part must be the part's. The noise makes the deletions' forced choices
//! and ties common, which is where a part's own vertex numbering once
//! leaked into the result. A part that asks the store about the spheres
//! poking out of it (`tiling::Beyond`) must be sure of more, and as right.

use super::fan::{Hole, LOCAL_HOLE};
use super::select::{select, Selection};
use super::umbrella::Region;
use crate::geom::Aabb;
use crate::io::memory::MemoryReader;
use crate::progress::NoProgress;
use crate::store::{build_store, BuildOptions, PointStore, TileTarget};
use crate::synth::{generate, mean_spacing_hint, Rng, Shape};
use crate::tiling::Beyond;
use glam::DVec3;
use std::collections::BTreeSet;

fn by_id(sel: &Selection, ids: &[u64]) -> Vec<[u64; 3]> {
    sel.tris
        .iter()
        .map(|t| {
            let mut u = t.map(|v| ids[v as usize]);
            u.sort_unstable();
            u
        })
        .collect()
}

#[test]
fn a_part_is_sure_only_of_the_whole_clouds_triangles() {
    let inf = f64::INFINITY;
    // A face across the ring on three sides, at three noise levels. The
    // doubt reaches about 70 spacings in, a third of this torus, so a part
    // must be wide to be sure of anything.
    let cases = [
        (0.3, 11, DVec3::new(-inf, -0.4, -inf), DVec3::splat(inf)),
        (0.5, 12, DVec3::splat(-inf), DVec3::new(0.5, inf, inf)),
        (0.1, 13, DVec3::new(-0.6, -inf, -inf), DVec3::splat(inf)),
    ];
    for (noise, seed, lo, hi) in cases {
        let dir = tempfile::tempdir().unwrap();
        let cloud = Cloud::stored(noise, seed, &dir.path().join("s"));
        // The box in the store's coordinates (relative to its origin).
        let loaded = Aabb::new(lo - cloud.origin, hi - cloud.origin);
        let alone = check_part(
            &cloud,
            noise,
            Region {
                loaded,
                beyond: None,
            },
        );
        let beyond = Beyond::new(&cloud.store, loaded, 0.5);
        let asking = Region {
            loaded,
            beyond: Some(&beyond),
        };
        // Asking the store about spheres that poke out proves more.
        let more = check_part(&cloud, noise, asking);
        assert!(
            more > alone,
            "noise {noise}: {more} sure asking, {alone} alone"
        );
    }
}

/// A noisy torus as a store holds it (f32 relative to its origin, as the
/// tiles and `Beyond` read it), with its ids.
struct Cloud {
    store: PointStore,
    origin: DVec3,
    points: Vec<DVec3>,
    ids: Vec<u64>,
    sp: f64,
}

impl Cloud {
    fn stored(noise: f64, seed: u64, dir: &std::path::Path) -> Self {
        let shape = Shape::torus(1.0, 0.35);
        let n = 20_000;
        let sp = mean_spacing_hint(&shape, n).unwrap();
        let points = generate(&shape, n, noise * sp, seed).unwrap().points;
        let mut reader = MemoryReader::new("torus", points, None);
        let opts = BuildOptions {
            tiles: TileTarget::Points(4000),
            ..Default::default()
        };
        let store = build_store(&mut reader, dir, &opts, &NoProgress).unwrap();
        let (mut points, mut ids) = (Vec::new(), Vec::new());
        let (mut p, mut i) = (Vec::new(), Vec::new());
        for t in store.tiles() {
            store.read_points(t.start, t.count, &mut p).unwrap();
            store.read_indices(t.start, t.count, &mut i).unwrap();
            points.extend_from_slice(&p);
            ids.extend_from_slice(&i);
        }
        Cloud {
            sp,
            origin: store.origin(),
            store,
            points,
            ids,
        }
    }
}

/// Checks the part of `cloud` in `region` against the whole cloud and
/// returns how many triangles the part is sure of.
fn check_part(cloud: &Cloud, noise: f64, region: Region) -> usize {
    let (points, ids) = (&cloud.points, &cloud.ids);
    // A ceiling below most corners' spacings, so the hole radius of most
    // triangles comes from it and the rest from the spacings.
    let hole = Hole::Local {
        multiple: LOCAL_HOLE,
        ceiling: 0.8 * cloud.sp,
    };
    let whole = select(points, ids, hole, Region::everything()).unwrap();
    assert!(whole.report.cleanup.forced > 0, "no forced choice");

    let loaded = region.loaded;
    let mut part: Vec<(DVec3, u64)> = points
        .iter()
        .zip(ids)
        .filter(|(p, _)| loaded.contains(**p))
        .map(|(p, &i)| (*p, i))
        .collect();
    let mut rng = Rng::new(5);
    for k in (1..part.len()).rev() {
        part.swap(k, rng.below(k as u64 + 1) as usize);
    }
    let (pp, pi): (Vec<DVec3>, Vec<u64>) = part.into_iter().unzip();
    let sel = select(&pp, &pi, hole, region).unwrap();

    let mut sure_ids = BTreeSet::new();
    for (v, &d) in sel.doubtful.iter().enumerate() {
        if !d {
            sure_ids.insert(pi[v]);
        }
    }
    let sure = |t: &[u64; 3]| t.iter().any(|v| sure_ids.contains(v));
    let whole_set: BTreeSet<[u64; 3]> = by_id(&whole, ids).into_iter().collect();
    let part_set: BTreeSet<[u64; 3]> = by_id(&sel, &pi).into_iter().collect();
    let part_sure: Vec<&[u64; 3]> = part_set.iter().filter(|t| sure(t)).collect();
    let whole_sure: Vec<&[u64; 3]> = whole_set.iter().filter(|t| sure(t)).collect();
    assert!(
        part_sure.len() > whole_set.len() / 10,
        "{} sure of {}",
        part_sure.len(),
        whole_set.len()
    );
    let wrong = part_sure
        .iter()
        .filter(|t| !whole_set.contains(**t))
        .count();
    let missing = whole_sure
        .iter()
        .filter(|t| !part_set.contains(**t))
        .count();
    assert_eq!(
        (wrong, missing),
        (0, 0),
        "noise {noise}: sure but not the whole cloud's"
    );
    part_sure.len()
}
