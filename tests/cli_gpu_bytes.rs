//! GPU bytes in every report (issue 38, item 6): `voxelize`, `bbcloud`, `info` and `eval`
//! print what `billow view` holds on the GPU for the asset, with and without BC7 sampling
//! (`billow_core::gpu_memory`; `viewer/tests/gpu_memory.rs` checks those figures against
//! the textures the viewer makes), and every report gives the same figures for the same
//! file. A BC7 volume is a byte a texel where blocks are sampled and eight decoded
//! (`Rgba16Float` in extinction space); with normals, four more a texel either way
//! (`Rgba8Snorm`).

mod common;

use billow_core::gpu_memory::{cloud_gpu_bytes, volume_gpu_bytes};
use billow_format::{mip_dims, CloudAsset, VolumeAsset};
use common::*;

fn json(r: &Run, what: &str) -> serde_json::Value {
    assert_eq!(r.code, Some(0), "{what}: {}", r.stderr);
    serde_json::from_str(&r.stdout).unwrap_or_else(|e| panic!("{what}: {e}: {}", r.stdout))
}

fn pair(v: &serde_json::Value) -> (u64, u64) {
    (
        v["gpu_bytes"].as_u64().expect("gpu_bytes"),
        v["gpu_bytes_no_bc"].as_u64().expect("gpu_bytes_no_bc"),
    )
}

#[test]
fn every_report_gives_the_gpu_bytes_of_the_asset() {
    let dir = tempfile::tempdir().unwrap();
    let oak = repo().join("fixtures/oak/eztree_oak_medium.gltf");
    let oak = oak.to_str().unwrap();
    let d = dir.path();

    // A BC7 volume with normals, and a raw one without.
    let v = json(
        &run(
            &[
                "voxelize",
                oak,
                "-o",
                "v.billow",
                "--res",
                "32",
                "--normals",
                "on",
                "--json",
            ],
            d,
        ),
        "voxelize",
    );
    let asset = VolumeAsset::read(&d.join("v.billow")).unwrap();
    let texels: u64 = (0..asset.levels.len() as u32)
        .map(|l| {
            mip_dims(asset.level_dims(0), l)
                .iter()
                .map(|&x| u64::from(x))
                .product::<u64>()
        })
        .sum();
    let blocks: u64 = (0..asset.levels.len() as u32)
        .map(|l| {
            let m = mip_dims(asset.level_dims(0), l);
            billow_format::bc7_len(m[0], m[1], m[2])
        })
        .sum();
    // Colour: BC7 blocks, or 8 bytes a texel decoded; normals 4 bytes a texel (Rgba8Snorm).
    assert_eq!(pair(&v), (blocks + 4 * texels, 12 * texels), "{v}");
    let g = volume_gpu_bytes(&asset, true);
    assert_eq!(pair(&v), (g.with_bc, g.without_bc));
    let i = json(&run(&["info", "v.billow", "--json"], d), "info");
    assert_eq!(pair(&i), pair(&v), "info agrees with voxelize");
    let e = json(
        &run(
            &[
                "eval",
                oak,
                "v.billow",
                "--views=+x",
                "--size",
                "32x32",
                "--json",
            ],
            d,
        ),
        "eval",
    );
    assert_eq!(pair(&e), pair(&v), "eval agrees with voxelize");
    let r = run(
        &[
            "voxelize",
            oak,
            "-o",
            "raw.billow",
            "--res",
            "32",
            "--compress",
            "none",
        ],
        d,
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(
        r.stderr.contains("GPU textures: "),
        "the summary names it: {}",
        r.stderr
    );
    let raw = VolumeAsset::read(&d.join("raw.billow")).unwrap();
    let i = json(&run(&["info", "raw.billow", "--json"], d), "info raw");
    let (a, b) = pair(&i);
    assert_eq!(a, b, "raw: the same with or without BC7");
    assert_eq!(a, volume_gpu_bytes(&raw, false).without_bc);

    // A cloud.
    let c = json(
        &run(
            &[
                "bbcloud", oak, "-o", "c.billow", "--preset", "draft", "--json",
            ],
            d,
        ),
        "bbcloud",
    );
    let cloud = CloudAsset::read(&d.join("c.billow")).unwrap();
    let g = cloud_gpu_bytes(&cloud, true);
    assert_eq!(pair(&c), (g.with_bc, g.without_bc), "{c}");
    assert!(g.with_bc < g.without_bc);
    let i = json(&run(&["info", "c.billow", "--json"], d), "info cloud");
    assert_eq!(pair(&i), pair(&c), "info agrees with bbcloud");
    let r = run(&["info", "c.billow"], d);
    assert!(
        r.stdout.contains("gpu:      GPU textures: "),
        "{}",
        r.stdout
    );
}
