//! Animated cells (VB paper §4, "Composite and animated scene", Figure 13): volume
//! instances move without re-baking by deforming their prism cells over time.
//!
//! [`Sway`] bends a volume by height like wind: a vertex at height fraction
//! `h ∈ [0, 1]` of the asset's bounds moves horizontally by
//! `A·H·h²·(sin(2πft + φ) + 0.3·sin(2π·2.3ft + 1.7φ))` along the wind direction
//! (`A` = amplitude as a fraction of the height `H`, `φ` a per-instance phase), so
//! the base stays put and the top sways most. The offset depends on height only, so
//! cells that share a face keep sharing it. A volume made of the one box of `voxelize`
//! would only shear: animated boxes are first cut into `layers` stacked boxes along
//! +Y ([`layered_box`]), with their 3D texture coordinates carried over exactly
//! (the box's affine position → uvw map), which lets the volume bend.

use billow_format::Prism;
use glam::{Mat3, Vec3};
use serde::Deserialize;

#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Sway {
    /// Top displacement as a fraction of the asset's height.
    #[serde(default = "amp")]
    pub amplitude: f32,
    /// Hertz.
    #[serde(default = "freq")]
    pub frequency: f32,
    /// Wind direction in the ground plane (x, z).
    #[serde(default = "dir")]
    pub direction: [f32; 2],
    /// Boxes stacked along +Y when the asset is a single box.
    #[serde(default = "layers")]
    pub layers: u32,
}

fn amp() -> f32 {
    0.04
}
fn freq() -> f32 {
    0.4
}
fn dir() -> [f32; 2] {
    [1.0, 0.0]
}
fn layers() -> u32 {
    8
}

impl Sway {
    pub fn validate(&self) -> Result<(), String> {
        if !(self.amplitude.is_finite() && self.amplitude.abs() <= 1.0) {
            return Err(format!("amplitude: {} must be in [-1, 1]", self.amplitude));
        }
        if !(self.frequency >= 0.0 && self.frequency.is_finite()) {
            return Err(format!("frequency: {} must be >= 0", self.frequency));
        }
        if !self.direction.iter().all(|c| c.is_finite()) {
            return Err("direction: must be finite".into());
        }
        if !(1..=256).contains(&self.layers) {
            return Err(format!("layers: {} must be 1 to 256", self.layers));
        }
        Ok(())
    }

    /// The horizontal offset at height fraction `h`, time `t`, phase `phase`.
    pub fn offset(&self, height: f32, h: f32, t: f32, phase: f32) -> Vec3 {
        let d = glam::Vec2::from(self.direction).normalize_or(glam::Vec2::X);
        let w = std::f32::consts::TAU * self.frequency * t;
        let s = (w + phase).sin() + 0.3 * (2.3 * w + 1.7 * phase).sin();
        let k = self.amplitude * height * h.clamp(0.0, 1.0).powi(2) * s;
        Vec3::new(d.x * k, 0.0, d.y * k)
    }

    /// `cells` deformed at time `t` (`bounds` = the asset's, `phase` per instance).
    pub fn deform(&self, cells: &[Prism], bounds: (Vec3, Vec3), t: f32, phase: f32) -> Vec<Prism> {
        let (lo, hi) = bounds;
        let height = (hi.y - lo.y).max(1e-12);
        cells
            .iter()
            .map(|c| Prism {
                pos: c.pos.map(|p| {
                    let v = Vec3::from(p);
                    (v + self.offset(height, (v.y - lo.y) / height, t, phase)).to_array()
                }),
                uvw: c.uvw,
            })
            .collect()
    }
}

/// The affine map `uvw = A·pos + b` of a prism (its vertices 0, 1, 2 and 3 span space).
fn affine(c: &Prism) -> Option<(Mat3, Vec3)> {
    let p = |i: usize| Vec3::from(c.pos[i]) - Vec3::from(c.pos[0]);
    let t = |i: usize| Vec3::from(c.uvw[i]) - Vec3::from(c.uvw[0]);
    let pm = Mat3::from_cols(p(1), p(2), p(3));
    if pm.determinant().abs() < 1e-12 {
        return None;
    }
    let a = Mat3::from_cols(t(1), t(2), t(3)) * pm.inverse();
    Some((a, Vec3::from(c.uvw[0]) - a * Vec3::from(c.pos[0])))
}

