//! The projection method (paper 2) on real scans of several kinds (issue
//! 39): aerial town and forest, a city block, an aerial sample, two
//! depth-camera frames of a room, a depth-camera crop of a milk carton,
//! three terrestrial scans (sources and licences in each fixture folder's
//! README). Each mesh, read back from the file written, has no non-manifold
//! edge, no inconsistently wound edge and no self-intersecting pair; the
//! depth-camera frames' quantised points put vertices within 1e-7 of a
//! neighbour's edge, which the kernel's f32 coordinates passed and the
//! written f64 ones touch (7 pairs in the room, 2 on the carton before).

mod common;

use common::reconstruct_fixture;
use scanmesh::io::read_mesh_any;
use scanmesh::mesh::{quality, self_intersections, Mesh};

#[test]
fn real_scans_project_without_crossing_or_twisting() {
    let dir = tempfile::tempdir().expect("tmp");
    for rel in [
        "las/autzen_town_cut.las",
        "las/32-1-472-150-76.laz",
        "las/warsaw_small.las",
        "las/sample_c.laz",
        "e57/kinect_two_scans.e57",
        "e57/three_scans.e57",
        "pcd/organised_milk.pcd",
    ] {
        let out = dir.path().join("m.ply");
        let said = reconstruct_fixture(rel, &out, &["--method", "projection", "--skip-invalid"]);
        assert!(said.contains(", 0 non-manifold edges"), "{rel}: {said}");
        assert!(said.contains(", 0 inconsistently wound"), "{rel}: {said}");
        let (v, t) = read_mesh_any(&out).expect("read");
        let mesh = Mesh::new(v, t);
        let q = quality(&mesh);
        assert!(q.triangles > 200, "{rel}: {q}");
        assert_eq!(q.non_manifold_edges, 0, "{rel}: {q}");
        assert!(q.consistently_oriented, "{rel}: {q}");
        assert_eq!(self_intersections(&mesh).pairs, 0, "{rel}");
    }
}
