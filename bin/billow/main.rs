//! The `billow` command line: argument parsing, progress, messages and exit codes.
//! All the work happens in the `billow` library; this binary only talks to the user.

#[macro_use]
mod stdout;

mod alloc;
mod bake_steps;
mod bbcloud;
mod bbcloud_args;
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
mod signals;
mod staged;
mod target;
mod view;
mod view_args;
mod view_load;
mod view_steps;
mod voxelize;
mod voxelize_args;
mod voxelize_bake;
mod voxelize_summary;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use crate::exit::{CliError, Code};

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
    #[command(allow_negative_numbers = true)]
    Inspect(inspect::Args),
    /// Describe a .billow asset: version, kind, header, chunks and their checksums.
    #[command(allow_negative_numbers = true)]
    Info(info::Args),
    /// Bake a mesh into a volumetric billboard: six-direction slices, composited MIPs, combined.
    #[command(allow_negative_numbers = true)]
    Voxelize(voxelize_args::Args),
    /// Cover a surface mesh with a tileable volume: one prism cell per triangle (volumetric textures).
    #[command(allow_negative_numbers = true)]
    Shell(shell::Args),
    /// Bake a mesh's foliage into a stochastic billboard cloud (+ LODs); the rest stays a mesh.
    #[command(allow_negative_numbers = true)]
    Bbcloud(bbcloud_args::Args),
    /// Compare a volume or billboard-cloud asset with its source mesh: reference vs asset renders, errors and timings per view.
    #[command(allow_negative_numbers = true)]
    Eval(eval::Args),
    /// Compare two images (e.g. screenshots): RMSE/PSNR, alpha coverage, SSIM, FLIP; --diff writes a heatmap.
    #[command(allow_negative_numbers = true)]
    Compare(compare::Args),
    /// View a scene (.ron), volume asset or mesh with the GPU viewer; --headless --screenshot renders a PNG.
    #[command(after_help = view_args::WINDOW_HELP)]
    #[command(allow_negative_numbers = true)]
    View(view_args::Args),
    /// Remove a volume's empty space: kd-tree boxes packed with aprons into a smaller atlas.
    #[command(allow_negative_numbers = true)]
    Emptyspace(emptyspace::Args),
}

/// Things every command may need from the global flags.
pub struct Ctx {
    pub quiet: bool,
}

/// clap's error for a command line that does not parse, as billow's one line: the problem,
/// clap's tips on the same line, and where to look (`billow voxelize --help`) instead of
/// the usage block clap prints over several lines.
fn usage_line(e: &clap::Error) -> String {
    let text = e.render().to_string();
    let mut problem = String::new();
    let mut tips = Vec::new();
    let mut command = "billow".to_string();
    for line in text.lines().map(str::trim).filter(|l| !l.is_empty()) {
        if let Some(p) = line.strip_prefix("error: ") {
            problem = p.to_string();
        } else if line.starts_with("For more information") {
        } else if let Some(t) = line.strip_prefix("tip: ") {
            tips.push(t.to_string());
        } else if let Some(u) = line.strip_prefix("Usage: ") {
            // `billow voxelize [OPTIONS] ...`: the command path is the words before the
            // first placeholder or option.
            let words: Vec<&str> = u
                .split_whitespace()
                .take_while(|w| !w.starts_with(['[', '<', '-']) && w.to_uppercase() != *w)
                .collect();
            if !words.is_empty() {
                command = words.join(" ");
            }
        } else if !problem.is_empty() {
            // The lines under the problem: the arguments it lists (`--height <HEIGHT>`).
            problem.push(' ');
            problem.push_str(line);
        }
    }
    if problem.is_empty() {
        problem = text
            .lines()
            .next()
            .unwrap_or("invalid command line")
            .to_string();
    }
    let mut line = problem;
    for t in tips {
        line.push_str("; ");
        line.push_str(&t);
    }
    line.push_str(&format!(" (see '{command} --help')"));
    line
}

/// A number that parses but lies outside its flag's range (`--threshold 256`,
/// `--supersample -5`, `--supersample 9`): exit 8 like every out-of-range value
/// (docs/cli.md), with the range in words instead of clap's `1..=8`.
fn out_of_range(e: &clap::Error) -> Option<String> {
    use clap::error::{ContextKind, ContextValue, ErrorKind};
    if e.kind() != ErrorKind::ValueValidation {
        return None;
    }
    let value = match e.get(ContextKind::InvalidValue)? {
        ContextValue::String(v) => v.clone(),
        _ => return None,
    };
    value.trim().parse::<f64>().ok()?;
    let flag = match e.get(ContextKind::InvalidArg)? {
        ContextValue::String(a) => a.split_whitespace().next().unwrap_or(a).to_string(),
        _ => return None,
    };
    // clap's ranged parsers say `9 is not in 1..=8`; a negative number for an unsigned
    // flag fails as "invalid digit".
    let text = e.render().to_string();
    let range = text.split(" is not in ").nth(1).and_then(|r| {
        let r = r.lines().next()?.trim();
        let (lo, hi) = r.split_once("..=")?;
        Some(format!("{lo} to {hi}"))
    });
    Some(match range {
        Some(r) => format!("{flag}: {value} is out of range ({r})"),
        None if value.trim().starts_with('-') => {
            format!("{flag}: {value} is out of range (it cannot be negative)")
        }
        None => format!("{flag}: {value} is out of range"),
    })
}

fn main() -> ExitCode {
    signals::install();
    stdout::install_panic_hook();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind as K;
            match e.kind() {
                // What the user asked for (--help, --version, a bare `billow`): clap's text.
                K::DisplayHelp
                | K::DisplayVersion
                | K::DisplayHelpOnMissingArgumentOrSubcommand => e.exit(),
                _ => {
                    use std::io::Write;
                    let (code, line) = match out_of_range(&e) {
                        Some(line) => (Code::BadParameter, line),
                        None => (Code::Usage, usage_line(&e)),
                    };
                    let _ = writeln!(std::io::stderr().lock(), "error: {line}");
                    return ExitCode::from(code as u8);
                }
            }
        }
    };
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
    match result.and_then(|()| stdout::finish()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            use std::io::Write;
            // A closed stderr must not turn this into a panic.
            let _ = writeln!(std::io::stderr().lock(), "error: {}", e.message);
            ExitCode::from(e.code as u8)
        }
    }
}
