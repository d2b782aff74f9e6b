//! What a check that cannot run does (feature `test-support`, which billow's tests and
//! examples, the CLI's tests and the viewer's tests turn on; never in the binary, and the
//! library itself never prints): it says so on stderr, `SKIP: <name>: <reason>`, written
//! straight to the process's stderr so that it shows even though a test harness captures
//! `eprintln!`, and it fails instead under CI (`CI` set) or `BILLOW_REQUIRE=all`, where
//! every resource it needs must be there. One rule for every test and report generator.
//!
//! Also the fixtures both the root tests (tests/) and the viewer's (viewer/tests/) draw,
//! so that a GPU test and its CPU twin build one scene: the thin layer ([`thin_layer`]),
//! the oak before a wall ([`oak_wall`]), boxes as prisms ([`box_prisms_z`]), and the
//! measure of a lit ball ([`mean_around`]).

use std::io::Write;
use std::path::PathBuf;

use billow_format::Prism;

pub mod oak_wall;
pub mod thin_layer;

/// The repository root (the library's package root), whichever package's test asks: the
/// CLI's tests run with their own manifest directory, bin/billow.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A check that cannot run here: `SKIP` on stderr, or a panic under CI /
/// `BILLOW_REQUIRE=all`.
pub fn skip(name: &str, reason: &str) {
    skip_unless_required(name, None, reason)
}

/// [`skip`] for a check that needs an external `tool` a machine may lack for good (e.g.
/// Khronos' `ktx`, which Debian does not package): it may still skip under CI /
/// `BILLOW_REQUIRE=all` when the tool is named in `BILLOW_OPTIONAL` (a comma list, e.g.
/// `BILLOW_OPTIONAL=ktx`), and says so on stderr all the same.
pub fn skip_tool(name: &str, tool: &str, reason: &str) {
    skip_unless_required(name, Some(tool), reason)
}

fn skip_unless_required(name: &str, tool: Option<&str>, reason: &str) {
    let waived = tool.is_some_and(|t| {
        std::env::var("BILLOW_OPTIONAL").is_ok_and(|v| v.split(',').any(|x| x.trim() == t))
    });
    let required = !waived
        && (std::env::var_os("CI").is_some()
            || std::env::var("BILLOW_REQUIRE").is_ok_and(|v| v == "all"));
    assert!(
        !required,
        "{name}: {reason} (required under CI / BILLOW_REQUIRE=all)"
    );
    let _ = writeln!(std::io::stderr(), "SKIP: {name}: {reason}");
}

/// The positions of the two prisms (vertical edges along z: bottom z = `a[2]`, top z =
/// `b[2]`) tiling the box `[a, b]`, split along its `(a.x, a.y)`–`(b.x, b.y)` diagonal.
pub fn box_positions_z(a: [f32; 3], b: [f32; 3]) -> [[[f32; 3]; 6]; 2] {
    let c = |x: f32, y: f32, z: f32| [x, y, z];
    [
        [
            c(a[0], a[1], a[2]),
            c(b[0], a[1], a[2]),
            c(b[0], b[1], a[2]),
            c(a[0], a[1], b[2]),
            c(b[0], a[1], b[2]),
            c(b[0], b[1], b[2]),
        ],
        [
            c(a[0], a[1], a[2]),
            c(b[0], b[1], a[2]),
            c(a[0], b[1], a[2]),
            c(a[0], a[1], b[2]),
            c(b[0], b[1], b[2]),
            c(a[0], b[1], b[2]),
        ],
    ]
}

/// The prisms of [`box_positions_z`], uvw = position mapped through `uvw_of` (the
/// library's own boxes, `billow::voxelize::box_prisms`, are extruded along y).
pub fn box_prisms_z(a: [f32; 3], b: [f32; 3], uvw_of: impl Fn([f32; 3]) -> [f32; 3]) -> Vec<Prism> {
    box_positions_z(a, b)
        .into_iter()
        .map(|pos| Prism {
            pos,
            uvw: pos.map(&uvw_of),
        })
        .collect()
}

/// Mean of the 3×3 pixels of `img` around the projection of the world point `p` (the
/// CPU and GPU shading tests measure a lit ball there).
pub fn mean_around(
    img: &crate::eval::ImageF32,
    cam: &billow_core::camera::Camera,
    p: glam::Vec3,
) -> glam::Vec4 {
    let (x, y) = cam
        .view_to_pixel(billow_core::camera::to_view(&cam.view(), p))
        .expect("in front of the camera");
    let (x, y) = (x as i64, y as i64);
    let mut acc = glam::Vec4::ZERO;
    for dy in -1..=1 {
        for dx in -1..=1 {
            acc += img.data[(x + dx) as usize + img.width as usize * (y + dy) as usize];
        }
    }
    acc / 9.0
}

/// The largest difference of any channel of any pixel between two images of one size.
pub fn max_abs_diff(a: &crate::eval::ImageF32, b: &crate::eval::ImageF32) -> f32 {
    a.data
        .iter()
        .zip(&b.data)
        .map(|(p, q)| (*p - *q).abs().max_element())
        .fold(0.0, f32::max)
}

/// The ray-traced reference of `scene` from each camera, 3 × 3 stratified samples per
/// pixel (the billboard-cloud tests' and pictures' renders).
pub fn reference_renders(
    scene: &crate::scene::Scene,
    cams: &[billow_core::camera::Camera],
) -> Vec<crate::eval::ImageF32> {
    let r = crate::eval::reference::ReferenceRenderer::new(scene);
    cams.iter()
        .map(|c| {
            r.render(
                c,
                crate::eval::reference::Sampling::Stratified { per_axis: 3 },
            )
            .expect("render")
        })
        .collect()
}
