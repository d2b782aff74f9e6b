//! The summary of `billow voxelize` (bin/billow/voxelize.rs): what `--json` prints, and
//! the plain-text lines on stderr.

use billow::emptyspace::EmptySpaceStats;
use billow::presets::{Preset, Source};
use serde::Serialize;

use crate::target::TargetSummary;
use crate::voxelize_args::NormalsArg;

#[derive(Serialize)]
pub(crate) struct Seconds {
    pub(crate) import: f64,
    /// `--normals auto`'s judgement: a bake at the judged level's size.
    pub(crate) judge_normals: f64,
    pub(crate) rasterize: f64,
    pub(crate) bake: f64,
    pub(crate) mip: f64,
    pub(crate) combine: f64,
    pub(crate) quantize: f64,
    pub(crate) compress: f64,
    /// With --prune: the empty-space removal.
    pub(crate) prune: f64,
    pub(crate) write: f64,
    pub(crate) total: f64,
}

/// Where the resolved `--res` and `--supersample` came from.
#[derive(Serialize)]
pub(crate) struct SettingsFrom {
    pub(crate) resolution: Source,
    pub(crate) supersample: Source,
}

#[derive(Serialize)]
pub(crate) struct Summary {
    pub(crate) input: String,
    pub(crate) output: String,
    /// The preset the settings came from (with --target-error: the chosen one's).
    pub(crate) preset: Option<Preset>,
    /// The resolved --res.
    pub(crate) resolution: String,
    pub(crate) settings_from: SettingsFrom,
    /// With --target-error: what was tried and chosen.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) target: Option<TargetSummary>,
    pub(crate) dims: [u32; 3],
    pub(crate) mip_count: u32,
    pub(crate) combine: String,
    pub(crate) supersample: u32,
    pub(crate) normals: bool,
    /// The stored normals are the diagonal of their second moment (`--normals moments`, or
    /// `auto` on a thin or fuzzy surface).
    pub(crate) normal_moments: bool,
    /// `--normals auto`: the coherence the choice was made on (see docs/voxelize.md).
    pub(crate) normal_coherence: Option<f32>,
    pub(crate) compress: String,
    pub(crate) triangles: usize,
    pub(crate) non_empty_voxels: u64,
    pub(crate) fragments: u64,
    pub(crate) bytes: u64,
    /// Texture bytes `billow view` holds on a device that samples BC7 blocks, and on one
    /// that does not (`billow_core::gpu_memory`; equal for `--compress none`).
    pub(crate) gpu_bytes: u64,
    pub(crate) gpu_bytes_no_bc: u64,
    /// With --prune: what the empty-space removal did (as `billow emptyspace --json`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) prune: Option<EmptySpaceStats>,
    /// The estimate `--memory-limit` was checked against (docs/voxelize.md, "Memory").
    pub(crate) estimated_peak_memory_bytes: u64,
    pub(crate) peak_memory_bytes: Option<u64>,
    pub(crate) seconds: Seconds,
    pub(crate) warnings: Vec<String>,
}

/// The summary on stderr: the output, its size and time, then [`summary_lines`].
pub(crate) fn print_text(s: &Summary, normals: NormalsArg) {
    eprintln!(
        "{}: {}x{}x{} voxels, {} MIP levels, {} non-empty, {:.1} MiB in {:.2} s",
        s.output,
        s.dims[0],
        s.dims[1],
        s.dims[2],
        s.mip_count,
        s.non_empty_voxels,
        s.bytes as f64 / (1 << 20) as f64,
        s.seconds.total
    );
    for line in summary_lines(s, normals) {
        eprintln!("  {line}");
    }
}

/// What the plain-text summary says below its first line: the settings and where each
/// came from, what `--normals` decided and why, and what `--prune` saved.
fn summary_lines(s: &Summary, normals: NormalsArg) -> Vec<String> {
    use billow::voxelize::toksvig::AUTO_NORMALS_MIN_COHERENCE;
    let from = |src: Source| match src {
        Source::Default => "default",
        Source::Preset => "preset",
        Source::Flag => "flag",
        Source::Target => "--target-error",
    };
    let mut lines = vec![format!(
        "settings: {}--res {} ({}), --supersample {} ({}), --combine {}, --compress {}",
        s.preset
            .map_or(String::new(), |p| format!("--preset {p}: ")),
        s.resolution,
        from(s.settings_from.resolution),
        s.supersample,
        from(s.settings_from.supersample),
        s.combine,
        s.compress
    )];
    const LIT: &str = "viewers light the albedo two-sided, like its mesh";
    lines.push(match (normals, s.normals, s.normal_coherence) {
        (NormalsArg::Auto, true, Some(k)) if k >= AUTO_NORMALS_MIN_COHERENCE => format!(
            "normals: moments (--normals auto; coherence {k:.2} ≥ {AUTO_NORMALS_MIN_COHERENCE}: \
             a closed surface, level 0 kept as baked; {LIT})"
        ),
        (NormalsArg::Auto, true, Some(k)) => format!(
            "normals: moments (--normals auto; coherence {k:.2} < {AUTO_NORMALS_MIN_COHERENCE}: \
             thin or fuzzy, such as foliage, level 0 thinned to the mesh's coverage; {LIT})"
        ),
        (NormalsArg::Auto, true, None) => {
            format!("normals: moments (--normals auto; nothing at the judged level; {LIT})")
        }
        (NormalsArg::Auto, false, _) => {
            "normals: none (--normals auto: given up, see the warning above)".to_string()
        }
        (_, true, _) if s.normal_moments => format!("normals: moments (--normals moments; {LIT})"),
        (_, true, _) => {
            "normals: mean (--normals on: Toksvig's mean normal, lit one-sided)".to_string()
        }
        (_, false, _) => "normals: none (--normals off)".to_string(),
    });
    lines.push(crate::output::gpu_line(s.gpu_bytes, s.gpu_bytes_no_bc));
    if let Some(p) = &s.prune {
        lines.push(if p.kept_whole {
            format!(
                "prune: kept whole ({})",
                p.note.as_deref().unwrap_or("no brick layout was smaller")
            )
        } else {
            format!(
                "prune: texels {:.1} → {:.1} MiB ({:.0} % saved), {} boxes, {} LOD bands",
                p.texel_bytes_before as f64 / (1 << 20) as f64,
                p.texel_bytes_after as f64 / (1 << 20) as f64,
                p.saving * 100.0,
                p.boxes,
                p.bands.len()
            )
        });
    }
    lines
}
