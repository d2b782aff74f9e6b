//! The asteroid belt of the VB paper's Figure 10, scaled for a software rasterizer:
//! `cargo run --release --example gen_asteroid_belt -- SCENE_DIR [RES] [INSTANCES]`
//! writes `SCENE_DIR/assets/asteroid_NN.billow` (12 rocks) and `dust_NN.billow` (6 dust
//! clouds), `RES`³ voxels each (default 64; the paper: 40 + 20 volumes at 128³), and the
//! scene `SCENE_DIR/asteroid_belt.ron`: `INSTANCES` (default 1200) billboards on a ring,
//! a quarter of them dust clouds overlapping the rocks. Deterministic.

use std::fmt::Write as _;
use std::path::PathBuf;

use billow::noise_volume::{asteroid, dust};
use billow::rng::Pcg32;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let dir = PathBuf::from(args.next().unwrap_or_else(|| "out/gallery".into()));
    let res: u32 = args.next().map_or(Ok(64), |s| s.parse())?;
    let count: usize = args.next().map_or(Ok(1200), |s| s.parse())?;
    let assets = dir.join("assets");
    std::fs::create_dir_all(&assets)?;
    let (rocks, clouds) = (12u64, 6u64);
    for i in 0..rocks {
        asteroid(res, 100 + i).write(&assets.join(format!("asteroid_{i:02}.billow")))?;
    }
    for i in 0..clouds {
        dust(res, 200 + i).write(&assets.join(format!("dust_{i:02}.billow")))?;
    }
    // Instances on a ring of radius 100 in the y = 0 plane, grouped per volume.
    let mut rng = Pcg32::seeded(1200, 10);
    let mut per: Vec<Vec<String>> = vec![Vec::new(); (rocks + clouds) as usize];
    for _ in 0..count {
        let is_dust = rng.next_f32() < 0.25;
        let k = if is_dust {
            rocks + u64::from(rng.below(clouds as u32))
        } else {
            u64::from(rng.below(rocks as u32))
        };
        let angle = rng.range_f32(0.0, std::f32::consts::TAU);
        let r = 100.0 + rng.range_f32(-14.0, 14.0);
        let y = rng.range_f32(-3.0, 3.0);
        let scale = if is_dust {
            rng.range_f32(5.0, 9.0)
        } else {
            rng.range_f32(0.8, 3.2)
        };
        per[k as usize].push(format!(
            "(translate: ({:.3}, {y:.3}, {:.3}), rotate_y_deg: {:.1}, scale: {scale:.3})",
            r * angle.cos(),
            r * angle.sin(),
            rng.range_f32(0.0, 360.0)
        ));
    }
    let mut s = String::new();
    writeln!(
        s,
        "// The asteroid belt (VB paper, Figure 10): {count} volumetric billboards sharing \
         {rocks} rock and {clouds} dust volumes ({res}^3, Perlin noise; \
         examples/gen_asteroid_belt.rs wrote this file and its assets)."
    )?;
    writeln!(s, "(")?;
    writeln!(
        s,
        "    camera: Some((eye: (0.0, 70.0, 175.0), target: (0.0, 0.0, 40.0), fov_deg: 45.0)),"
    )?;
    writeln!(s, "    light: (direction: (0.5, 0.6, 0.3), ambient: 0.35),")?;
    writeln!(s, "    volumes: [")?;
    for (k, inst) in per.iter().enumerate() {
        if inst.is_empty() {
            continue;
        }
        let name = if (k as u64) < rocks {
            format!("asteroid_{k:02}")
        } else {
            format!("dust_{:02}", k as u64 - rocks)
        };
        writeln!(s, "        (asset: \"assets/{name}.billow\", instances: [")?;
        for i in inst {
            writeln!(s, "            {i},")?;
        }
        writeln!(s, "        ]),")?;
    }
    writeln!(s, "    ],")?;
    writeln!(s, ")")?;
    std::fs::write(dir.join("asteroid_belt.ron"), s)?;
    eprintln!("wrote the asteroid belt to {}", dir.display());
    Ok(())
}
