//! A perspective pinhole camera, its primary rays, and the fixed evaluation view set.
//!
//! Conventions (shared by the reference ray tracer, the CPU slicer and the viewer):
//! - world space is right-handed; view space is right-handed with the camera at the
//!   origin looking down **−Z**, +Y up, +X right (`glam::Mat4::look_at_rh`);
//! - clip space is wgpu's: right-handed perspective, depth in `0..1` (near → 0, far → 1);
//! - pixel `(x, y)` covers `[x, x+1) × [y, y+1)`, row 0 at the **top** of the image;
//!   a sample at `(x + jx, y + jy)` with `jx, jy ∈ [0,1)` (centre = 0.5, 0.5);
//! - [`Camera::ray`] returns an *unnormalised* direction whose view-space z component is
//!   −1, so the ray parameter `t` **is the view depth** (distance along −Z); rays are
//!   valid for `t ∈ [near, far]`, exactly what a rasterizer's clip planes keep.
//!
//! Framing: the bounding sphere of the bounds (centre = box centre, radius = half the
//! box diagonal) is fitted inside the *smaller* of the two fields of view:
//! `distance = radius / sin(fov_min / 2)`, the "framed distance". The evaluation view
//! set ([`view_set`]) looks at the content from 6 axis and 8 diagonal directions,
//! each at 1×, 4× and 16× the framed distance, always with the same image size.
//!
//! The matrices are free functions too ([`look_at`], [`perspective`],
//! [`pixel_size_at`]): the viewer's camera (`billow_view::ViewCamera`, which adds an
//! orthographic mode for the shadow map) builds its view and projection with them and
//! converts to its uniform layout, so the two renderers cannot drift apart.
//!
//! The library and the viewer use it from here (`billow::camera`, the path it had before
//! it moved here, is gone).

// `!(a < b)` comparisons are deliberate: they also catch NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::{Mat4, Vec3, Vec4};

use crate::Aabb;

/// A perspective camera with its image size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    /// Approximate up vector (need not be orthogonal to the view direction, must not be parallel).
    pub up: Vec3,
    /// Vertical field of view in radians, in `(0, π)`.
    pub fov_y: f32,
    pub width: u32,
    pub height: u32,
    /// Near and far clip distances along the view axis, `0 < near < far`.
    pub near: f32,
    pub far: f32,
}

/// A primary ray: `origin + t · dir`, valid for `t ∈ [t_min, t_max]`; `t` is view depth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraRay {
    pub origin: Vec3,
    /// Unnormalised; its component along the view axis is 1.
    pub dir: Vec3,
    pub t_min: f32,
    pub t_max: f32,
}

/// Where [`framing`] puts the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Framing {
    pub target: Vec3,
    pub eye: Vec3,
    /// Distance from eye to target.
    pub distance: f32,
    /// Bounding-sphere radius.
    pub radius: f32,
}

