//! The lighting models of billow, pure math shared by the billboard bake
//! (`billow::bbcloud`), the reference renderer and CPU slicer (`billow::eval`), and mirrored
//! by the viewer's shaders (`mesh.wgsl`, `volume.wgsl`). Re-exported as
//! `billow::eval::lighting::{diffuse_factor, volume_diffuse_factor}`.

use glam::Vec3;

/// Direction towards the light (not normalised) where no scene names one: the viewer's
/// default scene light, the reference's and the CPU slicer's, and the billboard bake's.
pub const DEFAULT_LIGHT: Vec3 = Vec3::new(0.3, 1.0, 0.5);

/// Ambient fraction of [`DEFAULT_LIGHT`] (the unshadowed part of the light).
pub const DEFAULT_AMBIENT: f32 = 0.3;

/// `ambient + (1 − ambient) · |n·light|`: the one lighting model of billow — the
/// billboard bake's factor, the reference's, and the viewer's mesh pass (two-sided Lambert;
/// `viewer/src/shaders/mesh.wgsl`, which also multiplies the diffuse term by shadow
/// visibility).
#[inline]
pub fn diffuse_factor(n: Vec3, light: Vec3, ambient: f32) -> f32 {
    ambient + (1.0 - ambient) * n.dot(light).abs()
}

/// The runtime shading of a volume voxel (`billow::eval::lighting::Lighting::Volume`, the CPU
/// slicer and the viewer's `volume.wgsl`): `ambient + (1 − ambient) · visibility · max(n̄·light, 0)`.
///
/// `n` is the voxel's **Toksvig-filtered** normal, the alpha-weighted mean of the unit
/// normals it holds, *not* renormalised (`|n̄| ≤ 1`, `src/voxelize/toksvig.rs`); `light`
/// is the unit direction towards the light. This is the *effective normal* reading of
/// Toksvig: Lambert's cosine is linear in the normal, so `n̄·L` is exactly the mean of
/// `n·L` over the voxel's normals, and the shorter (rougher) the mean, the weaker the
/// directional term; clamping after the mean under-estimates only where the voxel's
/// normals straddle the terminator. A voxel whose normals cancel (`n̄ = 0`: opposite
/// faces, fuzz) gets the ambient term alone.
///
/// **One-sided**: volumes with normals are closed surfaces (`voxelize --normals auto`
/// keeps normals only where they agree, docs/voxelize.md), whose far side must stay dark
/// to show a terminator; the two-sided [`diffuse_factor`] of leaf cards would light it
/// as brightly as the near side. `visibility` is the shadow map's (1 without shadows).
#[inline]
pub fn volume_diffuse_factor(n: Vec3, light: Vec3, ambient: f32, visibility: f32) -> f32 {
    ambient + (1.0 - ambient) * visibility * n.dot(light).max(0.0)
}
