//! The generated scenes of the gallery (`make gallery`), deterministic:
//! `cargo run --release --example gen_gallery -- SCENE_DIR [RES] [INSTANCES]` writes
//! - the asteroid belt of the VB paper's Figure 10, scaled for a software rasterizer:
//!   `SCENE_DIR/assets/asteroid_NN.billow` (12 rocks) and `dust_NN.billow` (6 dust
//!   clouds), `RES`³ voxels each (default 64; the paper: 40 + 20 volumes at 128³), and
//!   `SCENE_DIR/asteroid_belt.ron`: `INSTANCES` (default 1200) billboards on a ring, a
//!   quarter of them dust clouds overlapping the rocks;
//! - `SCENE_DIR/field.ron` (Figure 9 right, "many instances of several volumes"): 300
//!   instances of six volumes on a ground — oaks, truss towers, furry balls, boulders,
//!   haze — whose assets `make gallery` bakes (`oak128`, `oak64`, `truss`, `furry_ball`)
//!   or this program writes (`asteroid_00`, `dust_00`).

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
            rng.range_f32(4.0, 7.0)
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
         examples/gen_gallery.rs wrote this file and its assets)."
    )?;
    writeln!(s, "(")?;
    writeln!(
        s,
        "    camera: Some((eye: (0.0, 70.0, 175.0), target: (0.0, 0.0, 40.0), fov_deg: 45.0)),"
    )?;
    writeln!(s, "    light: (direction: (0.5, 0.6, 0.3), ambient: 0.35),")?;
    writeln!(s, "    background: Some((0.01, 0.01, 0.025)),")?;
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
    write_field(&dir)?;
    eprintln!("wrote the gallery's generated scenes to {}", dir.display());
    Ok(())
}

/// Figure 9 right: many instances of six volumes scattered over a 400 × 400 ground.
fn write_field(dir: &std::path::Path) -> Result<(), Box<dyn std::error::Error>> {
    // (asset, count, scale range, lift above the ground in units of the scale)
    let kinds: [(&str, usize, f32, f32, f32); 6] = [
        ("oak128", 30, 0.25, 0.4, 0.0),
        ("oak64", 80, 0.15, 0.3, 0.0),
        ("truss", 20, 2.0, 3.5, 0.0),
        ("furry_ball", 60, 3.0, 6.0, 0.6),
        ("asteroid_00", 90, 2.0, 5.0, 0.5),
        ("dust_00", 20, 15.0, 25.0, 0.4),
    ];
    let mut rng = Pcg32::seeded(2500, 11);
    let mut s = String::new();
    writeln!(
        s,
        "// Many instances of several volumes (VB paper, Figure 9 right): {} billboards          sharing six volumes (examples/gen_gallery.rs wrote this file).",
        kinds.iter().map(|k| k.1).sum::<usize>()
    )?;
    writeln!(s, "(")?;
    writeln!(
        s,
        "    camera: Some((eye: (0.0, 70.0, 300.0), target: (0.0, 0.0, 20.0), fov_deg: 45.0)),"
    )?;
    writeln!(s, "    light: (direction: (0.4, 1.0, 0.3), ambient: 0.4),")?;
    writeln!(s, "    background: Some((0.55, 0.62, 0.72)),")?;
    writeln!(s, "    volumes: [")?;
    for (name, count, s0, s1, lift) in kinds {
        writeln!(s, "        (asset: \"assets/{name}.billow\", instances: [")?;
        for _ in 0..count {
            let scale = rng.range_f32(s0, s1);
            let (x, z) = (rng.range_f32(-200.0, 200.0), rng.range_f32(-200.0, 200.0));
            writeln!(
                s,
                "            (translate: ({x:.2}, {:.2}, {z:.2}), rotate_y_deg: {:.1}, scale: {scale:.3}),",
                lift * scale,
                rng.range_f32(0.0, 360.0)
            )?;
        }
        writeln!(s, "        ]),")?;
    }
    writeln!(s, "    ],")?;
    writeln!(
        s,
        "    ground: Some((size: 420.0, height: 0.0, color: (0.30, 0.36, 0.22))),"
    )?;
    writeln!(s, ")")?;
    std::fs::write(dir.join("field.ron"), s)?;
    Ok(())
}
