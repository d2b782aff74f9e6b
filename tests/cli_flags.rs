//! Every flag of every command, read from `billow --help` and `billow <command> --help`,
//! given a value that does not parse (exit 2) and a value that parses but is out of range
//! (exit 8), as docs/cli.md's rule says. A flag that takes no value, or whose every value
//! parses or none is out of range (free text, paths, keywords), is listed with the reason.
//! A flag that appears in `--help` but not in the table below fails the test, so a new
//! flag must be given its cases.

mod common;

use std::collections::BTreeSet;
use std::path::Path;

use common::run;

/// What to try on one flag.
enum Case {
    /// `unparsable` must exit 2; `out_of_range`, when there is one, must exit 8. `extra`
    /// arguments make the flag matter (e.g. `--bake ao` for `--ao-rays`).
    Values {
        unparsable: Option<&'static str>,
        out_of_range: Option<&'static str>,
        extra: &'static [&'static str],
    },
    /// Not tried, with the reason.
    Except(&'static str),
}

use Case::{Except, Values};

const fn both(unparsable: &'static str, out_of_range: &'static str) -> Case {
    Values {
        unparsable: Some(unparsable),
        out_of_range: Some(out_of_range),
        extra: &[],
    }
}

/// A keyword or enum flag: every wrong value is unparsable; nothing is "out of range".
const fn keyword(unparsable: &'static str) -> Case {
    Values {
        unparsable: Some(unparsable),
        out_of_range: None,
        extra: &[],
    }
}

const SWITCH: Case = Except("a switch: takes no value");
const PATH: Case =
    Except("a path: any text names a file (unwritable ones are tested in cli_outputs.rs)");

/// The arguments every run of `command` gets, without the flag under test.
fn base(command: &str) -> Vec<&'static str> {
    match command {
        "inspect" => vec!["t.obj"],
        "info" => vec!["t.billow"],
        "voxelize" => vec!["t.obj", "-o", "x.billow", "--res", "8"],
        "shell" => vec!["quad.obj", "t.billow", "-o", "x.billow", "--height", "0.1"],
        "bbcloud" => vec![
            "leaf.obj",
            "-o",
            "x.billow",
            "--samples",
            "10",
            "--atlas-size",
            "256",
        ],
        "eval" => vec![
            "t.obj",
            "t.billow",
            "--size",
            "16x16",
            "--spp",
            "1",
            "--views",
            "+x",
            "--distances",
            "1",
        ],
        "compare" => vec!["a.png", "a.png"],
        "view" => vec![
            "t.billow",
            "--headless",
            "--screenshot",
            "x.png",
            "--size",
            "16x16",
        ],
        "emptyspace" => vec!["e.billow", "-o", "x.billow"],
        other => panic!("no base arguments for command {other}: add them"),
    }
}

