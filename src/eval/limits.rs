//! The limits of `billow eval`'s view parameters, declared once: the CLI's parser
//! (`--size`, `--distances`, `--spacing`) and [`super::evaluate()`] check them.

/// The largest image side of a view, in pixels (`--size`).
pub const MAX_IMAGE_SIDE: u32 = 4096;

/// The largest distance factor of a view (`--distances`), in framed distances.
pub const MAX_DISTANCE_FACTOR: f32 = 1000.0;

/// The smallest and largest factor of a spacing (`--spacing adaptive:B|uniform:V`).
pub const SPACING_FACTOR: (f32, f32) = (0.01, 100.0);

/// Whether `n` is a valid image side ([`MAX_IMAGE_SIDE`]).
pub fn image_side_ok(n: u32) -> bool {
    (1..=MAX_IMAGE_SIDE).contains(&n)
}

/// Whether `f` is a valid distance factor: finite, above 0, at most
/// [`MAX_DISTANCE_FACTOR`].
pub fn distance_factor_ok(f: f32) -> bool {
    f.is_finite() && f > 0.0 && f <= MAX_DISTANCE_FACTOR
}

/// Whether `v` is a valid spacing factor ([`SPACING_FACTOR`]).
pub fn spacing_factor_ok(v: f32) -> bool {
    v.is_finite() && (SPACING_FACTOR.0..=SPACING_FACTOR.1).contains(&v)
}
