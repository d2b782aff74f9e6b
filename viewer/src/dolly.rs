//! The camera of a LOD-switch sweep (`billow view CLOUD --lod-sweep DIR`, docs/bbcloud.md,
//! "LOD switches"): a dolly zoom on the renderer's one billboard cloud. The camera moves
//! along a fixed direction while the field of view shrinks so the cloud keeps its screen
//! size. Which size: by default the one the viewer shows at the switch distance `D` with the
//! scene's field of view (`tan(fov_z/2) = tan(fov/2)·D/z`), i.e. each switch is judged at the
//! size it happens at on screen; with a fill fraction F the cloud's bounding sphere spans F
//! of the frame height at every switch (`tan(fov_z/2) = R/(F·z)`, a harsher test for the
//! coarse levels, which the viewer only shows small). Which frames are taken and how they
//! are judged is the `billow` library's (`billow::eval::lod_sweep`).

use glam::Vec3;

use crate::target::{RgbaImage, Target};
use crate::{Renderer, ViewCamera, ViewError};

/// A dolly around the renderer's one cloud; the renderer's LOD overrides are cleared when
/// it is dropped.
pub struct Dolly<'a> {
    r: &'a mut Renderer,
    target: Target,
    centre: Vec3,
    radius: f32,
    dir: Vec3,
    /// `tan(fov/2)` of the scene's camera.
    tan_half: f32,
    /// Constant fill fraction, or `None`: the size at the switch being swept.
    fill: Option<f32>,
}

/// One frame of the dolly.
pub struct DollyFrame {
    pub image: RgbaImage,
    /// (level, morph) the renderer chose for the cloud.
    pub lod: (usize, f32),
    /// How far the cloud had dissolved into the next level (0: one level shown).
    pub dissolve: f32,
}

/// The renderer does not hold exactly one billboard cloud (it holds this many).
#[derive(Debug)]
pub struct NotOneCloud(pub usize);

impl<'a> Dolly<'a> {
    /// A dolly of `width`×`height` frames looking along `view_dir` (`fov_y`: the scene's
    /// vertical field of view, radians; `fill`: a constant fill fraction), and the cloud's
    /// level-change distances.
    pub fn new(
        r: &'a mut Renderer,
        (width, height): (u32, u32),
        (view_dir, fov_y, fill): (Vec3, f32, Option<f32>),
    ) -> Result<(Dolly<'a>, Vec<f32>), NotOneCloud> {
        let setup = r.cloud_lod_setup();
        let [(centre, radius, distances, _)] = setup.as_slice() else {
            return Err(NotOneCloud(setup.len()));
        };
        let (centre, radius, distances) = (*centre, radius.max(1e-6), distances.clone());
        let target = Target::new(&r.gpu, width, height);
        let dolly = Dolly {
            r,
            target,
            centre,
            radius,
            dir: view_dir.normalize(),
            tan_half: (0.5 * fov_y).tan(),
            fill,
        };
        Ok((dolly, distances))
    }

    /// The frame at distance `z` with the cloud as large as at the switch `d`; `lod`: force
    /// the LOD choice as if the cloud were this far away (shown alone, not dissolving).
    pub fn frame(&mut self, z: f32, d: f32, lod: Option<f32>) -> Result<DollyFrame, ViewError> {
        let tan_half = match self.fill {
            Some(f) => self.radius / (f * z),
            None => self.tan_half * d / z,
        };
        let fov = 2.0 * tan_half.atan();
        let eye = self.centre + self.dir * z;
        let near = (z - 1.5 * self.radius).max(z * 1e-3);
        let far = z + 2.0 * self.radius;
        let up = if self.dir.cross(Vec3::Y).length() < 1e-3 {
            Vec3::Z
        } else {
            Vec3::Y
        };
        let cam = ViewCamera::look_at(
            eye,
            self.centre,
            up,
            fov,
            self.target.width,
            self.target.height,
            near,
            far,
        );
        self.r.lod_distance_override = lod;
        // A forced level is shown alone (coverage frames), not dissolving.
        self.r.dissolve_override = lod.map(|_| 0.0);
        // The mesh's coverage frames (level 0 forced) sample its textures at level 0
        // (`mesh_texture_level0`): its coverage without the hashed test's noise.
        self.r.mesh_texture_level0 = lod == Some(0.0);
        let stats = self.r.render(&self.target, &cam)?;
        let image = self.target.read(&self.r.gpu)?;
        Ok(DollyFrame {
            image,
            lod: stats.cloud_lods.first().copied().unwrap_or((0, 0.0)),
            dissolve: stats.cloud_dissolves.first().copied().unwrap_or(0.0),
        })
    }
}

impl Drop for Dolly<'_> {
    fn drop(&mut self) {
        self.r.lod_distance_override = None;
        self.r.dissolve_override = None;
        self.r.mesh_texture_level0 = false;
    }
}
