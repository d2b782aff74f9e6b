//! Atlas packing (alignment, no overlap, fill) and MIPs without dark fringes.

use billow::bbcloud::atlas::{compose, mip_chain, pack, Layout};
use billow::bbcloud::bake::Image;
use billow::rng::Pcg32;
use glam::Vec4;

fn layout() -> Layout {
    Layout {
        max_size: 512,
        gutter: 2,
        align: 4,
    }
}

#[test]
fn packing_is_aligned_disjoint_and_dense() {
    let mut rng = Pcg32::seeded(11, 0);
    let sizes: Vec<(u32, u32)> = (0..400)
        .map(|_| (8 + rng.below(60), 8 + rng.below(60)))
        .collect();
    let l = layout();
    let p = pack(&sizes, &l).expect("packs");
    assert!(p.sizes.len() >= 2, "needs several atlases: {:?}", p.sizes);
    let mut boxes = Vec::new();
    for (i, pl) in p.places.iter().enumerate() {
        let (w, h) = sizes[i];
        let (x0, y0) = (pl.x - l.gutter, pl.y - l.gutter);
        assert_eq!(
            (x0 % l.align, y0 % l.align),
            (0, 0),
            "allocation not aligned"
        );
        let (aw, ah) = (
            (w + 2 * l.gutter).div_ceil(l.align) * l.align,
            (h + 2 * l.gutter).div_ceil(l.align) * l.align,
        );
        let (sw, sh) = p.sizes[pl.atlas as usize];
        assert!(x0 + aw <= sw && y0 + ah <= sh, "outside the atlas");
        boxes.push((pl.atlas, x0, y0, x0 + aw, y0 + ah));
    }
    for (i, a) in boxes.iter().enumerate() {
        for b in &boxes[i + 1..] {
            let overlap = a.0 == b.0 && a.1 < b.3 && b.1 < a.3 && a.2 < b.4 && b.2 < a.4;
            assert!(!overlap, "allocations overlap: {a:?} {b:?}");
        }
    }
    for &(w, h) in &p.sizes {
        assert!(w.is_power_of_two() && h.is_power_of_two() && w <= 512 && h <= 512);
    }
    // Full atlases (all but the last) are packed densely.
    let full: u64 = p.sizes[..p.sizes.len() - 1]
        .iter()
        .map(|&(w, h)| u64::from(w * h))
        .sum();
    let used: u64 = boxes
        .iter()
        .filter(|b| (b.0 as usize) < p.sizes.len() - 1)
        .map(|b| u64::from((b.3 - b.1) * (b.4 - b.2)))
        .sum();
    assert!(
        used as f64 / full as f64 > 0.9,
        "fill {}",
        used as f64 / full as f64
    );
}

#[test]
fn mips_have_no_dark_fringes_and_gutters_extrude() {
    // A 6x6 image: an opaque green disc-ish blob on transparent black.
    let green = Vec4::new(0.1, 0.8, 0.2, 1.0);
    let texels: Vec<Vec4> = (0..36)
        .map(|i| {
            let (x, y) = (i % 6, i / 6);
            if (1..5).contains(&x) && (1..5).contains(&y) {
                green
            } else if x == 0 && y == 2 {
                green * 0.5 // half coverage, premultiplied
            } else {
                Vec4::ZERO
            }
        })
        .collect();
    let img = Image {
        width: 6,
        height: 6,
        texels,
    };
    let l = Layout {
        max_size: 64,
        gutter: 2,
        align: 4,
    };
    let p = pack(&[(6, 6), (6, 6)], &l).unwrap();
    let atlases = compose(&[&img, &img], &p, &l);
    let at = &atlases[0];
    // Gutter texel left of (0,2) copies it; the corner gutter copies the corner texel.
    let pl = p.places[0];
    let get = |x: u32, y: u32| at.texels[(y * at.width + x) as usize];
    assert_eq!(get(pl.x - 1, pl.y + 2), green * 0.5);
    assert_eq!(get(pl.x - 2, pl.y - 2), Vec4::ZERO);
    let mips = mip_chain(at.clone(), 32);
    assert_eq!(
        mips.len() as u32,
        32 - at.width.max(at.height).leading_zeros()
    );
    let lut = |b: u8| {
        let c = b as f64 / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    for (k, m) in mips.iter().enumerate() {
        for px in m.chunks_exact(4) {
            let a = px[3] as f64 / 255.0;
            if a < 0.05 {
                continue;
            }
            // Un-premultiplied colour stays green: no darkening towards the edges.
            let (r, g, b) = (lut(px[0]) / a, lut(px[1]) / a, lut(px[2]) / a);
            assert!(
                (g - 0.8).abs() < 0.06 && (r - 0.1).abs() < 0.03 && (b - 0.2).abs() < 0.04,
                "level {k}: {r} {g} {b} a {a}"
            );
            assert!(lut(px[1]) <= a + 1e-6, "premultiplied in linear: g <= a");
        }
    }
}
