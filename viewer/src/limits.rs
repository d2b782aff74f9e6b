//! The ranges of the viewer's numeric parameters, each declared once: a scene file's
//! fields ([`crate::scene`]), the slicing ([`crate::SliceParams::validate`]) and `billow
//! view`'s flags ([`ViewParams::validate`]) are checked against these, and a flag's error
//! is a [`ParamError`] the binary prints after the flag's name (`--fov: 200: must be in
//! (0, 180) degrees`).

use std::ops::RangeInclusive;

/// The vertical field of view, in degrees: strictly between these.
pub const FOV_DEG: (f32, f32) = (0.0, 180.0);
/// The half-width of a cloud's dithered LOD dissolve, in octaves of distance.
pub const DISSOLVE_OCTAVES: RangeInclusive<f32> = 0.0..=4.0;
/// The largest fraction of the frame height a LOD sweep keeps the cloud at (above 0).
pub const MAX_SWEEP_FILL: f32 = 4.0;
/// A linear colour's components (backgrounds, the ground).
pub const COLOUR: RangeInclusive<f32> = 0.0..=1.0;

/// A parameter outside its range: the problem, said after the parameter's name
/// ([`ParamError::param`]).
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// The framing distance (a multiple of the framed distance) is not above 0.
    #[error("must be > 0")]
    Distance(f32),
    #[error("{0}: must be in ({lo}, {hi}) degrees", lo = FOV_DEG.0, hi = FOV_DEG.1)]
    Fov(f32),
    /// The distance cloud LODs are chosen at is not above 0.
    #[error("{0}: must be > 0")]
    LodDistance(f32),
    #[error(
        "{0}: must be in [{lo}, {hi}] octaves",
        lo = DISSOLVE_OCTAVES.start(),
        hi = DISSOLVE_OCTAVES.end()
    )]
    Dissolve(f32),
    /// The scene time is not finite.
    #[error("must be finite")]
    Time(f32),
    /// The orbit step, in degrees a frame, is not finite.
    #[error("must be finite")]
    Orbit(f32),
    /// No frames to render.
    #[error("must be at least 1")]
    Frames,
    /// A slab would hold no slices.
    #[error("must be at least 1")]
    SlabMinSlices,
    #[error("{0}: must be in (0, {MAX_SWEEP_FILL}]")]
    SweepFill(f32),
    #[error("components must be in [{lo}, {hi}]", lo = COLOUR.start(), hi = COLOUR.end())]
    Background([f32; 3]),
}

impl ParamError {
    /// The parameter at fault, as [`ViewParams`]' field (`background` for
    /// [`check_background`]).
    pub fn param(&self) -> &'static str {
        match self {
            ParamError::Distance(_) => "distance",
            ParamError::Fov(_) => "fov_deg",
            ParamError::LodDistance(_) => "lod_distance",
            ParamError::Dissolve(_) => "dissolve",
            ParamError::Time(_) => "time",
            ParamError::Orbit(_) => "orbit_deg",
            ParamError::Frames => "frames",
            ParamError::SlabMinSlices => "slab_min_slices",
            ParamError::SweepFill(_) => "sweep_fill",
            ParamError::Background(_) => "background",
        }
    }
}

/// A field of view, degrees, strictly inside [`FOV_DEG`].
/// Whether `v` is a valid slice spacing factor (an adaptive spacing's bias, a uniform
/// spacing in level-0 voxels): finite and above 0 ([`crate::SliceParams::validate`] and
/// `billow view --spacing` both ask this).
pub fn spacing_factor_ok(v: f32) -> bool {
    v.is_finite() && v > 0.0
}

pub fn check_fov(fov_deg: f32) -> Result<(), ParamError> {
    if fov_deg > FOV_DEG.0 && fov_deg < FOV_DEG.1 {
        Ok(())
    } else {
        Err(ParamError::Fov(fov_deg))
    }
}

/// A dissolve half-width within [`DISSOLVE_OCTAVES`].
pub fn check_dissolve(octaves: f32) -> Result<(), ParamError> {
    if DISSOLVE_OCTAVES.contains(&octaves) {
        Ok(())
    } else {
        Err(ParamError::Dissolve(octaves))
    }
}

/// Whether every component of a colour is within [`COLOUR`].
pub fn is_colour(c: [f32; 3]) -> bool {
    c.iter().all(|x| COLOUR.contains(x))
}

/// An opaque background colour, each component within [`COLOUR`].
pub fn check_background(c: [f32; 3]) -> Result<(), ParamError> {
    if is_colour(c) {
        Ok(())
    } else {
        Err(ParamError::Background(c))
    }
}

/// Fewest slices per slab: at least 1.
pub fn check_slab_min_slices(n: u32) -> Result<(), ParamError> {
    if n >= 1 {
        Ok(())
    } else {
        Err(ParamError::SlabMinSlices)
    }
}

