//! Particle systems drawn as spherical billboards (Umenhoffer, Szirmay-Kalos & Szíjártó,
//! *Spherical billboards for rendering volumetric data*, ShaderX5): dust, smoke and fire
//! of a procedural explosion.
//!
//! # The explosion animation (deterministic in `seed` and time `t`)
//! Particle `i` of an emitter draws, from a SplitMix64 stream of `seed`: a direction
//! `dᵢ` (uniform on the sphere, plus an upward bias per kind: fire 0.3, smoke 0.8, dust
//! 0.1, renormalised), a travel `sᵢ ∈ [0.3, 1]·spread`, a lifetime `Lᵢ` in the
//! emitter's range, a start `t₀ᵢ = start + U(0, 0.1)·Lᵢ`, a radius `rᵢ` in the radius
//! range and a detail-noise offset. At age `a = t − t₀ᵢ ∈ [0, Lᵢ]`, `u = a / Lᵢ`:
//! - expansion `e(u) = 1 − (1 − u)³` (fast, then slowing): position
//!   `emitter + dᵢ·sᵢ·e(u) + (0, rise·u², 0)` (the cloud rises),
//!   radius `rᵢ·(0.35 + 0.65·e(u))` (particles expand);
//! - fade: density `τ·(1 − u)²` (dust, smoke), `τ·(1 − u)^1.5` (fire);
//! - fire cools: temperature bias `T₀·(1 − 0.55u)` and scale `T₁·(1 − 0.4u)`.
//!
//! Outside `[0, Lᵢ]` a particle does not exist. Per-kind defaults are the paper's:
//! dust `τ = 0.4`, albedo 0.9; smoke `τ = 0.4`, albedo 0.2; `g = 0` (the paper found 0
//! sufficient); fire is emission only (albedo 0), `T₀ = 1200 K`, `T₁ = 1600 K`.

#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod blackbody;
pub mod cie1931;
pub mod noise;
pub mod opacity;
pub mod phase;

use glam::Vec3;
use serde::Deserialize;

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
pub enum ParticleKind {
    Dust,
    Smoke,
    Fire,
}

