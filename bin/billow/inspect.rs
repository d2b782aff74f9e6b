//! `billow inspect MESH [--json] [--strict]`: an artist's first sanity check of a mesh.

use std::path::PathBuf;

use billow::import::{import, ImportOptions};
use billow::inspect::inspect;

use crate::exit::{CliError, Code};
use crate::output::{print_json, warn};
use crate::Ctx;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The mesh to import: .gltf, .glb or .obj (+ .mtl).
    mesh: PathBuf,
    /// Print a machine-readable JSON report on stdout instead of text.
    #[arg(long)]
    json: bool,
    /// Treat warnings (missing textures, skipped primitives) as errors.
    #[arg(long)]
    strict: bool,
}

pub fn run(args: Args, ctx: &Ctx) -> Result<(), CliError> {
    let opts = ImportOptions {
        strict: args.strict,
    };
    let imported = import(&args.mesh, &opts).map_err(|e| CliError::new(Code::from(&e), &e))?;
    let report = inspect(&imported, &args.mesh);
    if args.json {
        print_json(&report)?;
    } else {
        for w in &imported.report.warnings {
            warn(ctx, &format!("{}: {}", args.mesh.display(), w.message));
        }
        outln!("{report}");
    }
    Ok(())
}
