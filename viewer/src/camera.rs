//! The camera as the renderer needs it: a view matrix and a perspective with the
//! conventions of `billow::camera::Camera` (same projection formula, same pixel size).

use glam::{Mat4, Vec3, Vec4};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewCamera {
    /// World → view (right-handed, looking down −Z).
    pub view: Mat4,
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
    /// From the parts of a `billow::camera::Camera` (`view()`, `fov_y`, size, near, far).
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
            fov_y,
            width,
            height,
            near,
            far,
            ortho_half_height: None,
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

    /// A look-at camera; the view matrix is built exactly like `billow::camera::Camera::view`.
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
        let f = (target - eye).normalize();
        let up = if f.cross(up).length_squared() > 1e-8 * up.length_squared() {
            up
        } else if f.y.abs() > 0.999 {
            Vec3::NEG_Z
        } else {
            Vec3::Y
        };
        let s = f.cross(up).normalize();
        let u = s.cross(f);
        let view = Mat4::from_cols(
            Vec4::new(s.x, u.x, -f.x, 0.0),
            Vec4::new(s.y, u.y, -f.y, 0.0),
            Vec4::new(s.z, u.z, -f.z, 0.0),
            Vec4::new(-s.dot(eye), -u.dot(eye), f.dot(eye), 1.0),
        );
        Self::from_parts(view, fov_y, width, height, near, far)
    }

    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height.max(1) as f32
    }

    /// View → clip (wgpu depth 0..1), the formula of `billow::camera::Camera::projection`.
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
        let h = 1.0 / (0.5 * self.fov_y).tan();
        let w = h / self.aspect();
        let r = self.far / (self.near - self.far);
        Mat4::from_cols(
            Vec4::new(w, 0.0, 0.0, 0.0),
            Vec4::new(0.0, h, 0.0, 0.0),
            Vec4::new(0.0, 0.0, r, -1.0),
            Vec4::new(0.0, 0.0, r * self.near, 0.0),
        )
    }

    /// World size of one pixel at view depth `depth` (the paper's `z·tan(fov/2)/(h/2)`).
    pub fn pixel_size_at(&self, depth: f32) -> f32 {
        if let Some(hh) = self.ortho_half_height {
            return 2.0 * hh / self.height as f32;
        }
        depth * (0.5 * self.fov_y).tan() / (0.5 * self.height as f32)
    }

    /// The camera position in world space.
    pub fn eye(&self) -> Vec3 {
        self.view.inverse().w_axis.truncate()
    }

    /// World point → view space.
    pub fn to_view(&self, p: Vec3) -> Vec3 {
        (self.view * Vec4::new(p.x, p.y, p.z, 1.0)).truncate()
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
