//! Orthographic projected coverage of every MIP level of a volume asset, per axis:
//! `cargo run --release --example coverage_probe -- VOLUME.billow`. Per level and axis,
//! Σ over the level's texel columns of `1 − Π(1 − α)` × the column's cross-section in
//! level-0 texels, relative to level 0's: how much opacity the MIP chain adds or loses
//! when a column is composited at that level (no slicer, no filtering).

use billow::eval::volume_sampler::DecodedVolume;
use billow_format::VolumeAsset;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    for p in &args {
        let asset =
            VolumeAsset::read(std::path::Path::new(p)).unwrap_or_else(|e| panic!("{p}: {e}"));
        let vol = DecodedVolume::decode(&asset).unwrap();
        let d0 = vol.levels[0].dims;
        println!("{p}: {:?}, {} levels", d0, vol.levels.len());
        let mut base = [0.0f64; 3];
        for (l, lev) in vol.levels.iter().enumerate() {
            let d = lev.dims;
            let mut out = [0.0f64; 3];
            for axis in 0..3 {
                let (u, v) = match axis {
                    0 => (1, 2),
                    1 => (0, 2),
                    _ => (0, 1),
                };
                let area = (d0[u] as f64 / d[u] as f64) * (d0[v] as f64 / d[v] as f64);
                let mut s = 0.0;
                for j in 0..d[v] {
                    for i in 0..d[u] {
                        let mut t = 1.0f64;
                        for k in 0..d[axis] {
                            let mut p = [0u32; 3];
                            p[axis] = k;
                            p[u] = i;
                            p[v] = j;
                            let idx = p[0] + d[0] * (p[1] + d[1] * p[2]);
                            t *= 1.0 - lev.texels[idx as usize].w as f64;
                        }
                        s += (1.0 - t) * area;
                    }
                }
                out[axis] = s;
            }
            if l == 0 {
                base = out;
            }
            println!(
                "  level {l} {:?}: x {:+.1}%  y {:+.1}%  z {:+.1}%",
                d,
                100.0 * (out[0] / base[0] - 1.0),
                100.0 * (out[1] / base[1] - 1.0),
                100.0 * (out[2] / base[2] - 1.0)
            );
        }
    }
}
