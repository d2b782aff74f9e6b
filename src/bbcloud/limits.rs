//! What [`estimate`](super::estimate) lets a caller decide before the plane search: atlases
//! over [`MAX_ATLAS_BYTES`] are refused ([`Estimate::check_atlases`]), and a search
//! expected to take longer than [`SLOW_SEARCH_SECONDS`] is worth a warning
//! ([`Estimate::slow_search`]).

use super::{BbcloudOptions, Estimate, MAX_ATLAS_BYTES};

/// A plane search [`estimate`](super::estimate) expects to take longer than this, in seconds, is worth a
/// warning before it starts ([`Estimate::slow_search`]; `billow bbcloud` prints one).
pub const SLOW_SEARCH_SECONDS: f64 = 60.0;

/// Atlases an [`Estimate`] expects over [`MAX_ATLAS_BYTES`]: the bake is refused before
/// the plane search ([`Estimate::check_atlases`]). The message names the options that
/// shrink the atlases as `billow bbcloud`'s flags.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AtlasOverLimit {
    /// The estimated atlas bytes ([`Estimate::atlas_bytes`]).
    pub bytes: u64,
    /// Whether `bytes` is a lower bound (an explicit `texel_density`).
    pub lower_bound: bool,
}

impl std::fmt::Display for AtlasOverLimit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the atlases would take {}about {:.0} MiB (peak memory about 3x that), more than \
             the limit of {:.0} MiB; lower --atlas-size, --texel-density, --lods or \
             --mip-levels (nothing was baked)",
            if self.lower_bound { "at least " } else { "" },
            mib(self.bytes),
            mib(MAX_ATLAS_BYTES)
        )
    }
}

impl std::error::Error for AtlasOverLimit {}

impl AtlasOverLimit {
    /// The field of [`BbcloudOptions`] that set the atlases' size: `texel_density` when
    /// given, else `atlas_size`.
    pub fn option(&self) -> &'static str {
        if self.lower_bound {
            "texel_density"
        } else {
            "atlas_size"
        }
    }
}

/// Bytes in MiB, as the messages say them.
fn mib(bytes: u64) -> f64 {
    bytes as f64 / f64::from(1u32 << 20)
}

impl Estimate {
    /// Refuses atlases over [`MAX_ATLAS_BYTES`] before any heavy work (`opts` are the
    /// options the estimate was made for: with a `texel_density` the bytes are a lower
    /// bound). [`bake()`](super::bake()) checks the exact size again after the plane search.
    pub fn check_atlases(&self, opts: &BbcloudOptions) -> Result<(), AtlasOverLimit> {
        if self.atlas_bytes > MAX_ATLAS_BYTES {
            Err(AtlasOverLimit {
                bytes: self.atlas_bytes,
                lower_bound: opts.texel_density.is_some(),
            })
        } else {
            Ok(())
        }
    }

    /// Whether the plane search is expected to take longer than [`SLOW_SEARCH_SECONDS`].
    pub fn slow_search(&self) -> bool {
        self.search_seconds > SLOW_SEARCH_SECONDS
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bbcloud::TESTS_PER_SECOND;

    fn cost(atlas_bytes: u64, search_seconds: f64) -> Estimate {
        Estimate {
            foliage_triangles: 1,
            billboards: 1,
            atlas_bytes,
            search_tests: search_seconds * TESTS_PER_SECOND,
            search_seconds,
        }
    }

    #[test]
    fn atlases_over_the_limit_are_refused_before_the_bake() {
        let opts = BbcloudOptions::default();
        assert_eq!(cost(MAX_ATLAS_BYTES, 0.0).check_atlases(&opts), Ok(()));
        let e = cost(MAX_ATLAS_BYTES + 1, 0.0)
            .check_atlases(&opts)
            .unwrap_err();
        assert_eq!(
            (e.bytes, e.lower_bound, e.option()),
            (MAX_ATLAS_BYTES + 1, false, "atlas_size")
        );
        let dense = BbcloudOptions {
            texel_density: Some(1e4),
            ..BbcloudOptions::default()
        };
        let e = cost(3 << 30, 0.0).check_atlases(&dense).unwrap_err();
        assert_eq!(e.option(), "texel_density");
        assert!(
            e.to_string()
                .starts_with("the atlases would take at least about 3072 MiB"),
            "{e}"
        );
        assert!(e.to_string().contains("the limit of 1024 MiB"), "{e}");
    }

    #[test]
    fn a_search_over_the_threshold_is_slow() {
        assert!(!cost(0, SLOW_SEARCH_SECONDS).slow_search());
        assert!(cost(0, SLOW_SEARCH_SECONDS + 1.0).slow_search());
    }
}
