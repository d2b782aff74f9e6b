//! The steps the baking commands share (voxelize, bbcloud, shell, emptyspace): their
//! `--preset` and `--compress`, the outputs refused before any work, the import checked
//! against the outputs, and the summary printed at the end.

use std::path::Path;

use billow::compress::Compression;
use billow::import::{ImportError, Imported};
use billow::presets::{Preset, Source};
use serde::Serialize;

use crate::depfile;
use crate::exit::{usage, CliError, Code};
use crate::output::{
    print_json, refuse_clobbering, refuse_clobbering_read, refuse_file_as_folder, warn,
};
use crate::target::TargetSummary;
use crate::Ctx;

/// `--preset NAME`.
pub fn parse_preset(name: Option<&str>) -> Result<Option<Preset>, CliError> {
    name.map(str::parse::<Preset>)
        .transpose()
        .map_err(|e| usage("--preset", e))
}

/// `--compress bc|none`.
pub fn parse_compress(s: &str) -> Result<Compression, CliError> {
    s.parse().map_err(|e| usage("--compress", e))
}

/// Refuses, before any work, `outputs` that would replace `input` or each other, a
/// `folder` output (`(flag, dir)`) that is a file, and with `depfile` any path a Makefile
/// rule cannot hold (the outputs, the input and `also_named`).
pub fn refuse_outputs(
    input: &Path,
    outputs: &[(&str, &Path)],
    folder: Option<(&str, &Path)>,
    depfile: Option<&Path>,
    also_named: Option<&Path>,
) -> Result<(), CliError> {
    refuse_clobbering(&[input], outputs)?;
    if let Some((flag, dir)) = folder {
        refuse_file_as_folder(flag, dir)?;
    }
    let mut named: Vec<&Path> = outputs.iter().map(|(_, p)| *p).collect();
    named.push(input);
    named.extend(also_named);
    depfile::check(depfile, &named)
}

/// The mesh `input` (shown as `shown`) as imported: refused when an output would replace a
/// file it read, its warnings printed.
pub fn imported(
    input: &Path,
    shown: &str,
    result: Result<Imported, ImportError>,
    outputs: &[(&str, &Path)],
    ctx: &Ctx,
) -> Result<Imported, CliError> {
    let imported = result.map_err(|e| CliError::new(Code::from(&e), &e))?;
    refuse_clobbering_read(input, &imported.report.files, outputs)?;
    for w in &imported.report.warnings {
        warn(ctx, &format!("{shown}: {}", w.message));
    }
    Ok(imported)
}

/// Where a setting came from as the summary says it: with `--target-error`, the search.
pub fn settings_source(target: Option<&TargetSummary>, s: Source) -> Source {
    if target.is_some() {
        Source::Target
    } else {
        s
    }
}

/// The preset the settings came from: with `--target-error`, the chosen one's.
pub fn settings_preset(target: Option<&TargetSummary>, preset: Option<Preset>) -> Option<Preset> {
    target.map_or(preset, |t| t.chosen_preset)
}

/// Prints a bake's summary: `--target-error`'s choice on stderr, then `summary` as JSON on
/// stdout with `json`, else (not `--quiet`) `text`'s lines on stderr.
pub fn print_summary<T: Serialize>(
    ctx: &Ctx,
    json: bool,
    target: Option<&TargetSummary>,
    summary: &T,
    text: impl FnOnce(),
) -> Result<(), CliError> {
    if let (Some(t), false) = (target, ctx.quiet) {
        eprintln!("{}", t.line());
    }
    if json {
        print_json(summary)?;
    } else if !ctx.quiet {
        text();
    }
    Ok(())
}
