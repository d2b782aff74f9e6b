//! `billow view CLOUD --lod-sweep DIR`: what a viewer sees across every LOD switch of a
//! billboard cloud (Lacewell et al. 2006, §1 and §4: the two sides of a transition should
//! be "nearly indistinguishable"). docs/bbcloud.md, "LOD switches".
//!
//! Around each switch distance `D` the camera takes [`FRAMES`] frames at
//! `z_j = D·2^((j + ½)/STEPS_PER_OCTAVE)`, `j = −FRAMES/2 … FRAMES/2 − 1`, so exactly one
//! step crosses `D`, dollying along a fixed direction while the field of view shrinks so
//! the cloud keeps its screen size (a dolly zoom). Which size: by default the one the
//! viewer shows at `D` with the scene's field of view (`tan(fov_z/2) = tan(fov/2)·D/z`), i.e.
//! each switch is judged at the size it happens at on screen; with a fill fraction F the
//! cloud's bounding sphere spans F of the frame height at every switch
//! (`tan(fov_z/2) = R/(F·z)`, a harsher test for the coarse levels, which the viewer only
//! shows small). The error of each step is the RMSE and FLIP between consecutive frames
//! (premultiplied linear RGBA, [`billow::eval::metrics`]). A switch passes when its step is
//! at most [`STEP_RATIO_LIMIT`] times the median of the other steps around it (the steps
//! a dolly makes anyway: parallax, MIP changes, morphing).
//!
//! Coverage: at each billboard level's own switch distance (where it first replaces the
//! level before it), the frame is rendered once showing that level and once showing the
//! foliage mesh (level 0), and the opaque pixels (alpha ≥ 254.5/255) and total alpha of
//! both are compared.

use std::path::Path;

use billow::eval::{metrics, ImageF32};
use billow_view::target::Target;
use billow_view::{Renderer, ViewCamera};
use glam::{Vec3, Vec4};
use serde::Serialize;

use crate::exit::{CliError, Code};

/// Frames per switch (one step crosses the switch, the others are its neighbours).
pub const FRAMES: i32 = 8;
/// Dolly steps per doubling of the distance.
pub const STEPS_PER_OCTAVE: f32 = 8.0;
/// A switch passes when its step is at most this many times its neighbours' median.
pub const STEP_RATIO_LIMIT: f64 = 1.5;
/// A level's opaque-pixel count passes within this fraction of the mesh's.
pub const OPAQUE_TOLERANCE: f64 = 0.10;
/// Alpha at or above this counts as an opaque pixel.
pub const OPAQUE_ALPHA: f32 = 254.5 / 255.0;