/// How a view is framed, timed and sliced: the numbers `billow view` takes as flags.
/// `None` leaves the scene's (or the default) value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewParams {
    /// Without an explicit eye: the multiple of the framed distance, > 0.
    pub distance: f32,
    /// The vertical field of view, degrees ([`FOV_DEG`]).
    pub fov_deg: Option<f32>,
    /// Choose cloud LODs as if every instance were this far from the eye, > 0.
    pub lod_distance: Option<f32>,
    /// Every cloud's dissolve half-width ([`DISSOLVE_OCTAVES`]).
    pub dissolve: Option<f32>,
    /// Scene time, seconds: finite.
    pub time: f32,
    /// Degrees the camera orbits a frame: finite.
    pub orbit_deg: f32,
    /// Frames to render, ≥ 1.
    pub frames: Option<u32>,
    /// Fewest slices per slab, ≥ 1.
    pub slab_min_slices: u32,
    /// A LOD sweep's cloud size as a fraction of the frame height, in (0, [`MAX_SWEEP_FILL`]].
    pub sweep_fill: Option<f32>,
}

impl ViewParams {
    /// Every field checked against its range, in the order of the fields.
    pub fn validate(&self) -> Result<(), ParamError> {
        if !(self.distance.is_finite() && self.distance > 0.0) {
            return Err(ParamError::Distance(self.distance));
        }
        self.fov_deg.map_or(Ok(()), check_fov)?;
        if let Some(d) = self.lod_distance {
            if !(d > 0.0 && d.is_finite()) {
                return Err(ParamError::LodDistance(d));
            }
        }
        self.dissolve.map_or(Ok(()), check_dissolve)?;
        if !self.time.is_finite() {
            return Err(ParamError::Time(self.time));
        }
        if !self.orbit_deg.is_finite() {
            return Err(ParamError::Orbit(self.orbit_deg));
        }
        if self.frames == Some(0) {
            return Err(ParamError::Frames);
        }
        check_slab_min_slices(self.slab_min_slices)?;
        if let Some(f) = self.sweep_fill {
            if !(f > 0.0 && f <= MAX_SWEEP_FILL) {
                return Err(ParamError::SweepFill(f));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ok() -> ViewParams {
        ViewParams {
            distance: 1.0,
            fov_deg: Some(45.0),
            lod_distance: Some(10.0),
            dissolve: Some(0.375),
            time: 0.0,
            orbit_deg: 0.0,
            frames: Some(1),
            slab_min_slices: 16,
            sweep_fill: Some(1.0),
        }
    }

    #[test]
    fn good_params_pass() {
        assert_eq!(ok().validate(), Ok(()));
        let edges = ViewParams {
            dissolve: Some(4.0),
            sweep_fill: Some(MAX_SWEEP_FILL),
            slab_min_slices: 1,
            fov_deg: None,
            lod_distance: None,
            frames: None,
            ..ok()
        };
        assert_eq!(edges.validate(), Ok(()));
        assert_eq!(check_background([0.0, 0.5, 1.0]), Ok(()));
    }

    #[test]
    fn each_bad_param_is_refused_with_its_error() {
        let cases = [
            (
                ViewParams {
                    distance: 0.0,
                    ..ok()
                },
                "distance",
            ),
            (
                ViewParams {
                    distance: f32::INFINITY,
                    ..ok()
                },
                "distance",
            ),
            (
                ViewParams {
                    fov_deg: Some(180.0),
                    ..ok()
                },
                "fov_deg",
            ),
            (
                ViewParams {
                    fov_deg: Some(0.0),
                    ..ok()
                },
                "fov_deg",
            ),
            (
                ViewParams {
                    lod_distance: Some(0.0),
                    ..ok()
                },
                "lod_distance",
            ),
            (
                ViewParams {
                    dissolve: Some(4.5),
                    ..ok()
                },
                "dissolve",
            ),
            (
                ViewParams {
                    dissolve: Some(f32::NAN),
                    ..ok()
                },
                "dissolve",
            ),
            (
                ViewParams {
                    time: f32::NAN,
                    ..ok()
                },
                "time",
            ),
            (
                ViewParams {
                    orbit_deg: f32::INFINITY,
                    ..ok()
                },
                "orbit_deg",
            ),
            (
                ViewParams {
                    frames: Some(0),
                    ..ok()
                },
                "frames",
            ),
            (
                ViewParams {
                    slab_min_slices: 0,
                    ..ok()
                },
                "slab_min_slices",
            ),
            (
                ViewParams {
                    sweep_fill: Some(0.0),
                    ..ok()
                },
                "sweep_fill",
            ),
            (
                ViewParams {
                    sweep_fill: Some(4.5),
                    ..ok()
                },
                "sweep_fill",
            ),
        ];
        for (p, param) in cases {
            let e = p.validate().expect_err(param);
            assert_eq!(e.param(), param, "{p:?}");
        }
        assert_eq!(
            check_background([1.5, 0.0, 0.0]),
            Err(ParamError::Background([1.5, 0.0, 0.0]))
        );
    }

    #[test]
    fn messages_say_the_ranges() {
        assert_eq!(
            ParamError::Fov(200.0).to_string(),
            "200: must be in (0, 180) degrees"
        );
        assert_eq!(
            ParamError::Dissolve(5.0).to_string(),
            "5: must be in [0, 4] octaves"
        );
        assert_eq!(
            ParamError::SweepFill(5.0).to_string(),
            "5: must be in (0, 4]"
        );
        assert_eq!(
            ParamError::Background([2.0; 3]).to_string(),
            "components must be in [0, 1]"
        );
    }
}
