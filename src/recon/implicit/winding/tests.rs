use super::cells::{self, Gather};
use super::*;
use crate::synth::fibonacci::fibonacci_sphere;

/// Samples of a unit sphere with outward normals, `n` of them.
fn sphere(n: usize) -> Vec<(DVec3, DVec3)> {
    fibonacci_sphere(DVec3::ZERO, 1.0, n)
        .into_iter()
        .map(|p| (p, p.normalize()))
        .collect()
}

fn tree(samples: &[(DVec3, DVec3)], leaf: f64) -> WindingTree {
    let spacing = (4.0 * PI / samples.len() as f64).sqrt();
    let mut g = Gather::new(leaf, spacing);
    for (p, n) in samples {
        g.add(*p, *n).expect("in range");
    }
    g.tree()
}

/// The sum over every sample with the sphere's exact area shares.
fn brute(samples: &[(DVec3, DVec3)], q: DVec3) -> f64 {
    let a = 4.0 * PI / samples.len() as f64;
    samples
        .iter()
        .map(|(p, n)| {
            let d = *p - q;
            a * n.dot(d) / (4.0 * PI * d.length().powi(3))
        })
        .sum()
}

/// Inside a closed surface the winding number is 1, outside 0; the tree's
/// leaf areas (from the samples' spread, not given: about 10 % over, the
/// cubes' partial cuts) and its dipoles agree with the exact sum to 0.15
/// beyond a leaf or two: the sign, which is what is asked, is never in
/// doubt.
#[test]
fn a_sphere_winds_once_inside_and_not_outside() {
    let samples = sphere(20_000);
    let t = tree(&samples, 0.1);
    for (q, inside) in [
        (DVec3::ZERO, true),
        (DVec3::new(0.3, -0.4, 0.5), true),
        (DVec3::new(0.0, 0.0, 0.85), true),
        (DVec3::new(1.2, 0.1, 0.0), false),
        (DVec3::new(-2.0, 3.0, 1.0), false),
        (DVec3::new(0.0, -1.15, 0.0), false),
    ] {
        let (w, exact) = (t.at(q), brute(&samples, q));
        let expected = if inside { 1.0 } else { 0.0 };
        assert!((exact - expected).abs() < 0.02, "{q}: exact {exact}");
        assert!((w - exact).abs() < 0.15, "{q}: tree {w}, exact {exact}");
    }
}

/// Where the samples stop (a sphere without its bottom cap), the number
/// passes smoothly through 1/2 across the opening: half way at the
/// opening's centre, inside above it, outside below.
#[test]
fn an_open_sphere_is_half_wound_across_its_opening() {
    let samples: Vec<_> = sphere(20_000)
        .into_iter()
        .filter(|(p, _)| p.z > -0.6)
        .collect();
    let t = tree(&samples, 0.1);
    let at = |z: f64| t.at(DVec3::new(0.0, 0.0, z));
    assert!(at(0.0) > 0.8, "{}", at(0.0));
    assert!((at(-0.6) - 0.5).abs() < 0.1, "{}", at(-0.6));
    assert!(at(-1.2) < 0.25, "{}", at(-1.2));
    assert!(at(-0.3) > 0.5 && at(-0.9) < 0.5);
}

/// The tree is the same bits whatever order its samples come in.
#[test]
fn the_tree_does_not_depend_on_the_samples_order() {
    let samples = sphere(5_000);
    let mut reversed = samples.clone();
    reversed.reverse();
    let q = DVec3::new(0.2, 1.7, -0.3);
    assert_eq!(tree(&samples, 0.1).at(q), tree(&reversed, 0.1).at(q));
}

/// The leaf area follows the surface, not the density: a sphere sampled
/// four times as densely has about the same leaf areas in total.
#[test]
fn leaf_areas_follow_the_surface_not_the_density() {
    let total = |n: usize| -> f64 { tree(&sphere(n), 0.1).levels[0].iter().map(|d| d.area).sum() };
    let (sparse, dense) = (total(5_000), total(20_000));
    let sphere_area = 4.0 * PI;
    assert!((dense / sphere_area - 1.0).abs() < 0.15, "{dense}");
    assert!((sparse / dense - 1.0).abs() < 0.1, "{sparse} {dense}");
}

/// The memory plan reserves the tree's largest size at 64 bytes a cell.
#[test]
fn a_cell_is_the_size_the_plan_reserves() {
    assert_eq!(std::mem::size_of::<Dipole>(), 64);
    let t = tree(&sphere(2_000), 0.2);
    assert!(t.leaves() > 0 && t.leaves() <= cells::MAX_LEAVES);
}
