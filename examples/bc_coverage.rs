//! Alpha-tested coverage of a cloud's atlases before and after BC7 compression:
//! `cargo run --release --example bc_coverage -- RAW.billow BC.billow` (the same bake with
//! `--compress none` and `--compress bc`). Per atlas MIP level (summed over the atlases):
//! the share of texels with alpha ≥ the cut-off (0.5, what the viewer and the glTF
//! export test against) raw and decoded, their relative difference, the share of texels
//! whose test flips, and the colour RMSE in 8-bit steps. Used for docs/accuracy.md.

use billow::bbcloud::atlas::ALPHA_CUTOFF;
use billow_format::CloudAsset;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [raw, bc] = [&args[0], &args[1]]
        .map(|p| CloudAsset::read(std::path::Path::new(p)).unwrap_or_else(|e| panic!("{p}: {e}")));
    let cut = (ALPHA_CUTOFF * 255.0).ceil() as u8;
    let levels = raw.atlases.iter().map(|a| a.mips.len()).max().unwrap_or(0);
    println!("| MIP level | texels | covered raw | covered BC7 | rel. diff | flipped | RGBA RMSE (8-bit) |");
    println!("|---:|---:|---:|---:|---:|---:|---:|");
    for k in 0..levels {
        let (mut n, mut a, mut b, mut flip, mut se) = (0u64, 0u64, 0u64, 0u64, 0f64);
        for (x, y) in raw.atlases.iter().zip(&bc.atlases) {
            let (Some(p), Some(q)) = (x.mips.get(k), y.mips.get(k)) else {
                continue;
            };
            for (s, t) in p.chunks_exact(4).zip(q.chunks_exact(4)) {
                n += 1;
                let (ca, cb) = (s[3] >= cut, t[3] >= cut);
                a += u64::from(ca);
                b += u64::from(cb);
                flip += u64::from(ca != cb);
                for c in 0..4 {
                    let d = f64::from(s[c]) - f64::from(t[c]);
                    se += d * d;
                }
            }
        }
        let pct = |v: u64| 100.0 * v as f64 / n.max(1) as f64;
        println!(
            "| {k} | {n} | {:.3} % | {:.3} % | {:+.2} % | {:.3} % | {:.2} |",
            pct(a),
            pct(b),
            100.0 * (b as f64 - a as f64) / (a.max(1) as f64),
            pct(flip),
            (se / (4 * n.max(1)) as f64).sqrt()
        );
    }
}
