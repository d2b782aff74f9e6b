//! The `billow` command line: argument parsing, progress, messages and exit codes.
//! All the work happens in the `billow` library; this binary only talks to the user.

#[macro_use]
mod out;

mod alloc;
mod bbcloud;
mod compare;
mod depfile;
mod emptyspace;
mod eval;
mod exit;
mod info;
mod inspect;
mod lod_sweep;
mod output;
mod progress;
mod shell;
mod staged;
mod view;
mod view_load;
mod view_steps;
mod voxelize;
mod voxelize_bake;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use crate::exit::CliError;

#[global_allocator]
static ALLOC: alloc::Allocator = alloc::Allocator;

/// billow bakes meshes into image-based level-of-detail assets.
#[derive(Parser, Debug)]
#[command(name = "billow", version, about, long_about = None)]
pub struct Cli {
    /// Print nothing but errors (no warnings, no progress).
    #[arg(long, short, global = true)]
    quiet: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Import a mesh (glTF, GLB, OBJ) and report what billow sees: triangles, materials, textures, bounds.
    Inspect(inspect::Args),
    /// Describe a .billow asset: version, kind, header, chunks and their checksums.
    Info(info::Args),
    /// Bake a mesh into a volumetric billboard: six-direction slices, composited MIPs, combined.
    Voxelize(voxelize::Args),
    /// Cover a surface mesh with a tileable volume: one prism cell per triangle (volumetric textures).
    Shell(shell::Args),
    /// Bake a mesh's foliage into a stochastic billboard cloud (+ LODs); the rest stays a mesh.
    Bbcloud(bbcloud::Args),
    /// Compare a volume asset with its source mesh: reference vs asset renders, errors and timings per view.
    Eval(eval::Args),
    /// Compare two images (e.g. screenshots): RMSE/PSNR, alpha coverage, SSIM, FLIP; --diff writes a heatmap.
    Compare(compare::Args),
    /// View a scene (.ron), volume asset or mesh with the GPU viewer; --headless --screenshot renders a PNG.
    #[command(after_help = view::WINDOW_HELP)]
    View(view::Args),
    /// Remove a volume's empty space: kd-tree boxes packed with aprons into a smaller atlas.
    Emptyspace(emptyspace::Args),
}

/// Things every command may need from the global flags.
pub struct Ctx {
    pub quiet: bool,
}

fn main() -> ExitCode {
    out::install_panic_hook();
    let cli = Cli::parse();
    let ctx = Ctx { quiet: cli.quiet };
    let result: Result<(), CliError> = match cli.command {
        Command::Inspect(a) => inspect::run(a, &ctx),
        Command::Info(a) => info::run(a, &ctx),
        Command::Voxelize(a) => voxelize::run(a, &ctx),
        Command::Shell(a) => shell::run(a, &ctx),
        Command::Bbcloud(a) => bbcloud::run(a, &ctx),
        Command::Eval(a) => eval::run(a, &ctx),
        Command::Compare(a) => compare::run(a, &ctx),
        Command::View(a) => view::run(a, &ctx),
        Command::Emptyspace(a) => emptyspace::run(a, &ctx),
    };
    // The command's own error first; else a failure to write stdout (exit 7).
    match result.and_then(|()| out::finish()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            use std::io::Write;
            // A closed stderr must not turn this into a panic.
            let _ = writeln!(std::io::stderr().lock(), "error: {}", e.message);
            ExitCode::from(e.code as u8)
        }
    }
}
