//! What a frame drew ([`FrameStats`]): the renderer fills it, the volume plan adds its
//! slices and draws, `billow view --json` prints it. A leaf module.

/// What a frame drew.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct FrameStats {
    pub slices: usize,
    /// Slabs drawn, and slabs skipped because no cell meets them.
    pub slabs: usize,
    pub empty_slabs: usize,
    /// Cells of all volume instances.
    pub cells: usize,
    /// Cell × slice instances drawn (each up to a pentagon).
    pub instances: u64,
    pub draw_calls: usize,
    pub mesh_triangles: usize,
    /// World size of a level-0 voxel `v₀` (the finest over the volumes).
    pub voxel_size: f32,
    pub min_spacing: f32,
    pub max_spacing: f32,
    /// Per cloud instance: its level (0 = foliage mesh) and morph factor.
    pub cloud_lods: Vec<(usize, f32)>,
    /// Per cloud instance: how far it has dissolved into the next level (0: not
    /// dissolving; `cloud_pass` module docs).
    pub cloud_dissolves: Vec<f32>,
    /// Slices of the volumes' shadow pass (0 without shadows).
    pub shadow_slices: usize,
    /// Mesh draws and cloud instances rendered into the shadow cascades, summed over
    /// the cascades, and those left out because they lie outside a cascade's window.
    pub shadow_casters: usize,
    pub shadow_casters_culled: usize,
    /// The shadow atlas of an earlier frame was reused: nothing it depends on changed
    /// (`render::frame`'s `ShadowKey`), so no cascade was drawn and the shadow counts are
    /// those of the frame that drew it.
    pub shadow_reused: bool,
    /// Billboard quads (sides) drawn.
    pub cloud_quads: usize,
    /// Bytes written to the GPU per frame for the clouds (instance data and frame
    /// uniforms; the per-asset buffers are uploaded once).
    pub cloud_bytes_uploaded: usize,
    /// Particles drawn (at the frame's time).
    pub particles: usize,
}