/// How particles are drawn.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
pub enum BillboardMode {
    /// The exact perspective path through the sphere, clipped by the near plane and the
    /// scene (the paper's method, without its parallel-ray approximation).
    #[default]
    Spherical,
    /// Classic flat billboards at the particle centre: the artefacts the paper fixes.
    Planar,
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct EmitterDesc {
    pub position: [f32; 3],
    pub count: u32,
    /// Particle radius range (world units), before expansion.
    pub radius: (f32, f32),
    /// Lifetime range, seconds.
    pub lifetime: (f32, f32),
    #[serde(default)]
    pub seed: u64,
    /// How far particles travel (world units).
    #[serde(default = "ten")]
    pub spread: f32,
    /// How far the cloud rises over a lifetime (world units).
    #[serde(default)]
    pub rise: f32,
    /// Time of the explosion (seconds).
    #[serde(default)]
    pub start: f32,
}

fn ten() -> f32 {
    10.0
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ParticleSystemDesc {
    pub kind: ParticleKind,
    pub emitter: EmitterDesc,
    /// Density τ per world unit (default per kind).
    #[serde(default)]
    pub density: Option<f32>,
    /// Albedo of dust and smoke (default per kind; fire: 0).
    #[serde(default)]
    pub albedo: Option<f32>,
    /// Phase asymmetry g ∈ (−1, 1) of dust and smoke (default 0).
    #[serde(default)]
    pub g: Option<f32>,
    /// Fire: temperature bias T₀ and scale T₁ (K): T = T₀ + T₁·noise.
    #[serde(default)]
    pub t0: Option<f32>,
    #[serde(default)]
    pub t1: Option<f32>,
    /// Fire: emitted luminance at 2000 K (the black-body table's unit).
    #[serde(default = "one")]
    pub emission: f32,
    /// Strength of the animated detail noise (opacity of dust/smoke, temperature of
    /// fire), 0 = smooth particles.
    #[serde(default = "half")]
    pub detail: f32,
    #[serde(default)]
    pub mode: BillboardMode,
}

fn one() -> f32 {
    1.0
}
fn half() -> f32 {
    0.5
}

impl ParticleSystemDesc {
    pub fn density(&self) -> f32 {
        self.density.unwrap_or(match self.kind {
            ParticleKind::Fire => 0.6,
            _ => 0.4,
        })
    }
    pub fn albedo(&self) -> f32 {
        match self.kind {
            ParticleKind::Fire => 0.0,
            ParticleKind::Dust => self.albedo.unwrap_or(0.9),
            ParticleKind::Smoke => self.albedo.unwrap_or(0.2),
        }
    }
    pub fn g(&self) -> f32 {
        self.g.unwrap_or(0.0)
    }
    pub fn t0(&self) -> f32 {
        self.t0.unwrap_or(1200.0)
    }
    pub fn t1(&self) -> f32 {
        self.t1.unwrap_or(1600.0)
    }

    /// `Err(field: problem)` when a parameter is out of range.
    pub fn validate(&self) -> Result<(), String> {
        let e = &self.emitter;
        let pos = |x: f32| x > 0.0 && x.is_finite();
        if !e.position.iter().all(|c| c.is_finite()) {
            return Err("emitter.position: must be finite".into());
        }
        if e.count == 0 || e.count > 100_000 {
            return Err(format!("emitter.count: {} must be 1 to 100000", e.count));
        }
        if !(pos(e.radius.0) && e.radius.0 <= e.radius.1 && e.radius.1.is_finite()) {
            return Err(format!(
                "emitter.radius: {:?} must be 0 < min <= max",
                e.radius
            ));
        }
        if !(pos(e.lifetime.0) && e.lifetime.0 <= e.lifetime.1 && e.lifetime.1.is_finite()) {
            return Err(format!(
                "emitter.lifetime: {:?} must be 0 < min <= max",
                e.lifetime
            ));
        }
        if !(e.spread >= 0.0 && e.spread.is_finite() && e.rise.is_finite() && e.start.is_finite()) {
            return Err("emitter: spread must be >= 0, rise and start finite".into());
        }
        if !(self.density() >= 0.0 && self.density().is_finite()) {
            return Err(format!("density: {} must be >= 0", self.density()));
        }
        if !(0.0..=1.0).contains(&self.albedo()) {
            return Err(format!("albedo: {} must be in [0, 1]", self.albedo()));
        }
        if !(self.g() > -1.0 && self.g() < 1.0) {
            return Err(format!("g: {} must be in (-1, 1)", self.g()));
        }
        if !(self.t0() >= 0.0 && self.t1() >= 0.0 && self.t0().is_finite() && self.t1().is_finite())
        {
            return Err("t0, t1: temperatures must be >= 0".into());
        }
        if !(self.emission >= 0.0 && self.emission.is_finite()) {
            return Err(format!("emission: {} must be >= 0", self.emission));
        }
        if !(0.0..=1.0).contains(&self.detail) {
            return Err(format!("detail: {} must be in [0, 1]", self.detail));
        }
        Ok(())
    }
}

/// One live particle at a given time (world space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Particle {
    pub centre: Vec3,
    pub radius: f32,
    /// Density τ after the fade.
    pub density: f32,
    /// Fire: temperature bias and scale after cooling.
    pub t0: f32,
    pub t1: f32,
    /// Offset into the detail noise (its own patch).
    pub detail_offset: Vec3,
}

/// SplitMix64: a tiny portable generator for the animation's random draws.
struct Mix(u64);

impl Mix {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next()
    }
}

