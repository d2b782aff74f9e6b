//! The LOD-switch sweep of a billboard cloud and its verdict (Lacewell et al. 2006, §1 and
//! §4: the two sides of a transition should be "nearly indistinguishable"): which frames
//! are taken around each switch, what is measured between them, and when a switch or a
//! level passes. docs/bbcloud.md, "LOD switches"; `billow view CLOUD --lod-sweep DIR`
//! renders the frames with the GPU viewer (`billow_view::dolly`), this module judges them.
//!
//! Around each switch distance `D` the camera takes [`FRAMES`] frames at
//! `z_j = D·2^((j + ½)/STEPS_PER_OCTAVE)`, `j = −FRAMES/2 … FRAMES/2 − 1`
//! ([`frame_distances`]), so exactly one step ([`CROSSING`]) crosses `D`, dollying along a
//! fixed direction while the field of view shrinks so the cloud keeps its screen size (a
//! dolly zoom). The error of each step is the RMSE and FLIP between consecutive frames
//! (premultiplied linear RGBA, [`crate::eval::metrics`]). A switch passes when its step is
//! at most [`STEP_RATIO_LIMIT`] times the median of the other steps around it (the steps a
//! dolly makes anyway: parallax, MIP changes, morphing).
//!
//! Coverage: at each billboard level's own switch distance (where it first replaces the
//! level before it), the frame is rendered once showing that level and once showing the
//! foliage mesh (level 0), and the opaque pixels (alpha ≥ [`OPAQUE_ALPHA`]) and total alpha
//! of both are compared; a level passes within [`OPAQUE_TOLERANCE`] of the mesh's opaque
//! pixels.
//!
//! The renderer is the caller's: [`sweep`] asks for each frame through a closure, so this
//! library does not depend on the viewer.

use serde::Serialize;

use crate::eval::{metrics, EvalError, ImageF32};

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
/// Index, among a switch's steps, of the step that crosses the switch.
pub const CROSSING: usize = (FRAMES / 2 - 1) as usize;

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

/// A whole sweep: how it was taken, each switch and level, and the verdict.
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
    /// Every switch and every level passed.
    pub pass: bool,
}

/// One frame of the sweep, as the renderer showed it.
pub struct Frame {
    pub image: ImageF32,
    /// (level, morph) the renderer chose.
    pub lod: (usize, f32),
    /// How far the frame had dissolved into the next level (0: one level shown).
    pub dissolve: f32,
}

/// Why a sweep stopped: the renderer's error, a metric's, or nothing to sweep.
#[derive(Debug)]
pub enum SweepError<E> {
    /// The cloud has a single level: no switch.
    NoSwitch,
    /// Rendering (or writing) a frame failed.
    Frame(E),
    /// Comparing two frames failed.
    Metrics(EvalError),
}

impl<E: std::fmt::Display> std::fmt::Display for SweepError<E> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SweepError::NoSwitch => {
                write!(
                    f,
                    "the cloud has a single level, so there is no switch to sweep"
                )
            }
            SweepError::Frame(e) => e.fmt(f),
            SweepError::Metrics(e) => e.fmt(f),
        }
    }
}

impl<E: std::fmt::Debug + std::fmt::Display> std::error::Error for SweepError<E> {}

/// The median of `v` (0 when empty).
pub fn median(mut v: Vec<f64>) -> f64 {
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

/// `(a − b) / b`; infinite when only `b` is 0, 0 when both are.
pub fn rel(a: f64, b: f64) -> f64 {
    if b > 0.0 {
        (a - b) / b
    } else if a > 0.0 {
        f64::INFINITY
    } else {
        0.0
    }
}

/// The opaque pixels of `img` (alpha ≥ [`OPAQUE_ALPHA`]) and its total alpha.
pub fn opaque(img: &ImageF32) -> (u64, f64) {
    let n = img.data.iter().filter(|p| p.w >= OPAQUE_ALPHA).count() as u64;
    let a = img
        .data
        .iter()
        .map(|p| f64::from(p.w.clamp(0.0, 1.0)))
        .sum();
    (n, a)
}

/// The camera distances of the [`FRAMES`] frames around the switch at `dist`.
pub fn frame_distances(dist: f32) -> Vec<f32> {
    (-FRAMES / 2..FRAMES / 2)
        .map(|j| dist * 2f32.powf((j as f32 + 0.5) / STEPS_PER_OCTAVE))
        .collect()
}

/// Switch `k` (level `k` replaced by `k + 1` at `dist`) from its frames, taken at `zs`
/// ([`frame_distances`]): every step measured, the crossing judged against its neighbours.
pub fn judge_switch(
    k: usize,
    dist: f32,
    zs: &[f32],
    frames: &[Frame],
) -> Result<Switch, EvalError> {
    let mut steps = Vec::new();
    for (i, pair) in frames.windows(2).enumerate() {
        let (a, b) = (&pair[0], &pair[1]);
        let e = metrics::compare(&a.image, &b.image)?;
        steps.push(Step {
            z: [zs[i], zs[i + 1]],
            lods: [a.lod, b.lod],
            dissolve: [a.dissolve, b.dissolve],
            rmse: e.rmse,
            flip: e.flip,
        });
    }
    let crossing = CROSSING;
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
    Ok(Switch {
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
            opaque(&frames[crossing].image).0,
            opaque(&frames[crossing + 1].image).0,
        ],
        ratio,
        pass: ratio <= STEP_RATIO_LIMIT,
        steps,
    })
}

