//! billow: bakes meshes into image-based level-of-detail assets.
pub mod bbcloud;
pub mod bvh;
pub mod camera;
pub mod compress;
pub mod emptyspace;
pub mod eval;
pub mod export;
pub mod import;
pub mod inspect;
pub mod noise_volume;
pub mod presets;
pub mod procgen;
pub mod provenance;
pub mod rng;
pub mod scene;
pub(crate) mod shade;
pub mod shell;
pub mod texture;
pub mod voxelize;

/// For unit tests that cannot run on this machine (no AVX2, ...): `SKIP: <test>: <reason>`
/// on stderr, or a failure under CI (`CI` set) or `BILLOW_REQUIRE=all` — the contract of
/// `tests/common::skip`. Test builds only: the library itself never prints.
#[cfg(test)]
pub(crate) fn test_skip(test: &str, reason: &str) {
    let required = std::env::var_os("CI").is_some()
        || std::env::var("BILLOW_REQUIRE").is_ok_and(|v| v == "all");
    assert!(
        !required,
        "{test}: {reason} (required under CI / BILLOW_REQUIRE=all)"
    );
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "SKIP: {test}: {reason}");
}