/// The live particles of `s` at time `t` (module docs), in emission order.
pub fn particles_at(s: &ParticleSystemDesc, t: f32) -> Vec<Particle> {
    let e = &s.emitter;
    let mut rng = Mix(e.seed ^ 0x5eed_0000_0000_0000);
    let up = match s.kind {
        ParticleKind::Fire => 0.3,
        ParticleKind::Smoke => 0.8,
        ParticleKind::Dust => 0.1,
    };
    let mut out = Vec::new();
    for _ in 0..e.count {
        // Every particle draws the same number of values, alive or not.
        let z = rng.range(-1.0, 1.0);
        let phi = rng.range(0.0, std::f32::consts::TAU);
        let rxy = (1.0 - z * z).max(0.0).sqrt();
        let dir = (Vec3::new(rxy * phi.cos(), z, rxy * phi.sin()) + Vec3::new(0.0, up, 0.0))
            .normalize_or(Vec3::Y);
        let travel = rng.range(0.3, 1.0) * e.spread;
        let life = rng.range(e.lifetime.0, e.lifetime.1);
        let start = e.start + rng.range(0.0, 0.1) * life;
        let r = rng.range(e.radius.0, e.radius.1);
        let off = Vec3::new(rng.next(), rng.next(), rng.next()) * 8.0;
        let age = t - start;
        if !(age >= 0.0 && age <= life) {
            continue;
        }
        let u = age / life;
        let grow = 1.0 - (1.0 - u).powi(3);
        let fade = match s.kind {
            ParticleKind::Fire => (1.0 - u).powf(1.5),
            _ => (1.0 - u) * (1.0 - u),
        };
        out.push(Particle {
            centre: Vec3::from(e.position) + dir * travel * grow + Vec3::Y * (e.rise * u * u),
            radius: r * (0.35 + 0.65 * grow),
            density: s.density() * fade,
            t0: s.t0() * (1.0 - 0.55 * u),
            t1: s.t1() * (1.0 - 0.4 * u),
            detail_offset: off,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fire() -> ParticleSystemDesc {
        ParticleSystemDesc {
            kind: ParticleKind::Fire,
            emitter: EmitterDesc {
                position: [0.0, 1.0, 0.0],
                count: 115,
                radius: (0.5, 1.5),
                lifetime: (1.5, 3.0),
                seed: 7,
                spread: 6.0,
                rise: 4.0,
                start: 0.0,
            },
            density: None,
            albedo: None,
            g: None,
            t0: None,
            t1: None,
            emission: 1.0,
            detail: 0.5,
            mode: BillboardMode::Spherical,
        }
    }

    #[test]
    fn the_explosion_expands_rises_fades_and_cools() {
        let s = fire();
        s.validate().unwrap();
        assert!(
            particles_at(&s, -0.1).is_empty(),
            "nothing before the start"
        );
        let early = particles_at(&s, 0.3);
        let late = particles_at(&s, 1.4);
        assert!(!early.is_empty() && !late.is_empty());
        assert!(
            particles_at(&s, 3.5).is_empty(),
            "all gone after the longest life"
        );
        let mean = |v: &[Particle], f: &dyn Fn(&Particle) -> f32| {
            v.iter().map(f).sum::<f32>() / v.len() as f32
        };
        let c = Vec3::from(s.emitter.position);
        assert!(
            mean(&late, &|p| (p.centre - c).length()) > mean(&early, &|p| (p.centre - c).length())
        );
        assert!(mean(&late, &|p| p.radius) > mean(&early, &|p| p.radius));
        assert!(mean(&late, &|p| p.centre.y) > mean(&early, &|p| p.centre.y));
        assert!(mean(&late, &|p| p.density) < mean(&early, &|p| p.density));
        assert!(mean(&late, &|p| p.t0) < mean(&early, &|p| p.t0));
        // Deterministic.
        assert_eq!(particles_at(&s, 1.0), particles_at(&s, 1.0));
    }

    #[test]
    fn bad_parameters_name_the_field() {
        let mut s = fire();
        s.g = Some(1.0);
        assert!(s.validate().unwrap_err().starts_with("g:"));
        let mut s = fire();
        s.emitter.radius = (2.0, 1.0);
        assert!(s.validate().unwrap_err().starts_with("emitter.radius"));
    }
}