#[derive(Clone, Debug, Serialize)]
pub struct Step {
    /// Camera distances of the two frames.
    pub z: [f32; 2],
    /// (level, morph) the viewer chose in each frame.
    pub lods: [(usize, f32); 2],
    /// How far each frame had dissolved into the next level (0: one level shown).
    pub dissolve: [f32; 2],
    pub rmse: f64,
    pub flip: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct Switch {
    /// The level shown before and after.
    pub from: usize,
    pub to: usize,
    pub distance: f32,
    pub steps: Vec<Step>,
    /// Index in `steps` of the step that crosses the switch.
    pub crossing: usize,
    pub step_rmse: f64,
    pub step_flip: f64,
    /// Median RMSE of the other steps.
    pub neighbours_rmse: f64,
    /// Opaque pixels of the frames just before and just after the switch.
    pub opaque_pixels: [u64; 2],
    pub ratio: f64,
    pub pass: bool,
}

#[derive(Clone, Debug, Serialize)]
pub struct LevelCoverage {
    pub level: usize,
    /// Where it replaces the level before it.
    pub distance: f32,
    pub opaque_pixels: u64,
    pub mesh_opaque_pixels: u64,
    /// (level − mesh) / mesh.
    pub opaque_rel: f64,
    pub alpha_sum: f64,
    pub mesh_alpha_sum: f64,
    pub alpha_rel: f64,
    pub pass: bool,
}

#[derive(Clone, Debug, Serialize)]
pub struct Sweep {
    pub width: u32,
    pub height: u32,
    pub view_dir: [f32; 3],
    /// Vertical field of view at each switch distance, degrees.
    pub fov_deg: f32,
    /// Constant fill fraction, or `None`: each switch at its on-screen size.
    pub fill: Option<f32>,
    pub switches: Vec<Switch>,
    pub levels: Vec<LevelCoverage>,
    pub pass: bool,
}

fn internal(e: impl std::fmt::Display) -> CliError {
    CliError::new(Code::Internal, e)
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn rel(a: f64, b: f64) -> f64 {
    if b > 0.0 {
        (a - b) / b
    } else if a > 0.0 {
        f64::INFINITY
    } else {
        0.0
    }
}

struct Dolly<'a> {
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

impl Dolly<'_> {
    /// The frame at distance `z` with the cloud as large as at the switch `d`; `lod`: force
    /// the LOD choice as if the cloud were this far away.
    fn frame(
        &mut self,
        z: f32,
        d: f32,
        lod: Option<f32>,
    ) -> Result<(ImageF32, (usize, f32), f32), CliError> {
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
        // The mesh's coverage frames (level 0 forced) sample its textures at level 0: its
        // MIP chain draws its alpha-tested leaves 10 % thin here (`mesh_texture_level0`).
        self.r.mesh_texture_level0 = lod == Some(0.0);
        // A forced level is shown alone (coverage frames), not dissolving.
        self.r.dissolve_override = lod.map(|_| 0.0);
        let stats = self.r.render(&self.target, &cam).map_err(internal)?;
        let img = self.target.read(&self.r.gpu).map_err(internal)?;
        let lods = stats.cloud_lods.first().copied().unwrap_or((0, 0.0));
        let dissolve = stats.cloud_dissolves.first().copied().unwrap_or(0.0);
        Ok((
            ImageF32 {
                width: img.width,
                height: img.height,
                data: img.data.iter().map(|p| Vec4::from_array(*p)).collect(),
            },
            lods,
            dissolve,
        ))
    }
}

fn opaque(img: &ImageF32) -> (u64, f64) {
    let n = img.data.iter().filter(|p| p.w >= OPAQUE_ALPHA).count() as u64;
    let a = img
        .data
        .iter()
        .map(|p| f64::from(p.w.clamp(0.0, 1.0)))
        .sum();
    (n, a)
}

/// Runs the sweep on the renderer's one cloud instance; writes `switch_K.png` (the frames
/// on either side of switch K and their difference ×4) into `dir` when given.
pub fn sweep(
    r: &mut Renderer,
    (width, height): (u32, u32),
    (view_dir, fov_y, fill): (Vec3, f32, Option<f32>),
    dir: Option<&Path>,
) -> Result<Sweep, CliError> {
    let setup = r.cloud_lod_setup();
    let [(centre, radius, distances, _)] = setup.as_slice() else {
        return Err(CliError::new(
            Code::BadParameter,
            format!(
                "--lod-sweep: needs a scene with exactly one billboard cloud, this one has {}",
                setup.len()
            ),
        ));
    };
    let (centre, radius, distances) = (*centre, radius.max(1e-6), distances.clone());
    if distances.is_empty() {
        return Err(CliError::new(
            Code::BadParameter,
            "--lod-sweep: the cloud has a single level, so there is no switch to sweep",
        ));
    }
    let target = Target::new(&r.gpu, width, height);
    let mut d = Dolly {
        r,
        target,
        centre,
        radius,
        dir: view_dir.normalize(),
        tan_half: (0.5 * fov_y).tan(),
        fill,
    };
    let mut switches = Vec::new();
    for (k, &dist) in distances.iter().enumerate() {
        let zs: Vec<f32> = (-FRAMES / 2..FRAMES / 2)
            .map(|j| dist * 2f32.powf((j as f32 + 0.5) / STEPS_PER_OCTAVE))
            .collect();
        let mut frames = Vec::with_capacity(zs.len());
        for &z in &zs {
            frames.push(d.frame(z, dist, None)?);
        }
        let crossing = (FRAMES / 2 - 1) as usize;
        let mut steps = Vec::new();
        for i in 0..frames.len() - 1 {
            let (a, la, da) = &frames[i];
            let (b, lb, db) = &frames[i + 1];
            let e = metrics::compare(a, b).map_err(internal)?;
            steps.push(Step {
                z: [zs[i], zs[i + 1]],
                lods: [*la, *lb],
                dissolve: [*da, *db],
                rmse: e.rmse,
                flip: e.flip,
            });
        }
        if let Some(dir) = dir {
            let (a, b) = (&frames[crossing].0, &frames[crossing + 1].0);
            billow::eval::image::write_comparison_png(
                a,
                b,
                4.0,
                &dir.join(format!("switch_{k}.png")),
            )
            .map_err(|e| CliError::new(Code::OutputIo, e))?;
        }
        let neighbours = median(
            steps
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != crossing)
                .map(|(_, s)| s.rmse)
                .collect(),
        );
        let s = &steps[crossing];
        let ratio = if neighbours > 0.0 {
            s.rmse / neighbours
        } else if s.rmse > 0.0 {
            f64::INFINITY
        } else {
            1.0
        };
        switches.push(Switch {
            // Switch k replaces level k by k + 1 (while dissolving, both frames of the
            // crossing step report the outgoing level k).
            from: k,
            to: k + 1,
            distance: dist,
            crossing,
            step_rmse: s.rmse,
            step_flip: s.flip,
            neighbours_rmse: neighbours,
            opaque_pixels: [
                opaque(&frames[crossing].0).0,
                opaque(&frames[crossing + 1].0).0,
            ],
            ratio,
            pass: ratio <= STEP_RATIO_LIMIT,
            steps,
        });
    }
    let mut levels = Vec::new();
    for (k, &dist) in distances.iter().enumerate() {
        let (mesh, _, _) = d.frame(dist, dist, Some(0.0))?;
        let (lvl, lods, _) = d.frame(dist, dist, Some(dist))?;
        let (mo, ma) = opaque(&mesh);
        let (lo, la) = opaque(&lvl);
        let opaque_rel = rel(lo as f64, mo as f64);
        levels.push(LevelCoverage {
            level: lods.0.max(k + 1),
            distance: dist,
            opaque_pixels: lo,
            mesh_opaque_pixels: mo,
            opaque_rel,
            alpha_sum: la,
            mesh_alpha_sum: ma,
            alpha_rel: rel(la, ma),
            pass: opaque_rel.abs() <= OPAQUE_TOLERANCE,
        });
    }
    d.r.lod_distance_override = None;
    d.r.dissolve_override = None;
    let pass = switches.iter().all(|s| s.pass) && levels.iter().all(|l| l.pass);
    Ok(Sweep {
        width,
        height,
        view_dir: view_dir.normalize().to_array(),
        fov_deg: fov_y.to_degrees(),
        fill,
        switches,
        levels,
        pass,
    })
}

