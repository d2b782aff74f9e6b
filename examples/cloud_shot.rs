//! One image of a billboard-cloud level by billow's CPU cloud renderer
//! (`billow::eval::cloud_render`, what `billow eval` uses) from an exact camera, for
//! comparing with another renderer (tests/threejs: three.js rendering the `.glb` export).
//!
//! `cargo run --release --example cloud_shot -- CLOUD.billow OUT.png --lod K
//!  --eye X,Y,Z --target X,Y,Z --fov DEG --size WxH [--spp N]`
//!
//! Camera: right-handed, y up, looking from `eye` at `target`, `fov` the vertical field
//! of view in degrees, aspect `W/H` (the conventions of `billow_core::camera` and of a
//! three.js `PerspectiveCamera`). The trunk is lit as the asset was baked (header `light`,
//! `ambient`); the billboards carry their baked lighting. `--spp` samples per pixel (a
//! square number, stratified; default 16). Output: sRGB PNG, straight alpha, transparent
//! background, written atomically (temporary file + rename).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use billow::eval::cloud_render::{CloudRenderer, PreparedCloud};
use billow::eval::lighting::Lighting;
use billow::eval::reference::Sampling;
use billow_core::camera::Camera;
use billow_format::{read_file, CloudAsset};
use glam::Vec3;

struct Args {
    cloud: PathBuf,
    out: PathBuf,
    lod: usize,
    eye: Vec3,
    target: Vec3,
    fov_deg: f32,
    size: (u32, u32),
    spp: u32,
}

fn vec3(flag: &str, s: &str) -> Result<Vec3, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("{flag} '{s}': {e}"))?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Vec3::new(x, y, z)),
        _ => Err(format!("{flag} '{s}': expected three finite numbers X,Y,Z")),
    }
}

fn parse(args: &[String]) -> Result<Args, String> {
    let [cloud, out, rest @ ..] = args else {
        return Err("expected CLOUD.billow OUT.png and the options".into());
    };
    let mut a = Args {
        cloud: cloud.into(),
        out: out.into(),
        lod: 0,
        eye: Vec3::ZERO,
        target: Vec3::ZERO,
        fov_deg: 0.0,
        size: (0, 0),
        spp: 16,
    };
    let mut seen = Vec::new();
    for pair in rest.chunks(2) {
        let [flag, value] = pair else {
            return Err(format!("{}: missing its value", pair[0]));
        };
        let num = |e: std::num::ParseIntError| format!("{flag} '{value}': {e}");
        match flag.as_str() {
            "--lod" => a.lod = value.parse().map_err(num)?,
            "--eye" => a.eye = vec3(flag, value)?,
            "--target" => a.target = vec3(flag, value)?,
            "--fov" => {
                a.fov_deg = value
                    .parse()
                    .map_err(|e| format!("{flag} '{value}': {e}"))?
            }
            "--size" => {
                let (w, h) = value
                    .split_once('x')
                    .ok_or_else(|| format!("{flag} '{value}': expected WxH"))?;
                a.size = (w.parse().map_err(num)?, h.parse().map_err(num)?);
            }
            "--spp" => a.spp = value.parse().map_err(num)?,
            _ => return Err(format!("unknown option {flag}")),
        }
        seen.push(flag.as_str());
    }
    for required in ["--eye", "--target", "--fov", "--size"] {
        if !seen.contains(&required) {
            return Err(format!("{required} is required"));
        }
    }
    if !(a.fov_deg > 0.0 && a.fov_deg < 180.0) {
        return Err(format!("--fov {}: must be in (0, 180)", a.fov_deg));
    }
    if !(1..=4096).contains(&a.size.0) || !(1..=4096).contains(&a.size.1) {
        return Err("--size: each side must be 1 to 4096 pixels".into());
    }
    if a.eye == a.target {
        return Err("--eye and --target must differ".into());
    }
    Ok(a)
}

fn render(a: &Args) -> Result<(), String> {
    let shown = a.cloud.display();
    let container = read_file(&a.cloud).map_err(|e| format!("{shown}: {e}"))?;
    let asset = CloudAsset::from_container(container).map_err(|e| format!("{shown}: {e}"))?;
    let lighting =
        Lighting::for_cloud(&asset.header.params).map_err(|e| format!("{shown}: {e}"))?;
    let prepared = PreparedCloud::new(&asset).map_err(|e| format!("{shown}: {e}"))?;
    let renderer = CloudRenderer::new(&prepared, lighting).map_err(|e| format!("{shown}: {e}"))?;
    let n = (a.spp as f64).sqrt().round() as u32;
    if n == 0 || n * n != a.spp {
        return Err(format!("--spp {}: must be a square number", a.spp));
    }
    // Clip planes from the distance to the asset's bounds, loose on both sides.
    let b = &asset.header.bounds;
    let (lo, hi) = (Vec3::from(b.min), Vec3::from(b.max));
    let far_point = (a.eye - (lo + hi) * 0.5).length() + (hi - lo).length();
    let camera = Camera {
        eye: a.eye,
        target: a.target,
        up: Vec3::Y,
        fov_y: a.fov_deg.to_radians(),
        width: a.size.0,
        height: a.size.1,
        near: 1e-3 * far_point,
        far: 2.0 * far_point,
    };
    let r = renderer
        .render(a.lod, &camera, Sampling::Stratified { per_axis: n })
        .map_err(|e| format!("{shown}: {e}"))?;
    let tmp = temp_path(&a.out);
    r.image
        .write_png(&tmp)
        .map_err(|e| format!("{}: {e}", a.out.display()))?;
    std::fs::rename(&tmp, &a.out).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        format!("{}: {e}", a.out.display())
    })?;
    println!(
        "{}: LOD {} of {shown}, {} billboards ({} visible), coverage {:.4}, {:.2} s",
        a.out.display(),
        a.lod,
        r.stats.billboards,
        r.stats.visible_billboards,
        r.image.coverage(),
        r.stats.seconds
    );
    Ok(())
}

fn temp_path(out: &Path) -> PathBuf {
    let name = out
        .file_name()
        .map_or("out".into(), |n| n.to_string_lossy());
    out.with_file_name(format!(".{name}.tmp.png"))
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = parse(&args).and_then(|a| render(&a));
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            eprintln!(
                "usage: cloud_shot CLOUD.billow OUT.png [--lod K] --eye X,Y,Z --target X,Y,Z \
                 --fov DEG --size WxH [--spp N]"
            );
            ExitCode::from(2)
        }
    }
}
