//! How much of a voxelize run is the kernel handing out fresh memory: voxelizes one scene
//! several times in one process and prints, per run, the wall time, the stage times and
//! the page faults taken during the run.
//!
//! `cargo run --release --example voxelize_warm -- MESH RES RUNS [K]`
//!
//! Run it with glibc keeping freed memory (`MALLOC_MMAP_MAX_=0
//! MALLOC_TRIM_THRESHOLD_=100000000000`): from the second run on, every buffer comes from
//! memory the process already touched (the fault count drops to about 0), so the
//! difference between the first run and the later ones is the cost of first touches.
//! That bounds what any restructuring of the buffers (reuse, streaming in slabs) can save
//! on memory alone. Import and the asset write are not included.

use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

use billow::import::{import, ImportOptions};
use billow::voxelize::{voxelize, Resolution, VoxelizeOptions};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let parsed = match args.as_slice() {
        [mesh, res, runs, rest @ ..] if rest.len() <= 1 => (
            mesh,
            res.parse::<u32>(),
            runs.parse::<usize>(),
            rest.first().map_or(Ok(4), |k| k.parse::<u32>()),
        ),
        _ => {
            eprintln!("usage: voxelize_warm MESH RES RUNS [K]");
            return ExitCode::from(2);
        }
    };
    let (mesh, Ok(res), Ok(runs), Ok(k)) = parsed else {
        eprintln!("voxelize_warm: RES, RUNS and K must be whole numbers");
        return ExitCode::from(2);
    };
    let scene = match import(Path::new(mesh), &ImportOptions { strict: false }) {
        Ok(s) => s.scene,
        Err(e) => {
            eprintln!("voxelize_warm: {e}");
            return ExitCode::FAILURE;
        }
    };
    let opts = VoxelizeOptions {
        resolution: Resolution::Longest(res),
        supersample: k,
        ..Default::default()
    };
    for run in 0..runs {
        let f0 = faults();
        let t = Instant::now();
        let volume = match voxelize(&scene, &opts, &|_, _| {}) {
            Ok(v) => v,
            Err(e) => {
                eprintln!("voxelize_warm: {mesh}: {e}");
                return ExitCode::FAILURE;
            }
        };
        let wall = t.elapsed().as_secs_f64();
        let s = volume.stats.seconds;
        println!(
            "run {}: {wall:.3} s, faults {}, rasterize {:.3}, mip {:.3}, combine {:.3}, \
             quantize {:.3}",
            run + 1,
            faults().map_or("?".into(), |f| (f - f0.unwrap_or(0)).to_string()),
            s.rasterize,
            s.mip,
            s.combine,
            s.quantize
        );
        drop(volume);
    }
    ExitCode::SUCCESS
}

/// Minor plus major page faults of the process so far.
#[cfg(target_os = "linux")]
fn faults() -> Option<i64> {
    // SAFETY: `getrusage` fills the struct it is given; all-zero is a valid `rusage`.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    let rc = unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) };
    (rc == 0).then_some(u.ru_minflt + u.ru_majflt)
}

#[cfg(not(target_os = "linux"))]
fn faults() -> Option<i64> {
    None
}
