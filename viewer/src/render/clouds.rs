//! The renderer's billboard clouds: adding cloud assets and choosing each instance's
//! level, morph and dissolve per frame (`cloud_pass` module docs).

use glam::{Mat4, Vec3};

use billow_format::CloudAsset;

use super::{check_transforms, default_lod_distances, CloudEntry, Renderer};
use crate::camera::ViewCamera;
use crate::cloud_pass::{choose_lod, CloudDraw, CloudPass, LodChoice, DEFAULT_DISSOLVE};
use crate::mesh_pass::MeshPass;
use crate::ViewError;

impl Renderer {
    /// Adds a billboard-cloud asset drawn once per transform; its kept mesh is added to
    /// the mesh pass once per instance. `distances`: the level-change distances
    /// (`None`: [`default_lod_distances`]); `transition`: the fraction of each distance
    /// over which vertices morph.
    pub fn add_cloud(
        &mut self,
        asset: &CloudAsset,
        instances: Vec<Mat4>,
        distances: Option<Vec<f32>>,
        transition: f32,
        fov_y: f32,
    ) -> Result<(), ViewError> {
        self.add_cloud_blocks(asset, None, instances, distances, transition, fov_y)
    }

    /// [`Renderer::add_cloud`] of a compressed asset with its BC7 `blocks` (format 1.2):
    /// atlases and normal maps uploaded as blocks where the device allows it, else decoded.
    pub fn add_cloud_blocks(
        &mut self,
        asset: &CloudAsset,
        blocks: Option<&billow_format::CloudBlocks>,
        instances: Vec<Mat4>,
        distances: Option<Vec<f32>>,
        transition: f32,
        fov_y: f32,
    ) -> Result<(), ViewError> {
        check_transforms(&instances)?;
        self.shadows.forget();
        let pass = self
            .cloud_pass
            .get_or_insert_with(|| CloudPass::new(&self.gpu, &self.shadows.receiver_layout));
        let gpu = pass.upload_with(&self.gpu, asset, blocks)?;
        self.block_textures += gpu.block_textures;
        let levels = gpu.level_count();
        let distances = match distances {
            Some(d) => d,
            None => default_lod_distances(gpu.radius, fov_y, levels),
        };
        if distances.len() + 1 != levels
            || !distances.windows(2).all(|w| w[0] < w[1])
            || !distances.iter().all(|d| *d > 0.0 && d.is_finite())
        {
            return Err(ViewError::InvalidParam(format!(
                "a cloud with {levels} levels (foliage mesh + {} billboard levels) needs {} \
                 increasing positive LOD distances, got {distances:?}",
                levels - 1,
                levels - 1
            )));
        }
        if !(0.0..=1.0).contains(&transition) {
            return Err(ViewError::InvalidParam(format!(
                "transition {transition} must be in [0, 1]"
            )));
        }
        if !gpu.trunk.vertices.is_empty() {
            // One copy of the kept mesh per instance, all drawn with the cloud's textures
            // (uploaded once, by the cloud pass).
            let mesh_pass = self
                .mesh_pass
                .get_or_insert_with(|| MeshPass::new(&self.gpu, &self.shadows.receiver_layout));
            for m in &instances {
                let mut t = gpu.trunk.clone();
                for v in &mut t.vertices {
                    v.pos = m.transform_point3(Vec3::from(v.pos)).to_array();
                    v.normal = m.transform_vector3(Vec3::from(v.normal)).to_array();
                }
                let mesh = mesh_pass.upload_with_views(&self.gpu, &t, &gpu.mesh_textures)?;
                self.meshes.push(mesh);
            }
        }
        self.clouds.push(CloudEntry {
            gpu,
            instances,
            distances,
            transition,
            dissolve: DEFAULT_DISSOLVE,
        });
        Ok(())
    }

    /// Clouds added so far.
    pub fn cloud_count(&self) -> usize {
        self.clouds.len()
    }

    /// Sets cloud `index`'s dissolve half-width around each switch, in octaves of distance
    /// (`cloud_pass` module docs; 0 = switch in one frame).
    pub fn set_cloud_dissolve(&mut self, index: usize, octaves: f32) -> Result<(), ViewError> {
        if !(0.0..=4.0).contains(&octaves) {
            return Err(ViewError::InvalidParam(format!(
                "dissolve {octaves} must be in [0, 4] octaves"
            )));
        }
        let Some(c) = self.clouds.get_mut(index) else {
            return Err(ViewError::InvalidParam(format!(
                "no cloud {index} (there are {})",
                self.clouds.len()
            )));
        };
        c.dissolve = octaves;
        self.shadows.forget();
        Ok(())
    }

    /// Per cloud: its bounding sphere (centre placed by its first instance, radius), level-change
    /// distances and transition fraction (what [`select_level`](crate::cloud_pass::select_level) is given), for tools that
    /// sweep the LOD switches.
    pub fn cloud_lod_setup(&self) -> Vec<(Vec3, f32, Vec<f32>, f32)> {
        self.clouds
            .iter()
            .map(|c| {
                let m = c.instances.first().copied().unwrap_or(Mat4::IDENTITY);
                let centre = m.transform_point3(c.gpu.centre);
                (centre, c.gpu.radius, c.distances.clone(), c.transition)
            })
            .collect()
    }

    /// Buffers and bind groups the cloud pass has made for frames (not uploads) so far:
    /// constant from frame to frame once the instance count stops growing.
    pub fn cloud_resources_created(&self) -> u64 {
        self.cloud_pass
            .as_ref()
            .map_or(0, |p| p.resources_created())
    }

    /// Per cloud instance (cloud-major): what it shows for `camera`.
    pub(super) fn cloud_levels(&self, camera: &ViewCamera) -> Vec<LodChoice> {
        let eye = camera.eye();
        let mut out = Vec::new();
        for c in &self.clouds {
            for m in &c.instances {
                let z = self
                    .lod_distance_override
                    .unwrap_or_else(|| (m.transform_point3(c.gpu.centre) - eye).length());
                let dissolve = self.dissolve_override.unwrap_or(c.dissolve);
                out.push(choose_lod(z, &c.distances, c.transition, dissolve));
            }
        }
        out
    }

    /// One draw per cloud instance, at the levels `levels` ([`Renderer::cloud_levels`]).
    pub(super) fn cloud_draws(&self, levels: &[LodChoice]) -> Vec<CloudDraw<'_>> {
        let mut out = Vec::new();
        let mut k = 0;
        for c in &self.clouds {
            for m in &c.instances {
                let l = levels[k];
                out.push(CloudDraw {
                    cloud: &c.gpu,
                    model: *m,
                    level: l.level,
                    morph: l.morph,
                    dissolve: l.dissolve,
                    next_morph: l.next_morph,
                });
                k += 1;
            }
        }
        out
    }
}
