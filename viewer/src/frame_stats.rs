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
    /// No cascade was drawn: every tile of the shadow atlas was kept from earlier
    /// frames (nothing it depends on changed, `render::frame`'s `ShadowKey` and `Tile`,
    /// or a far tile kept while the camera moves, `Renderer::shadow_keep_far`), and the
    /// shadow counts are those of the frames that drew them.
    pub shadow_reused: bool,
    /// Per shadow cascade (finest first), what was drawn into it (as `shadow_casters`:
    /// those of the frame that drew the atlas when it is reused).
    pub shadow_cascades: Vec<CascadeStats>,
    /// Billboard quads (sides) drawn.
    pub cloud_quads: usize,
    /// Bytes written to the GPU per frame for the clouds (instance data and frame
    /// uniforms; the per-asset buffers are uploaded once).
    pub cloud_bytes_uploaded: usize,
    /// Particles drawn (at the frame's time).
    pub particles: usize,
}

/// What one shadow cascade drew: load-independent counts beside the frame's wall time.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct CascadeStats {
    /// Side of one of its texels across the light, world units.
    pub texel: f32,
    /// Its tile was drawn this frame (else kept from an earlier one).
    pub drawn: bool,
    /// Frames its tile has been kept while the cascade's fitted window or the clouds'
    /// levels moved on (`Renderer::shadow_keep_far`; 0: what this frame would draw).
    pub age: u32,
    /// Slices of the volumes drawn into it.
    pub slices: usize,
    /// Mesh draws and cloud instances drawn into it (a dissolving instance counts in
    /// both its levels), and those left out (outside its window).
    pub casters: usize,
    pub culled: usize,
    /// The clouds' billboard quads (the side facing the light) and foliage triangles.
    pub cloud_quads: usize,
    pub foliage_triangles: usize,
    /// The area of those quads and triangles across the light, in texels: the fragments
    /// the alpha test runs on, overlaps counted, before clipping to the window (the
    /// cascades' cost on a software rasteriser is mostly this fill).
    pub cloud_texels: f64,
}
