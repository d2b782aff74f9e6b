//! `billow compare` through the real binary: identical images give zero error, a known
//! difference gives the expected RMSE, a diff image is written, and different sizes or an
//! unreadable file are one-line errors with exit code 4 / 3.

mod common;

use common::run;

fn write(dir: &std::path::Path, name: &str, w: u32, h: u32, px: [u8; 4]) {
    image::RgbaImage::from_pixel(w, h, image::Rgba(px))
        .save(dir.join(name))
        .unwrap();
}

#[test]
fn compare_reports_errors_and_refuses_mismatched_images() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "a.png", 8, 4, [255, 255, 255, 255]);
    write(d, "b.png", 8, 4, [255, 255, 255, 255]);
    write(d, "c.png", 8, 4, [0, 0, 0, 255]);
    write(d, "small.png", 4, 4, [0, 0, 0, 255]);

    let r = run(&["compare", "a.png", "b.png", "--json"], d);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(v["error"]["rmse"].as_f64(), Some(0.0));
    assert_eq!(v["error"]["flip"].as_f64(), Some(0.0));

    // White against black, both opaque: RGB differ by 1, alpha by 0 → RMSE √(3/4).
    let r = run(
        &["compare", "a.png", "c.png", "--json", "--diff", "d.png"],
        d,
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    let rmse = v["error"]["rmse"].as_f64().unwrap();
    assert!((rmse - 0.75f64.sqrt()).abs() < 1e-6, "{rmse}");
    let diff = image::open(d.join("d.png")).unwrap();
    assert_eq!((diff.width(), diff.height()), (24, 4));

    let r = run(&["compare", "a.png", "small.png"], d);
    assert_eq!(r.code, Some(4));
    let line = r.error_line().unwrap_or_else(|e| panic!("{e}"));
    assert!(
        line.contains("small.png") && line.contains("same size"),
        "{line}"
    );

    let r = run(&["compare", "a.png", "missing.png"], d);
    assert_eq!(r.code, Some(3));
    let line = r.error_line().unwrap_or_else(|e| panic!("{e}"));
    assert!(line.contains("missing.png"), "{line}");
}
