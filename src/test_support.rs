//! What a check that cannot run does (feature `test-support`, which billow's tests and
//! examples, the CLI's tests and the viewer's tests turn on; never in the binary, and the
//! library itself never prints): it says so on stderr, `SKIP: <name>: <reason>`, written
//! straight to the process's stderr so that it shows even though a test harness captures
//! `eprintln!`, and it fails instead under CI (`CI` set) or `BILLOW_REQUIRE=all`, where
//! every resource it needs must be there. One rule for every test and report generator.

use std::io::Write;
use std::path::PathBuf;

/// The repository root (the library's package root), whichever package's test asks: the
/// CLI's tests run with their own manifest directory, bin/billow.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A check that cannot run here: `SKIP` on stderr, or a panic under CI /
/// `BILLOW_REQUIRE=all`.
pub fn skip(name: &str, reason: &str) {
    skip_unless_required(name, None, reason)
}

/// [`skip`] for a check that needs an external `tool` a machine may lack for good (e.g.
/// Khronos' `ktx`, which Debian does not package): it may still skip under CI /
/// `BILLOW_REQUIRE=all` when the tool is named in `BILLOW_OPTIONAL` (a comma list, e.g.
/// `BILLOW_OPTIONAL=ktx`), and says so on stderr all the same.
pub fn skip_tool(name: &str, tool: &str, reason: &str) {
    skip_unless_required(name, Some(tool), reason)
}

fn skip_unless_required(name: &str, tool: Option<&str>, reason: &str) {
    let waived = tool.is_some_and(|t| {
        std::env::var("BILLOW_OPTIONAL").is_ok_and(|v| v.split(',').any(|x| x.trim() == t))
    });
    let required = !waived
        && (std::env::var_os("CI").is_some()
            || std::env::var("BILLOW_REQUIRE").is_ok_and(|v| v == "all"));
    assert!(
        !required,
        "{name}: {reason} (required under CI / BILLOW_REQUIRE=all)"
    );
    let _ = writeln!(std::io::stderr(), "SKIP: {name}: {reason}");
}