impl Camera {
    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height.max(1) as f32
    }

    /// `tan(fov_y / 2)`.
    pub fn tan_half_fov_y(&self) -> f32 {
        (0.5 * self.fov_y).tan()
    }

    /// Horizontal field of view in radians.
    pub fn fov_x(&self) -> f32 {
        2.0 * (self.tan_half_fov_y() * self.aspect()).atan()
    }

    /// World → view matrix (right-handed, looking down −Z).
    pub fn view(&self) -> Mat4 {
        look_at(self.eye, self.target, self.up)
    }

    /// View → clip matrix (wgpu depth range 0..1).
    pub fn projection(&self) -> Mat4 {
        perspective(self.fov_y, self.aspect(), self.near, self.far)
    }

    /// World → clip matrix.
    pub fn view_projection(&self) -> Mat4 {
        self.projection() * self.view()
    }

    /// The up vector actually used: `up`, or a perpendicular fallback when `up` is
    /// (nearly) parallel to the view direction.
    pub fn safe_up(&self) -> Vec3 {
        safe_up(self.eye, self.target, self.up)
    }

    /// Primary ray through the image point `(px, py)` in pixel units (pixel centre of
    /// pixel `(x, y)` is `(x + 0.5, y + 0.5)`), in world space.
    pub fn ray(&self, px: f32, py: f32) -> CameraRay {
        let d = self.view_dir_of_pixel(px, py);
        let inv = self.view().inverse();
        CameraRay {
            origin: self.eye,
            dir: inv.transform_vector3(d),
            t_min: self.near,
            t_max: self.far,
        }
    }

    /// View-space direction through `(px, py)`, with z = −1.
    pub fn view_dir_of_pixel(&self, px: f32, py: f32) -> Vec3 {
        let t = self.tan_half_fov_y();
        let ndc_x = 2.0 * px / self.width as f32 - 1.0;
        let ndc_y = 1.0 - 2.0 * py / self.height as f32;
        Vec3::new(ndc_x * t * self.aspect(), ndc_y * t, -1.0)
    }

    /// A view-space point → pixel coordinates `(px, py)` (inverse of
    /// [`Camera::view_dir_of_pixel`]); `None` at or behind the eye.
    pub fn view_to_pixel(&self, p: Vec3) -> Option<(f32, f32)> {
        let depth = -p.z;
        if !(depth > 0.0) {
            return None;
        }
        let t = self.tan_half_fov_y();
        let ndc_x = p.x / (depth * t * self.aspect());
        let ndc_y = p.y / (depth * t);
        Some((
            0.5 * (ndc_x + 1.0) * self.width as f32,
            0.5 * (1.0 - ndc_y) * self.height as f32,
        ))
    }

    /// World size of one pixel at view depth `z` (the paper's `z · tan(fov/2) / (h/2)`).
    pub fn pixel_size_at(&self, depth: f32) -> f32 {
        pixel_size_at(self.fov_y, self.height, depth)
    }

    /// A camera looking along `view_dir` at `bounds`, at `distance_factor` × the framed
    /// distance, near/far enclosing the bounding sphere with margin.
    pub fn framed(
        bounds: &Aabb,
        view_dir: Vec3,
        fov_y: f32,
        width: u32,
        height: u32,
        distance_factor: f32,
    ) -> Camera {
        let aspect = width as f32 / height.max(1) as f32;
        let fov_x = 2.0 * ((0.5 * fov_y).tan() * aspect).atan();
        let f = framing(bounds, view_dir, fov_y.min(fov_x));
        let distance = f.distance * distance_factor;
        let dir = view_dir.normalize_or(Vec3::NEG_Z);
        let eye = f.target - dir * distance;
        let r = f.radius.max(1e-6);
        Camera {
            eye,
            target: f.target,
            up: default_up(dir),
            fov_y,
            width,
            height,
            near: ((distance - r) * 0.5).max(r * 1e-3),
            far: (distance + r) * 2.0,
        }
    }
}

/// World → view matrix of a camera at `eye` looking at `target` (right-handed, looking
/// down −Z), `up` replaced by [`safe_up`]'s fallback when (nearly) parallel to the view
/// direction.
pub fn look_at(eye: Vec3, target: Vec3, up: Vec3) -> Mat4 {
    let f = (target - eye).normalize();
    let s = f.cross(safe_up(eye, target, up)).normalize();
    let u = s.cross(f);
    Mat4::from_cols(
        Vec4::new(s.x, u.x, -f.x, 0.0),
        Vec4::new(s.y, u.y, -f.y, 0.0),
        Vec4::new(s.z, u.z, -f.z, 0.0),
        Vec4::new(-s.dot(eye), -u.dot(eye), f.dot(eye), 1.0),
    )
}

/// The up vector a look-at camera uses: `up`, or [`default_up`] of the view direction when
/// `up` is (nearly) parallel to it.
pub fn safe_up(eye: Vec3, target: Vec3, up: Vec3) -> Vec3 {
    let fwd = (target - eye).normalize_or_zero();
    if fwd.cross(up).length_squared() > 1e-8 * up.length_squared() {
        up
    } else {
        default_up(fwd)
    }
}

/// View → clip matrix of a perspective with vertical field of view `fov_y` (radians),
/// `aspect` = width / height, clip distances `near < far`; wgpu's depth range `0..1`.
pub fn perspective(fov_y: f32, aspect: f32, near: f32, far: f32) -> Mat4 {
    let h = 1.0 / (0.5 * fov_y).tan();
    let w = h / aspect;
    let r = far / (near - far);
    Mat4::from_cols(
        Vec4::new(w, 0.0, 0.0, 0.0),
        Vec4::new(0.0, h, 0.0, 0.0),
        Vec4::new(0.0, 0.0, r, -1.0),
        Vec4::new(0.0, 0.0, r * near, 0.0),
    )
}

