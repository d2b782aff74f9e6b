//! Lacewell et al. §5's preference for planes facing the expected view directions.
//!
//! "If a model will be viewed from a limited set of angles, visual quality is improved by
//! favoring billboards which have a high probability of facing the camera." A camera looking
//! along `e` sees a billboard of normal `n` with its area scaled by `|e·n|`, so the expected
//! on-screen area of a plane over the expected views is its projected area times the
//! *facing* `f(n) = E[|e·n|]`:
//!
//! - `Horizontal { up }`: every view direction perpendicular to `up`, all azimuths equally
//!   likely (a tree seen by a walker). `E|e·n| = (2/π)·√(1 − (n·up)²)`; the constant factor
//!   does not change which plane wins, so `f(n) = √(1 − (n·up)²)`: 1 for vertical planes,
//!   0 for horizontal ones.
//! - `Directions(d₁…d_k)`: those directions, equally likely: `f(n) = (1/k)·Σ|d_i·n|`.
//!
//! The search ranks candidates by `area · w(n)` with `w = (1 − s) + s·f(n)`, `s` the
//! strength in [0, 1] (1: rank by expected on-screen area; 0: no preference). Only the
//! choice among the N candidates changes: which elements a chosen plane takes is still its
//! ε-slab, and the reported area is the unweighted projected area. Arithmetic only (one
//! square root, correctly rounded in IEEE 754), so the result is portable.

use glam::Vec3;

/// The expected view directions.
#[derive(Clone, Debug, PartialEq)]
pub enum ViewDirs {
    /// All directions perpendicular to `up` (unit).
    Horizontal { up: Vec3 },
    /// These unit directions (their sign does not matter).
    Directions(Vec<Vec3>),
}

/// Most directions a [`ViewDirs::Directions`] preference may list.
pub const MAX_VIEW_DIRS: usize = 64;

/// A view preference: directions and strength `s` in [`super::UNIT_RANGE`] ([0, 1]).
#[derive(Clone, Debug, PartialEq)]
pub struct ViewPreference {
    pub dirs: ViewDirs,
    pub strength: f32,
}

impl ViewPreference {
    /// `f(n)` in [0, 1] for a unit normal.
    pub fn facing(&self, n: Vec3) -> f32 {
        match &self.dirs {
            ViewDirs::Horizontal { up } => {
                let c = n.dot(*up);
                (1.0 - c * c).max(0.0).sqrt()
            }
            ViewDirs::Directions(d) => {
                let s: f32 = d.iter().map(|e| e.dot(n).abs()).sum();
                (s / d.len().max(1) as f32).min(1.0)
            }
        }
    }

    /// The factor a candidate's projected area is multiplied by when ranking.
    pub fn weight(&self, n: Vec3) -> f32 {
        (1.0 - self.strength) + self.strength * self.facing(n)
    }

    /// Whether the parameters are usable (finite unit directions, strength in [0, 1]).
    pub fn is_valid(&self) -> bool {
        let unit = |v: &Vec3| v.is_finite() && (v.length() - 1.0).abs() < 1e-3;
        let dirs = match &self.dirs {
            ViewDirs::Horizontal { up } => unit(up),
            ViewDirs::Directions(d) => {
                !d.is_empty() && d.len() <= MAX_VIEW_DIRS && d.iter().all(unit)
            }
        };
        dirs && super::UNIT_RANGE.contains(&self.strength)
    }

    /// How the preference is recorded in the asset header.
    pub fn describe(&self) -> String {
        match &self.dirs {
            ViewDirs::Horizontal { up } => format!("horizontal(up {},{},{})", up.x, up.y, up.z),
            ViewDirs::Directions(d) => d
                .iter()
                .map(|v| format!("{},{},{}", v.x, v.y, v.z))
                .collect::<Vec<_>>()
                .join(";"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn horizontal_views_favour_vertical_planes() {
        let p = ViewPreference {
            dirs: ViewDirs::Horizontal { up: Vec3::Y },
            strength: 1.0,
        };
        assert_eq!(p.facing(Vec3::X), 1.0);
        assert_eq!(p.facing(Vec3::Y), 0.0);
        let tilted = Vec3::new(1.0, 1.0, 0.0).normalize();
        assert!((p.facing(tilted) - 0.5f32.sqrt()).abs() < 1e-6);
        let half = ViewPreference {
            strength: 0.5,
            ..p.clone()
        };
        assert_eq!(half.weight(Vec3::Y), 0.5);
    }

    #[test]
    fn listed_directions_average_the_cosines() {
        let p = ViewPreference {
            dirs: ViewDirs::Directions(vec![Vec3::Z, Vec3::X]),
            strength: 1.0,
        };
        assert_eq!(p.facing(Vec3::Z), 0.5);
        assert_eq!(p.facing(-Vec3::X), 0.5);
        assert_eq!(p.facing(Vec3::Y), 0.0);
        assert!(p.is_valid());
        assert!(!ViewPreference {
            dirs: ViewDirs::Directions(vec![]),
            strength: 1.0
        }
        .is_valid());
    }
}
