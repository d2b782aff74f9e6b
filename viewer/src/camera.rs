//! The camera as the renderer needs it: a view matrix and a perspective (or, for the
//! shadow map, orthographic) projection. The view, perspective and pixel-size math is the
//! shared core's ([`billow_core::camera`]): one
//! implementation; this type adds the orthographic mode and the checks the renderer needs,
//! and the renderer converts it to its uniform layout.

use glam::{Mat4, Vec3, Vec4};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewCamera {
    /// World → view (right-handed, looking down −Z).
    pub view: Mat4,
    /// The eye in world space: as given ([`ViewCamera::look_at`], a core camera) or
    /// recovered from `view` ([`ViewCamera::from_parts`]). [`ViewCamera::to_view`]
    /// subtracts it before rotating: far from the origin (a cell at 1e5) `view·p = R·p +
    /// t` cancels in f32 and moves each point by its own rounding. It must stay the eye
    /// of `view`: change the view with [`ViewCamera::with_view`], not a struct update.
    pub eye: Vec3,
    /// Vertical field of view, radians, in `(0, π)`.
    pub fov_y: f32,
    pub width: u32,
    pub height: u32,
    pub near: f32,
    pub far: f32,
    /// `Some(h)`: an orthographic camera showing `2h` world units vertically (`fov_y` is
    /// then unused) — the light's camera of the shadow map.
    pub ortho_half_height: Option<f32>,
}

impl ViewCamera {
    /// From the parts of a `billow_core::camera::Camera` (`view()`, `fov_y`, size, near, far).
    pub fn from_parts(
        view: Mat4,
        fov_y: f32,
        width: u32,
        height: u32,
        near: f32,
        far: f32,
    ) -> Self {
        ViewCamera {
            view,
            eye: view.inverse().w_axis.truncate(),
            fov_y,
            width,
            height,
            near,
            far,
            ortho_half_height: None,
        }
    }

    /// The perspective camera of a core camera (`billow_core::camera::Camera`): its view,
    /// field of view, size and clip distances.
    pub fn from_camera(c: &billow_core::camera::Camera) -> Self {
        Self {
            eye: c.eye,
            ..Self::from_parts(c.view(), c.fov_y, c.width, c.height, c.near, c.far)
        }
    }

    /// An orthographic camera at `eye` looking along `dir`, `2·half_height` world units
    /// tall, depth range `[near, far]` from the eye.
    #[allow(clippy::too_many_arguments)]
    pub fn orthographic(
        eye: Vec3,
        dir: Vec3,
        up: Vec3,
        half_height: f32,
        width: u32,
        height: u32,
        near: f32,
        far: f32,
    ) -> Self {
        let mut c = Self::look_at(eye, eye + dir, up, 1.0, width, height, near, far);
        c.ortho_half_height = Some(half_height);
        c
    }

    /// A look-at camera; the view matrix is [`billow_core::camera::look_at`]'s (as
    /// `billow_core::camera::Camera::view`).
    #[allow(clippy::too_many_arguments)]
    pub fn look_at(
        eye: Vec3,
        target: Vec3,
        up: Vec3,
        fov_y: f32,
        width: u32,
        height: u32,
        near: f32,
        far: f32,
    ) -> Self {
        let view = billow_core::camera::look_at(eye, target, up);
        Self {
            eye,
            ..Self::from_parts(view, fov_y, width, height, near, far)
        }
    }

    /// The same camera with another view matrix (its eye recovered from it).
    pub fn with_view(self, view: Mat4) -> Self {
        ViewCamera {
            view,
            eye: view.inverse().w_axis.truncate(),
            ..self
        }
    }

    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height.max(1) as f32
    }

    /// View → clip (wgpu depth 0..1): [`billow_core::camera::perspective`] (as
    /// `billow_core::camera::Camera::projection`), or the orthographic projection.
    pub fn projection(&self) -> Mat4 {
        if let Some(hh) = self.ortho_half_height {
            let range = self.far - self.near;
            return Mat4::from_cols(
                Vec4::new(1.0 / (hh * self.aspect()), 0.0, 0.0, 0.0),
                Vec4::new(0.0, 1.0 / hh, 0.0, 0.0),
                Vec4::new(0.0, 0.0, -1.0 / range, 0.0),
                Vec4::new(0.0, 0.0, -self.near / range, 1.0),
            );
        }
        billow_core::camera::perspective(self.fov_y, self.aspect(), self.near, self.far)
    }

    /// World size of one pixel at view depth `depth` (the paper's `z·tan(fov/2)/(h/2)`).
    pub fn pixel_size_at(&self, depth: f32) -> f32 {
        if let Some(hh) = self.ortho_half_height {
            return 2.0 * hh / self.height as f32;
        }
        billow_core::camera::pixel_size_at(self.fov_y, self.height, depth)
    }

    /// The camera position in world space.
    pub fn eye(&self) -> Vec3 {
        self.eye
    }

    /// World point → view space, camera-relative: `R·(p − eye)` (as the CPU slicer),
    /// equal to `view·p` in exact arithmetic.
    pub fn to_view(&self, p: Vec3) -> Vec3 {
        glam::Mat3::from_mat4(self.view) * (p - self.eye)
    }

    /// `Err` with the reason when the camera cannot render.
    pub fn validate(&self) -> Result<(), crate::ViewError> {
        let bad = |m: String| Err(crate::ViewError::InvalidParam(m));
        if self.width == 0 || self.height == 0 || self.width > 16384 || self.height > 16384 {
            return bad(format!(
                "image size {}x{} must be 1..=16384 per side",
                self.width, self.height
            ));
        }
        if let Some(hh) = self.ortho_half_height {
            if !(hh > 0.0 && hh.is_finite()) {
                return bad(format!("orthographic half height {hh} must be > 0"));
            }
        } else if !(self.fov_y > 0.0 && self.fov_y < std::f32::consts::PI) {
            return bad(format!(
                "field of view {} rad must be in (0, π)",
                self.fov_y
            ));
        }
        if !(self.near > 0.0 && self.far > self.near && self.far.is_finite()) {
            return bad(format!(
                "near {} / far {} must satisfy 0 < near < far",
                self.near, self.far
            ));
        }
        if !self.view.is_finite() {
            return bad("view matrix is not finite".into());
        }
        Ok(())
    }
}
