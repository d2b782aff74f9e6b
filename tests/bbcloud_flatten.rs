//! Billboards keep the coverage of the leaves they replace (issue 38, item 3): a leaf
//! tilted by θ from its billboard keeps `cos θ` of its area when projected onto it (the
//! paper's flattening), all of it when turned into the plane (`Flatten::Unfold`, the
//! default). The bundled oak's cloud (one level, the draft preset's ε 0.08, whose slabs
//! take leaves tilted far from their plane) judged by `billow::eval::evaluate` against the
//! ray-traced mesh over the six axis views at the framed distance: unfolded within
//! [`TOLERANCE`] of the mesh's coverage, projected well below it (the check can fail).

use billow::bbcloud::{bake, BbcloudOptions, Flatten};
use billow::eval::evaluate::{evaluate, Asset, EvaluateHooks, EvaluateOptions};
use billow::eval::suite::spec;
use billow::import::{import, ImportOptions};
use glam::Vec3;

/// Largest |coverage difference| of the unfolded cloud against the mesh.
const TOLERANCE: f64 = 0.06;
/// The projected cloud must be at least this much thinner than the mesh.
const PROJECTED_DEFICIT: f64 = 0.08;

fn coverage(flatten: Flatten) -> f64 {
    let oak = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fixtures/oak/eztree_oak_medium.gltf"
    );
    let scene = import(oak.as_ref(), &ImportOptions::default())
        .expect("the oak")
        .scene;
    let opts = BbcloudOptions {
        epsilon: 0.08,
        samples: 100,
        lods: 1,
        atlas_size: 512,
        flatten,
        ..BbcloudOptions::default()
    };
    let (cloud, _) = bake(&scene, &opts, "test", None, &|_, _| {}).expect("bake");
    let axes = [
        ("+x", Vec3::X),
        ("-x", Vec3::NEG_X),
        ("+y", Vec3::Y),
        ("-y", Vec3::NEG_Y),
        ("+z", Vec3::Z),
        ("-z", Vec3::NEG_Z),
    ];
    let options = EvaluateOptions {
        width: 96,
        height: 96,
        reference_per_axis: 2,
        views: axes.iter().map(|&(n, d)| spec(n, d, 1.0)).collect(),
        ..EvaluateOptions::default()
    };
    let e = evaluate(
        &scene,
        &Asset::Cloud(cloud),
        &options,
        &mut EvaluateHooks::default(),
    )
    .expect("evaluate");
    e.levels[0].mean.coverage_rel_diff
}

#[test]
fn unfolded_billboards_keep_the_leaves_coverage_projected_ones_do_not() {
    let unfolded = coverage(Flatten::Unfold);
    let projected = coverage(Flatten::Project);
    eprintln!(
        "coverage against the mesh: unfolded {:+.1} %, projected {:+.1} %",
        100.0 * unfolded,
        100.0 * projected
    );
    assert!(
        unfolded.abs() <= TOLERANCE,
        "unfolded cloud: coverage {:+.1} % against the mesh (tolerance ±{:.0} %)",
        100.0 * unfolded,
        100.0 * TOLERANCE
    );
    assert!(
        projected <= -PROJECTED_DEFICIT,
        "projected cloud: coverage {:+.1} %, expected at least {:.0} % below the mesh",
        100.0 * projected,
        100.0 * PROJECTED_DEFICIT
    );
}