/// Level `k + 1`'s coverage at its switch distance `dist`: the frame forced to show it
/// against the frame forced to show the mesh.
pub fn judge_level(k: usize, dist: f32, mesh: &Frame, level: &Frame) -> LevelCoverage {
    let (mo, ma) = opaque(&mesh.image);
    let (lo, la) = opaque(&level.image);
    let opaque_rel = rel(lo as f64, mo as f64);
    LevelCoverage {
        level: level.lod.0.max(k + 1),
        distance: dist,
        opaque_pixels: lo,
        mesh_opaque_pixels: mo,
        opaque_rel,
        alpha_sum: la,
        mesh_alpha_sum: ma,
        alpha_rel: rel(la, ma),
        pass: opaque_rel.abs() <= OPAQUE_TOLERANCE,
    }
}

/// Sweeps the switches at `distances` (the cloud's level-change distances). `frame(z, d,
/// lod)` renders the cloud from distance `z` at its screen size of the switch at `d`, the
/// level chosen as if the cloud were `lod` away when given (shown alone, not dissolving);
/// `crossing(k, before, after)` is given the two frames on either side of switch `k`.
/// Returns the switches and the levels' coverage, in order.
pub fn sweep<E>(
    distances: &[f32],
    mut frame: impl FnMut(f32, f32, Option<f32>) -> Result<Frame, E>,
    mut crossing: impl FnMut(usize, &ImageF32, &ImageF32) -> Result<(), E>,
) -> Result<(Vec<Switch>, Vec<LevelCoverage>), SweepError<E>> {
    if distances.is_empty() {
        return Err(SweepError::NoSwitch);
    }
    let mut switches = Vec::new();
    for (k, &dist) in distances.iter().enumerate() {
        let zs = frame_distances(dist);
        let mut frames = Vec::with_capacity(zs.len());
        for &z in &zs {
            frames.push(frame(z, dist, None).map_err(SweepError::Frame)?);
        }
        let switch = judge_switch(k, dist, &zs, &frames).map_err(SweepError::Metrics)?;
        crossing(k, &frames[CROSSING].image, &frames[CROSSING + 1].image)
            .map_err(SweepError::Frame)?;
        switches.push(switch);
    }
    let mut levels = Vec::new();
    for (k, &dist) in distances.iter().enumerate() {
        let mesh = frame(dist, dist, Some(0.0)).map_err(SweepError::Frame)?;
        let level = frame(dist, dist, Some(dist)).map_err(SweepError::Frame)?;
        levels.push(judge_level(k, dist, &mesh, &level));
    }
    Ok((switches, levels))
}

impl Sweep {
    /// The sweep's record and verdict: it passes when every switch and level does.
    pub fn new(
        (width, height): (u32, u32),
        (view_dir, fov_deg, fill): ([f32; 3], f32, Option<f32>),
        switches: Vec<Switch>,
        levels: Vec<LevelCoverage>,
    ) -> Sweep {
        let pass = switches.iter().all(|s| s.pass) && levels.iter().all(|l| l.pass);
        Sweep {
            width,
            height,
            view_dir,
            fov_deg,
            fill,
            switches,
            levels,
            pass,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_and_rel() {
        assert_eq!(median(vec![]), 0.0);
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
        assert_eq!(rel(11.0, 10.0), 0.1);
        assert_eq!(rel(1.0, 0.0), f64::INFINITY);
        assert_eq!(rel(0.0, 0.0), 0.0);
    }

    #[test]
    fn one_step_crosses_the_switch() {
        let zs = frame_distances(10.0);
        assert_eq!(zs.len(), FRAMES as usize);
        assert!(zs[CROSSING] < 10.0 && zs[CROSSING + 1] > 10.0);
    }

    /// A switch whose crossing step is twice its neighbours' fails; a level within the
    /// tolerance of the mesh's opaque pixels passes.
    #[test]
    fn verdicts() {
        use glam::Vec4;
        // Frame i: its first pixels opaque; the crossing step adds three, the others one.
        let frame = |n: usize| Frame {
            image: ImageF32 {
                width: 16,
                height: 1,
                data: (0..16)
                    .map(|p| if p < n { Vec4::ONE } else { Vec4::ZERO })
                    .collect(),
            },
            lod: (0, 0.0),
            dissolve: 0.0,
        };
        let counts: Vec<usize> = (0..FRAMES as usize)
            .map(|i| i + 2 * usize::from(i > CROSSING))
            .collect();
        let frames: Vec<Frame> = counts.iter().map(|&n| frame(n)).collect();
        let s = judge_switch(0, 10.0, &frame_distances(10.0), &frames).unwrap();
        assert!(s.ratio > STEP_RATIO_LIMIT && !s.pass, "{s:?}");
        let l = judge_level(0, 10.0, &frame(10), &frame(11));
        assert!(l.pass && l.level == 1, "{l:?}");
        let l = judge_level(0, 10.0, &frame(10), &frame(12));
        assert!(!l.pass, "{l:?}");
    }
}
