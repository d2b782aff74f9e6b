//! Slice export: PNG (straight alpha sRGB) and EXR (linear premultiplied) round trips.

use billow::export::{decode_texel, srgb_eotf, srgb_oetf, write_slices, ExportError, SliceFormat};
use billow_format::{mip_dims, ColourSpace, Header, Prism, VolumeAsset};

/// A valid premultiplied asset: straight colour × alpha in linear space, then encoded.
fn asset(dims: [u32; 3], mip_count: u32, cs: ColourSpace) -> VolumeAsset {
    let mut seed = 12345u32;
    let mut rnd = move || {
        seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (seed >> 8) as f32 / (1u32 << 24) as f32
    };
    let levels = (0..mip_count)
        .map(|i| {
            let d = mip_dims(dims, i);
            let mut v = Vec::new();
            for k in 0..d[0] * d[1] * d[2] {
                // Include fully transparent and fully opaque texels.
                let a = match k % 7 {
                    0 => 0.0,
                    1 => 1.0,
                    _ => rnd(),
                };
                let a8 = (a * 255.0f32).round() as u8;
                let a = f32::from(a8) / 255.0;
                let enc = |c: f32| {
                    let p = c * a;
                    let e = if cs == ColourSpace::SrgbPremultiplied {
                        srgb_oetf(p)
                    } else {
                        p
                    };
                    (e * 255.0).round() as u8
                };
                v.extend_from_slice(&[enc(rnd()), enc(rnd()), enc(rnd()), a8]);
            }
            v
        })
        .collect();
    VolumeAsset {
        header: Header::volume("test", cs, dims, mip_count, false),
        levels,
        normals: None,
        bands: Vec::new(),
        cells: vec![Prism {
            pos: [[0.0; 3]; 6],
            uvw: [[0.0; 3]; 6],
        }],
    }
}

/// Texel (x, y, z) of `level`.
fn texel(a: &VolumeAsset, level: u32, x: u32, y: u32, z: u32) -> [u8; 4] {
    let d = a.level_dims(level);
    let i = 4 * (x + d[0] * (y + d[1] * z)) as usize;
    a.levels[level as usize][i..i + 4].try_into().unwrap()
}

#[test]
fn png_round_trips_within_one_step() {
    for cs in [
        ColourSpace::SrgbPremultiplied,
        ColourSpace::LinearPremultiplied,
    ] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("new").join("slices"); // created
        let a = asset([7, 5, 4], 2, cs);
        let paths = write_slices(&a, 0, &out, SliceFormat::Png8).unwrap();
        assert_eq!(paths.len(), 4);
        assert_eq!(paths[3], out.join("slice_0003.png"));
        let mut worst = 0i32;
        for (z, p) in paths.iter().enumerate() {
            let img = image::open(p).unwrap().to_rgba8();
            assert_eq!(img.dimensions(), (7, 5));
            for y in 0..5 {
                for x in 0..7 {
                    let want = texel(&a, 0, x, y, z as u32);
                    // Row 0 of the image is the top of the volume (y = h − 1).
                    let px = img.get_pixel(x, 4 - y).0;
                    assert_eq!(px[3], want[3], "alpha is copied");
                    if want[3] == 0 {
                        assert_eq!(px, [0; 4], "alpha 0 → transparent black");
                        continue;
                    }
                    // Re-premultiply in linear space and re-encode.
                    let al = f32::from(px[3]) / 255.0;
                    for c in 0..3 {
                        let straight = srgb_eotf(f32::from(px[c]) / 255.0);
                        let p = straight * al;
                        let e = if cs == ColourSpace::SrgbPremultiplied {
                            srgb_oetf(p)
                        } else {
                            p
                        };
                        let back = (e * 255.0).round() as i32;
                        worst = worst.max((back - i32::from(want[c])).abs());
                    }
                }
            }
        }
        assert!(worst <= 1, "{cs:?}: round trip off by {worst}/255");
    }
}

#[test]
fn png_straight_values_are_what_a_viewer_needs() {
    // Half-transparent mid grey: linear straight 0.5 at alpha 128/255.
    let mut a = asset([1, 1, 1], 1, ColourSpace::SrgbPremultiplied);
    let al = 128.0 / 255.0;
    let p = (srgb_oetf(0.5 * al) * 255.0).round() as u8;
    a.levels[0] = vec![p, p, p, 128];
    let dir = tempfile::tempdir().unwrap();
    let paths = write_slices(&a, 0, dir.path(), SliceFormat::Png8).unwrap();
    let px = image::open(&paths[0]).unwrap().to_rgba8().get_pixel(0, 0).0;
    let want = (srgb_oetf(0.5) * 255.0).round() as u8; // 188
    assert!(
        (i32::from(px[0]) - i32::from(want)).abs() <= 1,
        "{px:?} vs {want}"
    );
    assert_eq!(px[3], 128);
}

#[test]
fn exr_is_linear_premultiplied_float() {
    let a = asset([6, 3, 5], 3, ColourSpace::SrgbPremultiplied);
    let dir = tempfile::tempdir().unwrap();
    let level = 1;
    let d = a.level_dims(level);
    let paths = write_slices(&a, level, dir.path(), SliceFormat::Exr).unwrap();
    assert_eq!(paths.len(), d[2] as usize);
    assert_eq!(paths[0].file_name().unwrap(), "slice_0000.exr");
    for (z, p) in paths.iter().enumerate() {
        let img = exr::prelude::read_first_rgba_layer_from_file(
            p,
            |res, _| (res.width(), vec![[0f32; 4]; res.width() * res.height()]),
            |(w, px), pos, (r, g, b, al): (f32, f32, f32, f32)| {
                px[pos.y() * *w + pos.x()] = [r, g, b, al]
            },
        )
        .unwrap();
        let (w, px) = &img.layer_data.channel_data.pixels;
        assert_eq!(*w, d[0] as usize);
        assert_eq!(px.len(), (d[0] * d[1]) as usize);
        for y in 0..d[1] {
            for x in 0..d[0] {
                let want = decode_texel(a.header.colour_space, texel(&a, level, x, y, z as u32));
                let got = px[(d[1] - 1 - y) as usize * *w + x as usize];
                for c in 0..4 {
                    assert_eq!(got[c], want[c], "texel ({x},{y},{z}) channel {c}");
                }
                assert!(got[0] <= got[3] + 1e-6, "premultiplied: colour ≤ alpha");
            }
        }
    }
}

#[test]
fn level_beyond_mip_count_is_refused() {
    let a = asset([4, 4, 4], 2, ColourSpace::SrgbPremultiplied);
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("never");
    let e = write_slices(&a, 2, &out, SliceFormat::Png8).unwrap_err();
    assert!(
        matches!(
            e,
            ExportError::NoSuchLevel {
                level: 2,
                mip_count: 2,
                ..
            }
        ),
        "{e:?}"
    );
    let msg = e.to_string();
    assert!(msg.contains("level 2") && msg.contains("never"), "{msg}");
    assert!(!out.exists(), "nothing created");
}

#[test]
fn coarsest_level_is_one_slice_of_one_pixel() {
    let a = asset([4, 4, 4], 3, ColourSpace::LinearPremultiplied);
    let dir = tempfile::tempdir().unwrap();
    let paths = write_slices(&a, 2, dir.path(), SliceFormat::Png8).unwrap();
    assert_eq!(paths.len(), 1);
    assert_eq!(
        image::open(&paths[0]).unwrap().to_rgba8().dimensions(),
        (1, 1)
    );
}