fn case(command: &str, flag: &str) -> Option<Case> {
    Some(match (command, flag) {
        // Global and clap's own.
        (_, "help") => Except("clap's help"),
        (_, "version") => Except("clap's version"),
        (_, "quiet") | (_, "json") | (_, "strict") => SWITCH,
        (_, "output") => PATH,
        (_, "depfile") => PATH,

        ("voxelize", "res") => both("abc", "0"),
        ("voxelize", "preset") | ("bbcloud", "preset") => keyword("bogus"),
        ("voxelize", "target-error") | ("bbcloud", "target-error") => both("abc", "0"),
        ("voxelize", "target-distances") | ("bbcloud", "target-distances") => Values {
            unparsable: Some("abc"),
            out_of_range: Some("1,0"),
            extra: &["--target-error", "0.5"],
        },
        ("voxelize", "target-weighting") | ("bbcloud", "target-weighting") => Values {
            unparsable: Some("bogus"),
            out_of_range: None, // a keyword
            extra: &["--target-error", "0.5"],
        },
        ("voxelize", "target-lights") | ("bbcloud", "target-lights") => Values {
            unparsable: Some("bogus"),
            out_of_range: Some("0,0,0"),
            extra: &["--target-error", "0.5"],
        },
        ("voxelize", "target-size") | ("bbcloud", "target-size") => Values {
            unparsable: Some("abc"),
            out_of_range: Some("0x16"),
            extra: &["--target-error", "0.5"],
        },
        ("voxelize", "supersample") => both("abc", "9"),
        ("voxelize", "combine") => Values {
            unparsable: Some("bogus"),
            out_of_range: Some(LONG_EXPR),
            extra: &[],
        },
        ("voxelize", "normals") => keyword("bogus"),
        ("voxelize", "compress")
        | ("bbcloud", "compress")
        | ("shell", "compress")
        | ("emptyspace", "compress") => keyword("bogus"),
        ("voxelize", "mips") => both("abc", "99"),
        ("voxelize", "margin") => both("abc", "100"),
        ("voxelize", "align") => both("abc", "0"),
        ("voxelize", "prune") => SWITCH,
        ("voxelize", "memory-limit") => both("abc", "0"),
        ("voxelize", "bounds") => both("a,b", "1,1,1,0,0,0"),
        ("voxelize", "ktx2") | ("voxelize", "slices") => PATH,
        ("voxelize", "ktx2-zstd") => Values {
            unparsable: Some("abc"),
            out_of_range: Some("23"),
            extra: &["--ktx2", "x.ktx2"],
        },
        ("voxelize", "slice-level") => Values {
            unparsable: Some("abc"),
            out_of_range: Some("99"),
            extra: &["--slices", "sl"],
        },
        ("voxelize", "slice-format") => keyword("bogus"),
        ("voxelize", "bake") => keyword("bogus"),
        ("voxelize", "ao-rays") => Values {
            unparsable: Some("abc"),
            out_of_range: Some("0"),
            extra: &["--bake", "ao"],
        },
        ("voxelize", "ao-distance") => Values {
            unparsable: Some("abc"),
            out_of_range: Some("-1"),
            extra: &["--bake", "ao"],
        },

        ("shell", "height") => both("abc", "0"),
        ("shell", "tiles") => both("a,b", "0,1"),
        ("shell", "surface-normals") => SWITCH,

        ("bbcloud", "epsilon") => both("abc", "0"),
        ("bbcloud", "samples") => both("abc", "0"),
        ("bbcloud", "seed") => Values {
            unparsable: Some("abc"),
            out_of_range: None, // every u64 is a seed
            extra: &[],
        },
        ("bbcloud", "lods") => both("abc", "0"),
        ("bbcloud", "up") => both("sideways", "0,0,0"),
        ("bbcloud", "view-dirs") => both("sideways", "0,0,0"),
        ("bbcloud", "view-strength") => Values {
            unparsable: Some("abc"),
            out_of_range: Some("2"),
            extra: &["--view-dirs", "+z"],
        },
        ("bbcloud", "normal-map") | ("bbcloud", "unlit") => SWITCH,
        ("bbcloud", "flatten") => keyword("bogus"),
        ("bbcloud", "mip-levels") => both("abc", "6"),
        ("bbcloud", "atlas-size") => both("abc", "1000"),
        ("bbcloud", "texel-density") => both("abc", "-1"),
        ("bbcloud", "light") => both("a,b,c", "0,0,0"),
        ("bbcloud", "ambient") => both("abc", "2"),
        ("bbcloud", "supersample") => both("abc", "9"),
        ("bbcloud", "max-extent") => both("abc", "0"),
        ("bbcloud", "foliage") => Values {
            unparsable: None, // any text is a material name
            out_of_range: Some("no-such-material"),
            extra: &[],
        },
        // A file name that ends in neither .glb nor .gltf names no glTF container.
        ("bbcloud", "gltf") => keyword("x.png"),
        ("bbcloud", "atlas") => PATH,
        ("bbcloud", "gltf-alpha") => keyword("bogus"),

        ("eval", "views") => both("bogus", "+x@2000x"),
        ("eval", "distances") => both("abc", "0"),
        ("eval", "size") => both("abc", "0x16"),
        ("eval", "spp") => both("abc", "2"),
        ("eval", "spacing") => both("bogus", "adaptive:0"),
        ("eval", "out") => PATH,
        ("eval", "lighting") => keyword("bogus"),
        ("eval", "lod") => both("abc", "9"),
        ("eval", "light") => both("abc", "0,0,0"),
        ("eval", "lights") => both("bogus", "a=0,0,0"),
        ("eval", "ambient") => Values {
            unparsable: Some("abc"),
            out_of_range: Some("2"),
            extra: &["--light", "0,1,0"],
        },
        ("eval", "shadows") => SWITCH,

        ("compare", "diff") => PATH,

        ("view", "headless") | ("view", "no-partition") => SWITCH,
        ("view", "print-passes") | ("view", "wireframe") => SWITCH,
        ("view", "screenshot") | ("view", "lod-sweep") => PATH,
        ("view", "sweep-fill") => both("abc", "0"),
        ("view", "size") => both("abc", "0x16"),
        ("view", "eye") | ("view", "look-at") => both("a,b,c", "inf,0,0"),
        ("view", "view") => keyword("bogus"),
        ("view", "distance") => both("abc", "0"),
        ("view", "fov") => both("abc", "180"),
        ("view", "spacing") => both("bogus", "uniform:0"),
        ("view", "slab-min-slices") => both("abc", "0"),
        ("view", "shadows") | ("view", "particle-layer") | ("view", "particle-mode") => {
            keyword("bogus")
        }
        ("view", "time") => both("abc", "inf"),
        ("view", "orbit") => both("abc", "inf"),
        ("view", "lod-distance") => both("abc", "0"),
        ("view", "dissolve") => both("abc", "5"),
        ("view", "frames") => both("abc", "0"),
        ("view", "background") => both("a", "2,0,0"),

        ("emptyspace", "threshold") => both("abc", "256"), // a byte
        ("emptyspace", "min-box") | ("emptyspace", "max-tiers") => Values {
            unparsable: Some("abc"),
            out_of_range: None, // every u32 is accepted (clamped to the volume)
            extra: &[],
        },
        ("emptyspace", "max-depth") => both("abc", "65"),
        ("emptyspace", "min-gain") => both("abc", "1"),
        ("emptyspace", "cell-cost") => both("abc", "-1"),
        _ => return None,
    })
}