/// The sweep as Markdown tables (docs/bbcloud.md).
pub fn table(s: &Sweep) -> String {
    let mut out = String::new();
    out.push_str(
        "| switch | distance | step at the switch (RMSE) | FLIP | median of its neighbours | ratio | opaque pixels before → after |\n\
         |---|---|---|---|---|---|---|\n",
    );
    for w in &s.switches {
        let name = |l: usize| {
            if l == 0 {
                "mesh".to_string()
            } else {
                format!("level {l}")
            }
        };
        out.push_str(&format!(
            "| {} → {} | {:.4} | {:.4} | {:.4} | {:.4} | {:.2}× {} | {} → {} |\n",
            name(w.from),
            name(w.to),
            w.distance,
            w.step_rmse,
            w.step_flip,
            w.neighbours_rmse,
            w.ratio,
            if w.pass { "" } else { "(over 1.5×)" },
            w.opaque_pixels[0],
            w.opaque_pixels[1]
        ));
    }
    out.push_str(
        "\n| level | at distance | opaque pixels | mesh's | difference | total alpha vs mesh |\n\
         |---|---|---|---|---|---|\n",
    );
    for l in &s.levels {
        out.push_str(&format!(
            "| {} | {:.4} | {} | {} | {:+.1} % | {:+.1} % |\n",
            l.level,
            l.distance,
            l.opaque_pixels,
            l.mesh_opaque_pixels,
            100.0 * l.opaque_rel,
            100.0 * l.alpha_rel
        ));
    }
    out
}
