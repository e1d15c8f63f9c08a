//! The embedded sample behind `scanmesh demo`: the Stanford dragon at low
//! resolution (the vrip reconstruction from the Stanford 3D Scanning
//! Repository, quadric-decimated by Open3D to 9,892 vertices and 20,000
//! triangles), compressed into the binary, so the main job runs on a real
//! shape with no file to find.
//!
//! Why not the repository's own res4 decimation (5,205 vertices): its
//! "crude algorithm" (the repository's words) left 358 folds, triangle
//! pairs of opposite winding, zero-thickness fins whose samples carry
//! opposite normals; 2.7 % of the sample's normals came out mis-oriented
//! (0.26 % here), and `--closed` left 10 holes where they drew the zero
//! set out of the band (1 here).
//!
//! The demo's run (`run`): the sample reconstructed in a scratch store,
//! then the mesh checked against the dragon's own triangles; the caller
//! prints what each step returns.

mod run;

use crate::io::{read_mesh_from, IoError};
use crate::pipeline::WorkspaceError;
use crate::recon::implicit::reconstruct::ReconError;
use crate::recon::projection::ProjectionError;
use crate::store::{Causes, StoreError};
use crate::synth::{generate, mean_spacing_hint, Scan, Shape, SynthError, TriMesh};

pub use run::{normals_line, picture, DemoCheck, DemoMesh, DemoMethod, DemoSample, NEXT_STEPS};

const DRAGON_PLY_GZ: &[u8] = include_bytes!("../../assets/dragon_q20k.ply.gz");

/// Why the demo could not run.
#[derive(Debug, thiserror::Error)]
pub enum DemoError {
    /// Reading the embedded sample or writing an output failed.
    #[error(transparent)]
    Io(#[from] IoError),
    /// A synthetic shape could not be sampled.
    #[error(transparent)]
    Synth(#[from] SynthError),
    /// Building or reading the scratch store failed.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// No plan fits the memory promise.
    #[error(transparent)]
    Workspace(#[from] WorkspaceError),
    /// The implicit reconstruction failed.
    #[error(transparent)]
    Implicit(#[from] ReconError),
    /// The local-projection reconstruction failed.
    #[error(transparent)]
    Projection(#[from] ProjectionError),
    /// The mesh written has nothing finite to draw.
    #[error("the demo mesh has nothing to draw")]
    NothingToDraw,
}

impl DemoError {
    /// What this error comes down to ([`Causes`]).
    pub fn causes(&self) -> Causes<'_> {
        match self {
            DemoError::Workspace(w) => w.causes(),
            DemoError::Store(e) => e.causes(),
            _ => Causes::default(),
        }
    }
}

/// The embedded dragon mesh, read straight from the binary.
pub(crate) fn dragon_mesh() -> Result<TriMesh, DemoError> {
    let name = std::path::Path::new("dragon_q20k.ply.gz (embedded)");
    let (vertices, faces) = read_mesh_from(name, DRAGON_PLY_GZ)?;
    Ok(TriMesh { vertices, faces })
}

/// `n` points sampled from the dragon with Gaussian noise of `noise_spacing`
/// times the mean spacing, with their true (face) normals.
pub fn dragon_scan(
    n: usize,
    noise_spacing: f64,
    seed: u64,
) -> Result<(Scan, TriMesh, f64), DemoError> {
    let mesh = dragon_mesh()?;
    let shape = Shape::mesh(mesh.clone());
    let spacing = mean_spacing_hint(&shape, n)?;
    let scan = generate(&shape, n, noise_spacing * spacing, seed)?;
    Ok((scan, mesh, spacing))
}