/// World size of one pixel at view depth `depth` for a perspective of vertical field of
/// view `fov_y` on an image `height` pixels tall (the paper's `z · tan(fov/2) / (h/2)`).
pub fn pixel_size_at(fov_y: f32, height: u32, depth: f32) -> f32 {
    depth * (0.5 * fov_y).tan() / (0.5 * height as f32)
}

/// World +Y, or −Z when looking (nearly) straight up or down.
pub fn default_up(view_dir: Vec3) -> Vec3 {
    let d = view_dir.normalize_or_zero();
    if d.y.abs() > 0.999 {
        Vec3::NEG_Z
    } else {
        Vec3::Y
    }
}

/// Places a camera looking along `view_dir` so the bounding sphere of `bounds` just fills
/// a field of view `fov` (radians; pass the smaller of the horizontal and vertical fovs).
pub fn framing(bounds: &Aabb, view_dir: Vec3, fov: f32) -> Framing {
    let (target, radius) = if bounds.is_empty() {
        (Vec3::ZERO, 1.0)
    } else {
        (bounds.center(), (0.5 * bounds.size().length()).max(1e-6))
    };
    let distance = radius / (0.5 * fov).sin().max(1e-6);
    let dir = view_dir.normalize_or(Vec3::NEG_Z);
    Framing {
        target,
        eye: target - dir * distance,
        distance,
        radius,
    }
}

/// One view of the evaluation set.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewSpec {
    /// e.g. `"-z@1x"`, `"+x+y-z@16x"`: the direction the camera looks along, and the
    /// multiple of the framed distance.
    pub name: String,
    /// Direction the camera looks along (unit).
    pub dir: Vec3,
    pub distance_factor: f32,
}

/// Which directions of the view set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewDirections {
    /// ±X, ±Y, ±Z.
    Axes,
    /// The 8 directions (±1, ±1, ±1)/√3.
    Diagonals,
    /// Axes then diagonals (14).
    All,
}

/// Distance multiples of the view set: framed, 4×, 16×.
pub const VIEW_DISTANCE_FACTORS: [f32; 3] = [1.0, 4.0, 16.0];

/// The documented fixed view set: for each direction (axes in the order +X −X +Y −Y +Z
/// −Z, then diagonals with signs in binary order, x slowest), each distance factor of
/// [`VIEW_DISTANCE_FACTORS`].
pub fn view_set(dirs: ViewDirections) -> Vec<ViewSpec> {
    view_set_with(dirs, &VIEW_DISTANCE_FACTORS)
}

/// The named directions of `dirs`, in view-set order (`"+x"`, …, `"-x-y-z"`).
pub fn view_directions(dirs: ViewDirections) -> Vec<(String, Vec3)> {
    let mut list: Vec<(String, Vec3)> = Vec::new();
    let sign = |s: f32| if s > 0.0 { '+' } else { '-' };
    if matches!(dirs, ViewDirections::Axes | ViewDirections::All) {
        for (axis, v) in [("x", Vec3::X), ("y", Vec3::Y), ("z", Vec3::Z)] {
            for s in [1.0f32, -1.0] {
                list.push((format!("{}{axis}", sign(s)), v * s));
            }
        }
    }
    if matches!(dirs, ViewDirections::Diagonals | ViewDirections::All) {
        for sx in [1.0f32, -1.0] {
            for sy in [1.0f32, -1.0] {
                for sz in [1.0f32, -1.0] {
                    let name = format!("{}x{}y{}z", sign(sx), sign(sy), sign(sz));
                    list.push((name, Vec3::new(sx, sy, sz).normalize()));
                }
            }
        }
    }
    list
}

/// [`view_set`] with other distance factors (each direction, then each factor in order).
pub fn view_set_with(dirs: ViewDirections, factors: &[f32]) -> Vec<ViewSpec> {
    views_of(view_directions(dirs), factors)
}

/// Every `(direction, factor)` pair, directions slowest, named `"{dir}@{factor}x"`.
pub fn views_of(dirs: Vec<(String, Vec3)>, factors: &[f32]) -> Vec<ViewSpec> {
    let mut out = Vec::new();
    for (name, dir) in dirs {
        for &f in factors {
            out.push(ViewSpec {
                name: format!("{name}@{f}x"),
                dir,
                distance_factor: f,
            });
        }
    }
    out
}

