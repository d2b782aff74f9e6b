//! `billow view CLOUD --lod-sweep DIR`: what a viewer sees across every LOD switch of a
//! billboard cloud (docs/bbcloud.md, "LOD switches"). The frames are rendered by the
//! viewer's dolly ([`billow_view::dolly`]) and judged by the library
//! ([`billow::eval::lod_sweep`]); this module joins the two, writes each switch's frames
//! and prints the tables.

use std::path::Path;

use billow::eval::lod_sweep::{self, Frame, Sweep, SweepError, STEP_RATIO_LIMIT};
use billow::eval::ImageF32;
use billow_view::dolly::{Dolly, NotOneCloud};
use billow_view::Renderer;
use glam::{Vec3, Vec4};

use crate::exit::{CliError, Code};

/// Runs the sweep on the renderer's one cloud instance; writes `switch_K.png` (the frames
/// on either side of switch K and their difference ×4) into `dir` when given.
pub fn sweep(
    r: &mut Renderer,
    (width, height): (u32, u32),
    (view_dir, fov_y, fill): (Vec3, f32, Option<f32>),
    dir: Option<&Path>,
) -> Result<Sweep, CliError> {
    let (mut dolly, distances) =
        Dolly::new(r, (width, height), (view_dir, fov_y, fill)).map_err(|NotOneCloud(n)| {
            CliError::new(
                Code::BadParameter,
                format!(
                    "--lod-sweep: needs a scene with exactly one billboard cloud, this one has {n}"
                ),
            )
        })?;
    let frame = |z: f32, d: f32, lod: Option<f32>| {
        let f = dolly
            .frame(z, d, lod)
            .map_err(|e| CliError::new(Code::Internal, e))?;
        Ok(Frame {
            image: ImageF32 {
                width: f.image.width,
                height: f.image.height,
                data: f.image.data.iter().map(|p| Vec4::from_array(*p)).collect(),
            },
            lod: f.lod,
            dissolve: f.dissolve,
        })
    };
    let crossing = |k: usize, a: &ImageF32, b: &ImageF32| match dir {
        Some(dir) => billow::eval::image::write_comparison_png(
            a,
            b,
            4.0,
            &dir.join(format!("switch_{k}.png")),
        )
        .map_err(|e| CliError::new(Code::OutputIo, e)),
        None => Ok(()),
    };
    let (switches, levels) =
        lod_sweep::sweep(&distances, frame, crossing).map_err(|e| match e {
            SweepError::NoSwitch => CliError::new(Code::BadParameter, format!("--lod-sweep: {e}")),
            SweepError::Frame(e) => e,
            SweepError::Metrics(e) => CliError::new(Code::Internal, e),
        })?;
    Ok(Sweep::new(
        (width, height),
        (view_dir.normalize().to_array(), fov_y.to_degrees(), fill),
        switches,
        levels,
    ))
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
            if w.pass {
                String::new()
            } else {
                format!("(over {STEP_RATIO_LIMIT}×)")
            },
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
