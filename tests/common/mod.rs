//! Helpers for driving the real `billow` binary in integration tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The `billow` binary Cargo built for this test (only the CLI package's tests,
/// bin/billow/Cargo.toml, have one).
pub fn bin() -> PathBuf {
    match option_env!("CARGO_BIN_EXE_billow") {
        Some(p) => PathBuf::from(p),
        None => panic!(
            "this test drives the binary: declare it in bin/billow/Cargo.toml, not in the library's Cargo.toml"
        ),
    }
}

/// The repository root, from the library's package or the CLI's (bin/billow).
pub fn repo() -> PathBuf {
    billow::test_support::repo()
}

/// A test that cannot run: `SKIP` on stderr, or a failure under CI / `BILLOW_REQUIRE=all`
/// ([`billow::test_support::skip`], the one rule).
pub fn skip(test: &str, reason: &str) {
    billow::test_support::skip(test, reason)
}

/// [`skip`] for a test that needs an external `tool` a machine may lack for good (waived by
/// `BILLOW_OPTIONAL`, [`billow::test_support::skip_tool`]).
pub fn skip_tool(test: &str, tool: &str, reason: &str) {
    billow::test_support::skip_tool(test, tool, reason)
}

/// `../shared/assets`, or `None` (after [`skip`]) when absent.
pub fn shared_assets(test: &str) -> Option<PathBuf> {
    let p = repo().join("../shared/assets");
    if p.is_dir() {
        Some(p)
    } else {
        skip(test, "../shared/assets not found");
        None
    }
}

pub struct Run {
    /// `None` when killed by a signal or the timeout.
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
    pub timed_out: bool,
}

impl Run {
    /// The single `error: ...` line a failing command must print, or a description of what is wrong.
    pub fn error_line(&self) -> Result<&str, String> {
        let lines: Vec<&str> = self
            .stderr
            .lines()
            .filter(|l| !l.starts_with("warning:"))
            .collect();
        match lines.as_slice() {
            [l] if l.starts_with("error: ") => Ok(l),
            _ => Err(format!(
                "expected one 'error:' line on stderr, got {:?}",
                self.stderr
            )),
        }
    }
}

/// Runs `billow args...` with a wall-clock limit and an address-space limit (`ulimit -v`,
/// in KiB) so that a hang or an allocation bomb fails the test instead of the machine.
pub fn run_limited(args: &[&str], dir: &Path, timeout: Duration, mem_kib: u64) -> Run {
    run_with(args, dir, timeout, mem_kib, &[("RAYON_NUM_THREADS", "2")])
}