/// The direction named like the view set's (`"+x"`, `"-y"`, `"+x-y+z"`; each axis at
/// most once, in x, y, z order), normalised; `None` for anything else.
pub fn parse_direction(name: &str) -> Option<Vec3> {
    let b = name.as_bytes();
    if b.is_empty() || !b.len().is_multiple_of(2) || b.len() > 6 {
        return None;
    }
    let mut v = Vec3::ZERO;
    let mut last: Option<usize> = None;
    for pair in b.chunks_exact(2) {
        let s = match pair[0] {
            b'+' => 1.0,
            b'-' => -1.0,
            _ => return None,
        };
        let axis = match pair[1] {
            b'x' => 0,
            b'y' => 1,
            b'z' => 2,
            _ => return None,
        };
        if last.is_some_and(|l| axis <= l) {
            return None;
        }
        last = Some(axis);
        v[axis] = s;
    }
    Some(v.normalize())
}

impl ViewSpec {
    /// The camera for this view of `bounds`.
    pub fn camera(&self, bounds: &Aabb, fov_y: f32, width: u32, height: u32) -> Camera {
        Camera::framed(bounds, self.dir, fov_y, width, height, self.distance_factor)
    }
}

/// Homogeneous helper: world point → view space.
pub fn to_view(view: &Mat4, p: Vec3) -> Vec3 {
    (*view * Vec4::new(p.x, p.y, p.z, 1.0)).truncate()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Camera {
        let b = Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
        Camera::framed(&b, Vec3::NEG_Z, 60f32.to_radians(), 64, 48, 1.0)
    }

    #[test]
    fn centre_ray_hits_target_and_t_is_depth() {
        let c = cam();
        let r = c.ray(32.0, 24.0);
        let d = (c.target - c.eye).length();
        let p = r.origin + r.dir * d;
        assert!((p - c.target).length() < 1e-4, "{p}");
    }

    #[test]
    fn pixel_roundtrip_and_clip_agree() {
        let c = cam();
        let v = c.view();
        for (px, py) in [(0.5, 0.5), (63.5, 10.25), (12.0, 47.0)] {
            let dv = c.view_dir_of_pixel(px, py) * 3.0;
            let (qx, qy) = c.view_to_pixel(dv).unwrap();
            assert!((qx - px).abs() < 1e-3 && (qy - py).abs() < 1e-3);
            // Clip-space agrees with the pixel mapping.
            let w = c.ray(px, py);
            let world = w.origin + w.dir * 3.0;
            let clip = c.view_projection() * world.extend(1.0);
            let ndc = clip.truncate() / clip.w;
            let sx = 0.5 * (ndc.x + 1.0) * 64.0;
            let sy = 0.5 * (1.0 - ndc.y) * 48.0;
            assert!(
                (sx - px).abs() < 1e-2 && (sy - py).abs() < 1e-2,
                "{sx} {sy}"
            );
            assert!((to_view(&v, world).z + 3.0).abs() < 1e-3);
        }
    }

    #[test]
    fn view_set_sizes_and_names() {
        assert_eq!(view_set(ViewDirections::All).len(), 42);
        assert_eq!(view_set(ViewDirections::Axes)[0].name, "+x@1x");
        assert_eq!(view_set(ViewDirections::Diagonals).len(), 24);
    }

    #[test]
    fn directions_parse_like_the_view_set_names() {
        for (name, dir) in view_directions(ViewDirections::All) {
            assert_eq!(parse_direction(&name), Some(dir), "{name}");
        }
        assert_eq!(
            parse_direction("+x-z"),
            Some(Vec3::new(1.0, 0.0, -1.0).normalize())
        );
        for bad in ["", "x", "+", "+y+x", "+x+x", "*x", "+w", "+x+y+z+x"] {
            assert_eq!(parse_direction(bad), None, "{bad}");
        }
        let v = view_set_with(ViewDirections::Axes, &[2.5]);
        assert_eq!(v.len(), 6);
        assert_eq!(v[5].name, "-z@2.5x");
    }

    #[test]
    fn framing_fits_sphere() {
        let b = Aabb {
            min: Vec3::ZERO,
            max: Vec3::ONE,
        };
        for spec in view_set(ViewDirections::All) {
            let c = spec.camera(&b, 45f32.to_radians(), 32, 32);
            assert!(c.safe_up().cross(c.target - c.eye).length() > 1e-3);
            assert!(c.near > 0.0 && c.far > c.near);
            let dist = (c.eye - c.target).length();
            assert!(c.near < dist - 0.87 && c.far > dist + 0.87);
        }
    }
}
