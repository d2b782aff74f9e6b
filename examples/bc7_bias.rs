//! Measurement for docs/accuracy.md (not a check): how far a raw volume's colour moves
//! through the linear conversion (`billow::compress::linear_colour`) and the volume BC7
//! encoder, as sums of its premultiplied linear channels and their luminance per MIP
//! level, split between tiles with an empty texel (the zero-anchored blocks) and full
//! ones, with the texel RMSE of the encoder (8-bit steps, non-empty texels).
//!
//! `cargo run --release --example bc7_bias -- VOLUME.billow` (a `--compress none` volume)

use billow::compress::{encode_bc7_with, linear_colour};
use billow_format::{decode_bc7, mip_dims, VolumeAsset};

fn sums(l: &[u8], f: impl Fn(usize, u8) -> f64) -> [f64; 4] {
    let mut s = [0f64; 4];
    for t in l.chunks_exact(4) {
        for c in 0..4 {
            s[c] += f(c, t[c]);
        }
    }
    s
}

fn main() {
    let p = std::env::args_os().nth(1).expect("VOLUME.billow");
    let a = VolumeAsset::read(std::path::Path::new(&p)).expect("read the volume");
    let lut = billow::texture::srgb_to_linear_lut();
    let mut lin = a.clone();
    linear_colour(&mut lin);
    let dims = a.level_dims(0);
    let lum = |s: &[f64; 4]| 0.2126 * s[0] + 0.7152 * s[1] + 0.0722 * s[2];
    for i in 0..a.levels.len() {
        let d = mip_dims(dims, i as u32);
        let src = sums(&a.levels[i], |c, b| {
            if c < 3 {
                f64::from(lut[b as usize])
            } else {
                f64::from(b) / 255.0
            }
        });
        let l8 = sums(&lin.levels[i], |_, b| f64::from(b) / 255.0);
        let enc = encode_bc7_with(&lin.levels[i], d, 0, false, true);
        let dec = decode_bc7(&enc, d, 0);
        let bc = sums(&dec, |_, b| f64::from(b) / 255.0);
        let (mut sq, mut n) = (0f64, 0u64);
        for (s, t) in lin.levels[i].chunks_exact(4).zip(dec.chunks_exact(4)) {
            if s != [0; 4] {
                for c in 0..4 {
                    sq += (f64::from(s[c]) - f64::from(t[c])).powi(2);
                }
                n += 4;
            }
        }
        print!("texel RMSE {:.3} ", (sq / n.max(1) as f64).sqrt());
        // By tile class: tiles with an empty texel (zero-anchored) and full ones.
        let (w, h) = (d[0] as usize, d[1] as usize);
        let mut cls = [[[0f64; 2]; 2]; 2]; // [full?][src/dec][lum, alpha]
        for z in 0..d[2] as usize {
            for by in (0..h).step_by(4) {
                for bx in (0..w).step_by(4) {
                    let mut any_empty = false;
                    let mut acc = [[0f64; 2]; 2];
                    for y in by..(by + 4) {
                        for x in bx..(bx + 4) {
                            if x >= w || y >= h {
                                any_empty = true;
                                continue;
                            }
                            let o = 4 * (x + w * (y + h * z));
                            let s = &lin.levels[i][o..o + 4];
                            any_empty |= s == [0; 4];
                            for (k, t) in [s, &dec[o..o + 4]].into_iter().enumerate() {
                                let f = |c: usize| f64::from(t[c]) / 255.0;
                                acc[k][0] += 0.2126 * f(0) + 0.7152 * f(1) + 0.0722 * f(2);
                                acc[k][1] += f(3);
                            }
                        }
                    }
                    let c = usize::from(!any_empty);
                    for k in 0..2 {
                        cls[c][k][0] += acc[k][0];
                        cls[c][k][1] += acc[k][1];
                    }
                }
            }
        }
        for (c, name) in [(0, "anchored"), (1, "full")] {
            print!(
                "{name}: lum share {:.1}% bias {:+.2}% alpha {:+.2}% | ",
                100.0 * cls[c][0][0] / (cls[0][0][0] + cls[1][0][0]),
                100.0 * (cls[c][1][0] / cls[c][0][0] - 1.0),
                100.0 * (cls[c][1][1] / cls[c][0][1] - 1.0)
            );
        }
        let rel = |x: &[f64; 4]| -> String {
            (0..4)
                .map(|c| format!("{:+.2}%", 100.0 * (x[c] / src[c] - 1.0)))
                .collect::<Vec<_>>()
                .join(" ")
        };
        println!(
            "level {i}: linear8 {} lum {:+.2}% | bc7 {} lum {:+.2}%",
            rel(&l8),
            100.0 * (lum(&l8) / lum(&src) - 1.0),
            rel(&bc),
            100.0 * (lum(&bc) / lum(&src) - 1.0)
        );
    }
}