/// A `--combine` expression over the 1024-token limit.
const LONG_EXPR: &str = concat!(
    "expr:px",
    // 600 × "+px" = 1200 tokens
    "+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px",
    "+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px",
    "+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px",
    "+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px",
    "+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px",
    "+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px",
    "+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px",
    "+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px",
    "+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px",
    "+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px",
    "+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px",
    "+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px",
    "+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px",
    "+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px",
    "+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px",
    "+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px",
    "+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px",
    "+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px",
    "+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px",
    "+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px+px",
);

/// Section `title` of a clap help text: the first word of each entry line.
fn section(help: &str, title: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut inside = false;
    for line in help.lines() {
        if !line.starts_with(' ') {
            inside = line.trim_end() == title;
            continue;
        }
        if inside {
            out.push(line.trim_start().to_string());
        }
    }
    out
}

/// The long flags of a command's help (`--name`), whether each takes a value.
fn flags(help: &str) -> Vec<(String, bool)> {
    let mut out = Vec::new();
    for entry in section(help, "Options:") {
        let Some(at) = entry.find("--") else { continue };
        // `-o, --output <OUTPUT>` or `--res <RES>`; continuation lines start otherwise.
        if !(entry.starts_with("--") || entry.starts_with('-') && at == 4) {
            continue;
        }
        let rest = &entry[at + 2..];
        let name: String = rest
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '-')
            .collect();
        // `--normals [<WHEN>]`: an optional value (a bare flag means a default) still takes one.
        let takes_value =
            rest[name.len()..].starts_with(" <") || rest[name.len()..].starts_with(" [<");
        out.push((name, takes_value));
    }
    out
}