/// [`run_limited`] with extra environment variables.
pub fn run_with(
    args: &[&str],
    dir: &Path,
    timeout: Duration,
    mem_kib: u64,
    envs: &[(&str, &str)],
) -> Run {
    let mut cmd = Command::new("sh");
    cmd.arg("-c")
        .arg(format!("ulimit -v {mem_kib}; exec \"$0\" \"$@\""))
        .arg(bin())
        .args(args)
        .current_dir(dir)
        .envs(envs.iter().copied())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut child = cmd.spawn().expect("spawn billow");
    // The pipes are drained while the child runs: a child whose output outgrows the pipe
    // buffer (64 KiB, e.g. `eval --json` with many views) would otherwise block on its
    // write and never exit.
    let drain = |mut r: Box<dyn std::io::Read + Send>| {
        std::thread::spawn(move || {
            let mut buf = Vec::new();
            let _ = r.read_to_end(&mut buf);
            buf
        })
    };
    let stdout = drain(Box::new(child.stdout.take().expect("stdout")));
    let stderr = drain(Box::new(child.stderr.take().expect("stderr")));
    let start = Instant::now();
    let mut timed_out = false;
    loop {
        if child.try_wait().expect("wait").is_some() {
            break;
        }
        if start.elapsed() > timeout {
            let _ = child.kill();
            timed_out = true;
            break;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    let status = child.wait().expect("wait");
    let (stdout, stderr) = (stdout.join().unwrap(), stderr.join().unwrap());
    Run {
        code: if timed_out { None } else { status.code() },
        stdout: String::from_utf8_lossy(&stdout).into_owned(),
        stderr: String::from_utf8_lossy(&stderr).into_owned(),
        timed_out,
    }
}

/// Runs `billow args...` in `dir` (generous limits).
pub fn run(args: &[&str], dir: &Path) -> Run {
    run_limited(args, dir, Duration::from_secs(120), 8 << 20)
}

/// `billow view TARGET --headless --screenshot SHOT --fov 45 --shadows off ARGS…` in `dir`
/// (the viewer's headless picture a test compares with the CPU reference): `None`, after
/// [`skip`], without a GPU adapter; any other failure panics.
pub fn headless_shot(
    test: &str,
    target: &str,
    shot: &str,
    args: &[&str],
    dir: &Path,
) -> Option<()> {
    let mut all = vec![
        "view",
        target,
        "--headless",
        "--screenshot",
        shot,
        "--fov",
        "45",
        "--shadows",
        "off",
    ];
    all.extend_from_slice(args);
    let r = run(&all, dir);
    if r.code == Some(5) && r.stderr.contains("adapter") {
        skip(test, "no GPU adapter");
        return None;
    }
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    Some(())
}

pub fn sha256(path: &Path) -> String {
    use sha2::{Digest, Sha256};
    let bytes = std::fs::read(path).unwrap();
    format!("{:x}", Sha256::digest(bytes))
}

/// How [`leaf_canopy`] scatters its leaves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Leaves {
    /// A canopy (tests/relight_moments.rs): leaves in a ball flattened to 0.6 in y, each
    /// tilted up to 35° from horizontal (a canopy's leaves face the sky more than the
    /// horizon), one shade of green, 0.14 wide.
    Canopy,
    /// Foliage (tests/voxelize_coverage.rs): leaves of random orientation in a ball of
    /// radius 1, denser towards the centre, greens that vary, 0.12 wide; and a trunk-like
    /// square column of four faces below (x, z in [−0.08, 0.08], y from −1.6 to −0.6),
    /// whose coverage is correlated along every horizontal ray.
    Foliage,
}

/// `n` small double-sided opaque square leaves scattered as `leaves` says (the one leafy
/// scene of the root tests; the same `n`, `seed` and kind give the same scene).
pub fn leaf_canopy(n: u32, seed: u64, leaves: Leaves) -> billow::scene::Scene {
    use billow::rng::Pcg32;
    use billow::scene::{Material, SceneBuilder};
    use glam::{Vec3, Vec4};
    let foliage = leaves == Leaves::Foliage;
    let mut rng = Pcg32::seeded(seed, if foliage { 7 } else { 3 });
    let mut sb = SceneBuilder::new();
    let leaf = sb.material(Material {
        double_sided: true,
        ..Material::default()
    });
    let mesh = sb.mesh("leaves");
    for _ in 0..n {
        let p = loop {
            let p = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            if p.length_squared() <= 1.0 {
                break p;
            }
        };
        let (c, nrm, half) = if foliage {
            let c = p * (0.4 + 0.6 * rng.next_f32());
            let nrm = (Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0)
                .normalize_or(Vec3::Y);
            (c, nrm, 0.06)
        } else {
            let tilt = 35f32.to_radians() * rng.next_f32();
            let phi = std::f32::consts::TAU * rng.next_f32();
            let nrm = Vec3::new(tilt.sin() * phi.cos(), tilt.cos(), tilt.sin() * phi.sin());
            (p * Vec3::new(1.0, 0.6, 1.0), nrm, 0.07)
        };
        let a = nrm.any_orthonormal_vector() * half;
        let b = nrm.cross(a);
        let colour = if foliage {
            Vec4::new(0.2, 0.4 + 0.4 * rng.next_f32(), 0.1, 1.0)
        } else {
            Vec4::new(0.25, 0.6, 0.15, 1.0)
        };
        sb.quad(
            [c - a - b, c + a - b, c + a + b, c - a + b],
            colour,
            leaf,
            mesh,
        );
    }
    if foliage {
        let bark = sb.mesh("trunk");
        let (lo, hi, w) = (-1.6f32, -0.6f32, 0.08f32);
        let c = Vec4::new(0.3, 0.2, 0.1, 1.0);
        for (p, q) in [
            (Vec3::new(-w, 0.0, -w), Vec3::new(w, 0.0, -w)),
            (Vec3::new(w, 0.0, -w), Vec3::new(w, 0.0, w)),
            (Vec3::new(w, 0.0, w), Vec3::new(-w, 0.0, w)),
            (Vec3::new(-w, 0.0, w), Vec3::new(-w, 0.0, -w)),
        ] {
            let y = |v: Vec3, h: f32| Vec3::new(v.x, h, v.z);
            sb.quad([y(p, lo), y(q, lo), y(q, hi), y(p, hi)], c, leaf, bark);
        }
    }
    sb.finish()
}

/// `scene` baked densely as `billow voxelize --normals MODE` decides (`opts` left as the
/// bake used them: `surface`, `normals`, `moments`), quietly.
#[allow(dead_code)]
pub fn bake_mode(
    scene: &billow::scene::Scene,
    opts: &mut billow::voxelize::VoxelizeOptions,
    mode: billow::voxelize::NormalsMode,
) -> (billow::voxelize::Volume, billow::voxelize::NormalsOutcome) {
    let quiet = |_: billow::voxelize::Stage, _: f32| {};
    billow::voxelize::bake_with_normals(
        scene,
        opts,
        mode,
        |o| billow::voxelize::voxelize(scene, o, &quiet),
        |v| (v.normal_coherence, v.normals.is_some()),
    )
    .expect("bake")
}
