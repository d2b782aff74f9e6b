//! Measurement for docs/accuracy.md (not a check): what the exact-zero constraint of the
//! BC7 encoder costs on a raw volume (`billow voxelize --compress none`, e.g. the oak at
//! 128³): bytes, empty texels that would decode non-zero without it, and the RMSE over
//! the non-empty texels' bytes, without and with the constraint.
//!
//! `cargo run --release --example bc7_exact_zero -- VOLUME.billow`

use billow::compress::encode_bc7_with;
use billow_format::{decode_bc7, mip_dims, VolumeAsset};

fn main() {
    let Some(p) = std::env::args_os().nth(1) else {
        eprintln!("usage: bc7_exact_zero VOLUME.billow (a raw volume: --compress none)");
        std::process::exit(2);
    };
    let a = VolumeAsset::read(std::path::Path::new(&p)).expect("read the volume");
    let dims = a.level_dims(0);
    for keep in [false, true] {
        let (mut sq, mut n, mut leaks, mut bytes) = (0f64, 0u64, 0u64, 0usize);
        for (i, l) in a.levels.iter().enumerate() {
            let d = mip_dims(dims, i as u32);
            let enc = encode_bc7_with(l, d, 0, false, keep);
            bytes += enc.len();
            let dec = decode_bc7(&enc, d, 0);
            for (s, t) in l.chunks_exact(4).zip(dec.chunks_exact(4)) {
                if s == [0; 4] && t != [0; 4] {
                    leaks += 1;
                }
                if s != [0; 4] {
                    for c in 0..4 {
                        let e = f64::from(s[c]) - f64::from(t[c]);
                        sq += e * e;
                    }
                    n += 4;
                }
            }
        }
        println!(
            "keep_zero={keep}: {bytes} bytes, leaking empty texels {leaks}, RMSE over non-empty texel bytes {:.4}",
            (sq / n as f64).sqrt()
        );
    }
}
