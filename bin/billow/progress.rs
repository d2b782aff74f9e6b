//! Progress accounting: where each stage a library reports falls on the one bar of a
//! command, and a bar that only moves forward and ends at 100 %.
//!
//! The bakers report `(stage, fraction of that stage)` from several threads, in no
//! particular order; several stages restart their fraction (one plane search per LOD).
//! [`Monotone`] keeps the largest position seen, so the bar never goes backwards, and
//! [`Monotone::finish`] shows 100 % before the bar is cleared.

use std::sync::Mutex;

use indicatif::ProgressBar;

/// Positions on the bar (per mille).
pub const LEN: u64 = 1000;

pub struct Monotone {
    bar: ProgressBar,
    pos: Mutex<u64>,
}

impl Monotone {
    /// `bar` must have length [`LEN`].
    pub fn new(bar: ProgressBar) -> Self {
        Monotone {
            bar,
            pos: Mutex::new(0),
        }
    }

    /// Moves the bar to `fraction` of the whole command (0..=1), unless it is already
    /// further; `message` names the stage.
    pub fn set(&self, fraction: f64, message: impl FnOnce() -> String) {
        let p = position(fraction);
        let mut pos = self.pos.lock().unwrap_or_else(|e| e.into_inner());
        if p >= *pos {
            *pos = p;
            self.bar.set_message(message());
            self.bar.set_position(p);
        }
    }

    /// Shows 100 % and clears the bar.
    pub fn finish(&self) {
        *self.pos.lock().unwrap_or_else(|e| e.into_inner()) = LEN;
        self.bar.set_position(LEN);
        self.bar.finish_and_clear();
    }

    /// The position the bar shows (for tests).
    #[cfg(test)]
    fn position(&self) -> u64 {
        *self.pos.lock().unwrap()
    }
}

fn position(fraction: f64) -> u64 {
    let f = if fraction.is_finite() {
        fraction.clamp(0.0, 1.0)
    } else {
        0.0
    };
    (f * LEN as f64).round() as u64
}

/// `voxelize`: the six directions (each rasterized, then its pyramid built) take 85 %,
/// `Rasterize` and `Mip` report fractions of directions done; then combine and quantize.
pub fn voxelize_fraction(stage: billow::voxelize::Stage, f: f32) -> f64 {
    use billow::voxelize::Stage;
    let f = f64::from(f.clamp(0.0, 1.0));
    let (lo, span) = match stage {
        Stage::Rasterize | Stage::Mip => (0.0, 0.85),
        Stage::Combine => (0.85, 0.12),
        Stage::Quantize => (0.97, 0.03),
    };
    lo + span * f
}

/// `bbcloud` with `lods` levels: the plane search takes half the bar, shared evenly by
/// the levels (each reports its own 0..1, so the level places it); rendering the
/// billboards 40 %, packing the atlases 10 %.
pub fn bbcloud_fraction(stage: billow::bbcloud::Stage, f: f32, lods: u32) -> f64 {
    use billow::bbcloud::Stage;
    let f = f64::from(f.clamp(0.0, 1.0));
    match stage {
        Stage::Search { level } => {
            let n = f64::from(lods.max(1));
            let l = f64::from(level.min(lods.max(1) - 1));
            0.5 * (l + f) / n
        }
        Stage::Render => 0.5 + 0.4 * f,
        Stage::Pack => 0.9 + 0.1 * f,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use billow::bbcloud::Stage as B;

    /// What `bbcloud` reports for 3 LODs: each level's search from 0 to 1, then the
    /// render and pack counters (pack from parallel threads, out of order). The old
    /// accounting put every level's search on the same half of the bar, so the bar went
    /// back at each new level (28 % → 14 % in the report), and it ended short of 100 %.
    #[test]
    fn bbcloud_bar_only_moves_forward_and_ends_full() {
        let bar = Monotone::new(ProgressBar::hidden());
        let mut events = Vec::new();
        for level in 0..3 {
            for k in 0..=10 {
                events.push((B::Search { level }, k as f32 / 10.0));
            }
        }
        for k in 1..=20 {
            events.push((B::Render, k as f32 / 20.0));
        }
        for l in [2, 0, 1] {
            events.push((B::Pack, l as f32 / 3.0));
        }
        let (mut last, mut shown) = (0.0, 0);
        for (stage, f) in events {
            let x = bbcloud_fraction(stage, f, 3);
            // The search levels and the render counter map forward by themselves; the
            // pack reports come from parallel threads, so only the bar keeps them in order.
            if !matches!(stage, B::Pack) {
                assert!(x >= last - 1e-12, "{stage:?} {f}: {x} after {last}");
                last = x;
            }
            bar.set(x, String::new);
            assert!(bar.position() >= shown, "{stage:?} {f}: the bar went back");
            shown = bar.position();
        }
        let before = bar.position();
        assert!(before < LEN, "the last pack report is below 100 %");
        bar.finish();
        assert_eq!(bar.position(), LEN);
    }

    #[test]
    fn monotone_ignores_late_reports() {
        let bar = Monotone::new(ProgressBar::hidden());
        bar.set(0.28, String::new);
        bar.set(0.14, String::new);
        assert_eq!(bar.position(), 280);
        bar.set(f64::NAN, String::new);
        assert_eq!(bar.position(), 280);
        bar.set(0.5, String::new);
        assert_eq!(bar.position(), 500);
    }

    #[test]
    fn voxelize_stages_in_order_reach_the_end() {
        use billow::voxelize::Stage as V;
        let mut last = 0.0;
        for (s, f) in [
            (V::Rasterize, 0.1),
            (V::Mip, 1.0 / 6.0),
            (V::Rasterize, 0.5),
            (V::Mip, 1.0),
            (V::Combine, 0.5),
            (V::Combine, 1.0),
            (V::Quantize, 1.0),
        ] {
            let x = voxelize_fraction(s, f);
            assert!(x >= last, "{s:?} {f}");
            last = x;
        }
        assert!((last - 1.0).abs() < 1e-9);
    }
}