/// When `cells` are one box (`voxelize`'s two prisms filling `bounds` with one affine
/// texture mapping), that box cut into `layers` boxes stacked along +Y, two prisms each;
/// otherwise `None` (pruned and shell assets keep their own cells).
pub fn layered_box(cells: &[Prism], bounds: (Vec3, Vec3), layers: u32) -> Option<Vec<Prism>> {
    if cells.len() != 2 || layers < 2 {
        return None;
    }
    let (lo, hi) = bounds;
    let inside = cells.iter().flat_map(|c| c.pos.iter()).all(|p| {
        let v = Vec3::from(*p);
        v.cmpge(lo - 1e-4 * (hi - lo)).all() && v.cmple(hi + 1e-4 * (hi - lo)).all()
    });
    let (a, b) = affine(&cells[0])?;
    let same_map = affine(&cells[1]).is_some_and(|(a2, b2)| {
        (a2 - a).to_cols_array().iter().all(|x| x.abs() < 1e-4)
            && (b2 - b).abs().max_element() < 1e-4
    });
    if !inside || !same_map {
        return None;
    }
    let uvw = |p: Vec3| (a * p + b).to_array();
    let mut out = Vec::with_capacity(2 * layers as usize);
    for j in 0..layers {
        let y0 = lo.y + (hi.y - lo.y) * j as f32 / layers as f32;
        let y1 = if j + 1 == layers {
            hi.y
        } else {
            lo.y + (hi.y - lo.y) * (j + 1) as f32 / layers as f32
        };
        let q = |x: f32, z: f32| [Vec3::new(x, y0, z), Vec3::new(x, y1, z)];
        let corners = [
            [q(lo.x, lo.z), q(hi.x, lo.z), q(hi.x, hi.z)],
            [q(lo.x, lo.z), q(hi.x, hi.z), q(lo.x, hi.z)],
        ];
        for tri in corners {
            let pos: [Vec3; 6] = std::array::from_fn(|i| tri[i % 3][usize::from(i >= 3)]);
            out.push(Prism {
                pos: pos.map(|p| p.to_array()),
                uvw: pos.map(uvw),
            });
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box() -> Vec<Prism> {
        // Two prisms filling [0,1]³ (vertical edges along z), uvw = position.
        let c = |x: f32, y: f32| [x, y];
        let tris = [
            [c(0.0, 0.0), c(1.0, 0.0), c(1.0, 1.0)],
            [c(0.0, 0.0), c(1.0, 1.0), c(0.0, 1.0)],
        ];
        tris.iter()
            .map(|t| {
                let pos: [[f32; 3]; 6] = std::array::from_fn(|i| {
                    let v = t[i % 3];
                    [v[0], v[1], if i < 3 { 0.0 } else { 1.0 }]
                });
                Prism { pos, uvw: pos }
            })
            .collect()
    }

    #[test]
    fn layers_keep_the_texture_mapping_and_the_base_stays() {
        let b = (Vec3::ZERO, Vec3::ONE);
        let l = layered_box(&unit_box(), b, 4).expect("a box");
        assert_eq!(l.len(), 8);
        for c in &l {
            for i in 0..6 {
                let (p, t) = (Vec3::from(c.pos[i]), Vec3::from(c.uvw[i]));
                assert!((p - t).abs().max_element() < 1e-5, "uvw = position");
            }
        }
        let s = Sway {
            amplitude: 0.1,
            frequency: 1.0,
            direction: [1.0, 0.0],
            layers: 4,
        };
        let d = s.deform(&l, b, 0.3, 0.0);
        for (c0, c1) in l.iter().zip(&d) {
            for i in 0..6 {
                let (p0, p1) = (Vec3::from(c0.pos[i]), Vec3::from(c1.pos[i]));
                assert_eq!(p0.y, p1.y);
                if p0.y == 0.0 {
                    assert_eq!(p0, p1, "the base does not move");
                }
                if p0.y == 1.0 {
                    assert!(
                        (p1.x - p0.x).abs() > 0.01 && p1.z == p0.z,
                        "the top sways in x"
                    );
                }
                assert_eq!(
                    c0.uvw[i], c1.uvw[i],
                    "texture coordinates travel with the cell"
                );
            }
        }
        // Not a box (three prisms): no layering.
        let mut three = unit_box();
        three.push(three[0]);
        assert!(layered_box(&three, b, 4).is_none());
    }
}
