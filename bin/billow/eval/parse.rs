//! `billow eval`'s argument parsing: the lights, image size, distances, views, slice
//! spacing and samples per pixel, each refused with its flag's name (exit 2).

use billow::eval::lighting::{parse_light_set, EvalLight, LightSetError};
use billow::eval::limits::{
    distance_factor_ok, image_side_ok, spacing_factor_ok, MAX_DISTANCE_FACTOR, MAX_IMAGE_SIDE,
    SPACING_FACTOR,
};
use billow_core::camera::{parse_direction, view_directions, views_of, ViewDirections, ViewSpec};
use billow_core::slicing::Spacing;
use glam::Vec3;

use super::Args;
use crate::exit::{usage, CliError, Code};

pub(crate) fn bad(flag: &str, e: impl std::fmt::Display) -> CliError {
    CliError::new(Code::BadParameter, format!("{flag}: {e}"))
}

/// `--light`/`--lights`/`--ambient`: the lights to evaluate under, or `None` (the asset's
/// own lighting, `--lighting`).
pub(crate) fn parse_lights(args: &Args) -> Result<Option<Vec<EvalLight>>, CliError> {
    if !(args.ambient.is_finite() && (0.0..=1.0).contains(&args.ambient)) {
        return Err(bad(
            "--ambient",
            format!("{} is out of range (0 to 1)", args.ambient),
        ));
    }
    let vector = |flag: &str, text: &str| -> Result<Vec3, CliError> {
        let v: Vec<f32> = text
            .split(',')
            .map(|x| x.trim().parse::<f32>())
            .collect::<Result<_, _>>()
            .map_err(|e| usage(flag, format!("'{text}': {e} (expected X,Y,Z)")))?;
        match v[..] {
            [x, y, z] => Ok(Vec3::new(x, y, z)),
            _ => Err(usage(flag, format!("'{text}': expected X,Y,Z"))),
        }
    };
    let light = |flag: &str, name: String, dir: Vec3| {
        EvalLight::new(name, dir, args.ambient).ok_or_else(|| {
            bad(
                flag,
                format!("({}, {}, {}) is not a direction", dir.x, dir.y, dir.z),
            )
        })
    };
    if let Some(l) = &args.light {
        let dir = vector("--light", l)?;
        return Ok(Some(vec![light("--light", "light".into(), dir)?]));
    }
    let Some(set) = &args.lights else {
        if args.shadows {
            return Err(usage("--shadows", "needs --light or --lights"));
        }
        return Ok(None);
    };
    parse_light_set(set, args.ambient)
        .map(Some)
        .map_err(|e| match e {
            LightSetError::Syntax(m) => usage("--lights", m),
            LightSetError::NotADirection(m) => bad("--lights", m),
        })
}

/// `WxH`, each 1..=[`MAX_IMAGE_SIDE`].
pub fn parse_size(s: &str) -> Result<(u32, u32), CliError> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| usage("--size", format!("'{s}': expected WxH, e.g. 128x128")))?;
    let p = |v: &str| -> Result<u32, CliError> {
        let n: u32 = v
            .trim()
            .parse()
            .map_err(|e| usage("--size", format!("'{s}': {e}")))?;
        if !image_side_ok(n) {
            return Err(bad(
                "--size",
                format!("'{s}': each side must be 1 to {MAX_IMAGE_SIDE} pixels"),
            ));
        }
        Ok(n)
    };
    Ok((p(w)?, p(h)?))
}

/// `1,4,16`: positive finite factors up to [`MAX_DISTANCE_FACTOR`].
pub fn parse_distances(s: &str) -> Result<Vec<f32>, CliError> {
    let mut out: Vec<f32> = Vec::new();
    for part in s.split(',') {
        let f: f32 = part
            .trim()
            .parse()
            .map_err(|e| usage("--distances", format!("'{part}': {e}")))?;
        if !distance_factor_ok(f) {
            return Err(bad(
                "--distances",
                format!("'{part}': a factor must be above 0 and at most {MAX_DISTANCE_FACTOR}"),
            ));
        }
        if !out.contains(&f) {
            out.push(f);
        }
    }
    Ok(out)
}

/// See `--views`.
pub fn parse_views(s: &str, distances: &[f32]) -> Result<Vec<ViewSpec>, CliError> {
    let mut out: Vec<ViewSpec> = Vec::new();
    let mut push = |v: ViewSpec| {
        if !out.iter().any(|o| o.name == v.name) {
            out.push(v);
        }
    };
    for item in s.split(',').map(str::trim) {
        let set = match item {
            "axes" => Some(ViewDirections::Axes),
            "diagonals" => Some(ViewDirections::Diagonals),
            "all" => Some(ViewDirections::All),
            _ => None,
        };
        if let Some(set) = set {
            views_of(view_directions(set), distances)
                .into_iter()
                .for_each(&mut push);
            continue;
        }
        let unknown = || {
            usage(
                "--views",
                format!(
                    "unknown view '{item}': expected axes, diagonals, all, a direction like +x or \
                     +x-y+z, or a view like +x@4x"
                ),
            )
        };
        let (dir_name, factor) = match item.split_once('@') {
            Some((d, f)) => {
                let f = f.strip_suffix('x').ok_or_else(unknown)?;
                // A factor out of range is that (8); anything else does not parse (2).
                let f = parse_distances(f).map_err(|e| {
                    if e.code == Code::BadParameter {
                        e
                    } else {
                        unknown()
                    }
                })?;
                (d, Some(f[0]))
            }
            None => (item, None),
        };
        let dir = parse_direction(dir_name).ok_or_else(unknown)?;
        let factors = factor.map_or_else(|| distances.to_vec(), |f| vec![f]);
        views_of(vec![(dir_name.to_string(), dir)], &factors)
            .into_iter()
            .for_each(&mut push);
    }
    Ok(out)
}

/// See `--spacing` (a uniform spacing in level-0 voxels: [`EvaluateOptions::spacing`]).
pub fn parse_spacing(s: &str) -> Result<Spacing, CliError> {
    let (mode, arg) = match s.split_once(':') {
        Some((m, a)) => (m.trim(), Some(a.trim())),
        None => (s.trim(), None),
    };
    let num = |a: Option<&str>| -> Result<f32, CliError> {
        let Some(a) = a else { return Ok(1.0) };
        let v: f32 = a
            .parse()
            .map_err(|e| usage("--spacing", format!("'{s}': {e}")))?;
        if !spacing_factor_ok(v) {
            return Err(bad(
                "--spacing",
                format!(
                    "'{s}': the factor must be between {} and {}",
                    SPACING_FACTOR.0, SPACING_FACTOR.1
                ),
            ));
        }
        Ok(v)
    };
    match mode {
        "adaptive" => Ok(Spacing::Adaptive { bias: num(arg)? }),
        "uniform" => {
            let v = num(arg)?;
            Ok(Spacing::Uniform { spacing: v })
        }
        _ => Err(usage(
            "--spacing",
            format!("'{s}': expected adaptive, adaptive:BIAS, uniform or uniform:VOXELS"),
        )),
    }
}

pub(crate) fn spp_per_axis(spp: u32) -> Result<u32, CliError> {
    let n = (1..=16).find(|n| n * n == spp);
    n.ok_or_else(|| {
        bad(
            "--spp",
            format!("{spp} is not a square number from 1 to 256 (e.g. 1, 4, 9, 16, 64)"),
        )
    })
}
