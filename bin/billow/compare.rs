//! `billow compare REFERENCE.png TEST.png [--diff OUT.png] [--json]`: the eval's image
//! metrics (RMSE/PSNR on premultiplied linear RGBA, alpha coverage, SSIM, FLIP) between two
//! images of the same size, e.g. two `billow view` screenshots.

use std::path::{Path, PathBuf};

use billow::eval::image::{comparisons_png_bytes, ImageF32};
use billow::eval::metrics::{compare, ImageError};
use serde::Serialize;

use crate::exit::{CliError, Code};
use crate::output::{encode_image, image_out, print_json, refuse_clobbering, ImageOut};
use crate::staged::{out_err, Staged};
use crate::Ctx;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The reference image (PNG, EXR or any format the `image` crate reads).
    reference: PathBuf,
    /// The image compared with it (same size).
    test: PathBuf,
    /// Write reference | test | heatmap (×4) here, atomically: PNG, or JPEG for a .jpg/.jpeg name.
    #[arg(long, value_name = "OUT.png")]
    diff: Option<PathBuf>,
    /// Print a JSON summary on stdout.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct Summary {
    reference: String,
    test: String,
    width: u32,
    height: u32,
    error: ImageError,
}

/// Reads an image as premultiplied linear RGBA ([`ImageF32::from_image`]).
fn load(p: &Path) -> Result<ImageF32, CliError> {
    let img = image::open(p).map_err(|e| {
        let why = match &e {
            // The image crate's "The file extension `."billow"` was not recognized".
            image::ImageError::Unsupported(_)
                if p.extension()
                    .is_some_and(|x| x.eq_ignore_ascii_case("billow")) =>
            {
                "a billow asset, not an image (`billow eval MESH ASSET` compares an asset \
                 with its mesh)"
                    .to_string()
            }
            image::ImageError::Unsupported(_) => format!(
                "not an image billow reads ({e}); compare takes PNG, JPEG, EXR, TGA, BMP, \
                 GIF, HDR or WebP"
            ),
            _ => e.to_string(),
        };
        CliError::new(Code::from(&e), format!("{}: {why}", p.display()))
    })?;
    Ok(ImageF32::from_image(&img))
}

pub fn run(args: Args, ctx: &Ctx) -> Result<(), CliError> {
    if let Some(d) = &args.diff {
        refuse_clobbering(&[&args.reference, &args.test], &[("--diff", d)])?;
    }
    let diff_kind = args
        .diff
        .as_deref()
        .map(|d| image_out("--diff", d))
        .transpose()?;
    let r = load(&args.reference)?;
    let t = load(&args.test)?;
    if (r.width, r.height) != (t.width, t.height) {
        return Err(CliError::new(
            Code::InvalidInput,
            format!(
                "{}: {}x{} but {} is {}x{}: the images must be the same size",
                args.test.display(),
                t.width,
                t.height,
                args.reference.display(),
                r.width,
                r.height
            ),
        ));
    }
    let error = compare(&r, &t).map_err(|e| CliError::new(Code::InvalidInput, e))?;
    if let Some(d) = &args.diff {
        let png = comparisons_png_bytes(&r, &[&t], 4.0, d)
            .map_err(|e| CliError::new(Code::Internal, format!("{}: {e}", d.display())))?;
        let png = encode_image(diff_kind.unwrap_or(ImageOut::Png), png, d)?;
        let mut stage = Staged::new(d);
        stage.stage(d, &png).map_err(|e| out_err(d, e))?;
        stage.commit_or_fail()?;
    }
    if args.json {
        print_json(&Summary {
            reference: args.reference.display().to_string(),
            test: args.test.display().to_string(),
            width: r.width,
            height: r.height,
            error,
        })?;
    } else if !ctx.quiet {
        outln!(
            "RMSE {:.5}  PSNR {:.2} dB  FLIP {:.4}  SSIM luma {:.4}  alpha {:.4}  coverage {:+.2}%",
            error.rmse,
            error.psnr,
            error.flip,
            error.ssim_luma,
            error.ssim_alpha,
            error.coverage_rel_diff * 100.0
        );
    }
    Ok(())
}
