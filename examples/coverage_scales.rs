//! The optical-depth scale of every MIP level of a bake and what it matched
//! (`Volume::coverage`): `cargo run --release --example coverage_scales -- MESH [RES] [COMBINE]`.

use billow::import::{import, ImportOptions};
use billow::voxelize::{voxelize, CombineFn, Resolution, VoxelizeOptions};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene = import(std::path::Path::new(&args[0]), &ImportOptions::default())
        .unwrap()
        .scene;
    let res: u32 = args.get(1).map_or(128, |r| r.parse().unwrap());
    let combine: CombineFn = args
        .get(2)
        .map_or("opaque", |c| c.as_str())
        .parse()
        .unwrap();
    let opts = VoxelizeOptions {
        resolution: Resolution::Longest(res),
        combine,
        ..VoxelizeOptions::default()
    };
    let v = voxelize(&scene, &opts, &|_, _| {}).unwrap();
    let c = &v.coverage;
    let rel = |a: [f64; 3]| a.map(|x| format!("{x:.0}"));
    println!(
        "mesh {:?}\nlevel 0 before {:?} ({:+.1} %)\nlevel 0 after {:?} ({:+.1} %)\nscales {:?}",
        rel(c.mesh),
        rel(c.level0_before),
        100.0 * (c.level0_before.iter().sum::<f64>() / c.mesh.iter().sum::<f64>() - 1.0),
        rel(c.level0_after),
        100.0 * (c.level0_after.iter().sum::<f64>() / c.mesh.iter().sum::<f64>() - 1.0),
        c.scales
    );
    // Per level, the model's rendered coverage of the stored bytes against the mesh.
    let dims0 = v.grid.dims.map(|d| d as usize);
    let voxel = v.grid.voxel.as_dvec3().to_array();
    for (l, bytes) in v.levels.iter().enumerate() {
        let d = v.grid.level_dims(l as u32).map(|d| d as usize);
        let cols = billow::voxelize::coverage::Columns::from_rgba8(d, bytes);
        let m = billow::voxelize::coverage::Model::new(&cols, dims0, voxel).coverage(1.0);
        println!(
            "level {l} {d:?}: x {:+.1} % y {:+.1} % z {:+.1} %",
            100.0 * (m[0] / c.mesh[0] - 1.0),
            100.0 * (m[1] / c.mesh[1] - 1.0),
            100.0 * (m[2] / c.mesh[2] - 1.0)
        );
    }
}