/// The files the base arguments name, in `d`.
fn setup(d: &Path) {
    let w = |name: &str, text: &str| std::fs::write(d.join(name), text).unwrap();
    w(
        "t.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    );
    w(
        "quad.obj",
        "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 1 0\n\
         f 1/1/1 4/4/1 3/3/1 2/2/1\n",
    );
    w(
        "leaf.obj",
        "mtllib leaf.mtl\nusemtl leaf\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0.2\nf 1 2 3\nf 2 4 3\n",
    );
    w("leaf.mtl", "newmtl leaf\nKd 0.2 0.6 0.2\nd 0.5\n");
    for (args, what) in [
        (
            vec!["voxelize", "t.obj", "-o", "t.billow", "--res", "8", "-q"],
            "t.billow",
        ),
        (
            vec![
                "voxelize", "t.obj", "-o", "e.billow", "--res", "8", "--align", "8", "-q",
            ],
            "e.billow",
        ),
    ] {
        let r = run(&args, d);
        assert_eq!(r.code, Some(0), "making {what}: {}", r.stderr);
    }
    image::RgbaImage::from_pixel(4, 4, image::Rgba([255, 0, 0, 255]))
        .save(d.join("a.png"))
        .unwrap();
}

#[test]
fn every_flag_follows_the_exit_code_rule() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    setup(d);
    let top = run(&["--help"], d);
    assert_eq!(top.code, Some(0), "{}", top.stderr);
    let commands: Vec<String> = section(&top.stdout, "Commands:")
        .iter()
        .map(|l| l.split_whitespace().next().unwrap().to_string())
        .filter(|c| c != "help")
        .collect();
    assert!(commands.len() >= 9, "commands: {commands:?}");

    let mut failures = Vec::new();
    let mut excepted = Vec::new();
    let mut tried = 0;
    let mut seen = BTreeSet::new();
    for command in &commands {
        let help = run(&[command, "--help"], d);
        assert_eq!(help.code, Some(0), "{command}: {}", help.stderr);
        let flags = flags(&help.stdout);
        assert!(!flags.is_empty(), "{command}: no flags in {}", help.stdout);
        for (flag, takes_value) in flags {
            seen.insert(format!("{command} --{flag}"));
            let Some(c) = case(command, &flag) else {
                failures.push(format!(
                    "{command} --{flag}: not in tests/cli_flags.rs's table; give it cases"
                ));
                continue;
            };
            let (unparsable, out_of_range, extra) = match c {
                Values {
                    unparsable,
                    out_of_range,
                    extra,
                } => (unparsable, out_of_range, extra),
                Except(why) => {
                    excepted.push(format!("{command} --{flag}: {why}"));
                    continue;
                }
            };
            assert!(
                takes_value,
                "{command} --{flag} takes no value but has cases"
            );
            for (value, want) in [(unparsable, 2), (out_of_range, 8)] {
                let Some(value) = value else { continue };
                let mut args = vec![command.as_str()];
                // The base arguments, without the flag under test (e.g. --res).
                let b = base(command);
                let mut i = 0;
                while i < b.len() {
                    if b[i] == format!("--{flag}") {
                        i += 2;
                        continue;
                    }
                    args.push(b[i]);
                    i += 1;
                }
                args.extend_from_slice(extra);
                let arg = format!("--{flag}={value}");
                args.push(&arg);
                let r = run(&args, d);
                tried += 1;
                let shown = &value[..value.len().min(40)];
                if r.code != Some(want) {
                    failures.push(format!(
                        "{command} --{flag}={shown}: exit {:?}, expected {want}: {}",
                        r.code,
                        r.stderr.lines().next().unwrap_or("")
                    ));
                } else if r
                    .stderr
                    .lines()
                    .next()
                    .is_none_or(|l| !l.starts_with("error: "))
                {
                    failures.push(format!(
                        "{command} --{flag}={shown}: no 'error:' line: {}",
                        r.stderr
                    ));
                }
            }
        }
    }
    eprintln!(
        "{} flags, {tried} runs; not tried:\n  {}",
        seen.len(),
        excepted.join("\n  ")
    );
    assert!(tried >= 80, "only {tried} runs");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
