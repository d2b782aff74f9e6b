//! Per atlas MIP level of a cloud: mean alpha, tested share, and rendered share
//! (bilinear + alpha test), summed over the atlases (scratch).
use billow::bbcloud::atlas::{rendered_coverage, ALPHA_CUTOFF};
use billow::bbcloud::bake::Image;
use billow_format::CloudAsset;
use glam::Vec4;
fn main() {
    let p = std::env::args().nth(1).unwrap();
    let c = CloudAsset::read(std::path::Path::new(&p)).unwrap();
    let levels = c.atlases.iter().map(|a| a.mips.len()).max().unwrap_or(0);
    for k in 0..levels {
        let (mut n, mut sum, mut t, mut r) = (0u64, 0f64, 0u64, 0f64);
        for a in &c.atlases {
            let Some(m) = a.mips.get(k) else { continue };
            let (w, h) = ((a.width >> k).max(1), (a.height >> k).max(1));
            let img = Image {
                width: w,
                height: h,
                texels: m
                    .chunks_exact(4)
                    .map(|p| Vec4::new(0.0, 0.0, 0.0, f32::from(p[3]) / 255.0))
                    .collect(),
            };
            r += rendered_coverage(&img, 1.0, ALPHA_CUTOFF) * img.texels.len() as f64;
            for px in m.chunks_exact(4) {
                n += 1;
                sum += f64::from(px[3]) / 255.0;
                t += u64::from(px[3] >= 128);
            }
        }
        let n = n as f64;
        println!(
            "mip {k}: mean {:.4} tested {:.4} rendered {:.4}",
            sum / n,
            t as f64 / n,
            r / n
        );
    }
}
