//! `billow view TARGET`: the wgpu viewer (docs/viewer.md). TARGET is a scene file (.ron),
//! a volume asset (.billow) or a mesh (.gltf/.glb/.obj). All rendering is in the
//! `billow-view` crate; this module loads the inputs, builds the camera and writes the PNG.

use std::time::Instant;

use billow::eval::ImageF32;
use billow_core::camera::{parse_direction, Camera};
use billow_core::slicing::Spacing;
use billow_core::Aabb;
use billow_view::content::Content;
use billow_view::limits::{check_background, spacing_factor_ok, ParamError, ViewParams};
use billow_view::scene::SceneFile;
use billow_view::{FrameStats, Gpu, SliceParams, ViewCamera, ViewError};
use glam::{Mat4, Vec3, Vec4};
use serde::Serialize;

use crate::eval::parse_size;
use crate::exit::{bad, usage, CliError, Code};
use crate::output::{print_json, refuse_clobbering, refuse_clobbering_read};
use crate::view_args::Args;
use crate::view_load::{load_content, load_scene};
use crate::view_steps::{self, Steps};
use crate::Ctx;

#[derive(Serialize)]
struct Summary {
    target: String,
    screenshot: Option<String>,
    adapter: String,
    width: u32,
    height: u32,
    passes: Vec<&'static str>,
    /// What the renderer built and what the last frame encoded (tests compare its
    /// `pass_list` with `passes`).
    record: billow_view::gpu::RenderRecord,
    frames: u32,
    /// Mean and minimum wall time per frame (encode, submit, wait for the GPU), ms.
    frame_ms_mean: f64,
    frame_ms_min: f64,
    /// The first frame (includes compiling the shaders on lavapipe, which compiles a
    /// fragment shader at its first draw).
    frame_ms_first: f64,
    /// How long each start-up step took.
    startup_ms: Startup,
    /// Per shadow cascade, in how many of the frames its tile was drawn (the others
    /// kept it), and the mean per frame of the cloud texels drawn into the cascades
    /// (`stats.shadow_cascades[k].cloud_texels` of the tiles drawn).
    shadow_tiles_drawn: Vec<u32>,
    shadow_texels_per_frame: f64,
    stats: FrameStats,
}

/// The start-up of `billow view --headless`, step by step, in milliseconds: the scene and
/// its assets read and decoded, the adapter and device, the uploads (until the GPU has
/// them), the pipelines built before the first frame, the first frame (encode, submit,
/// wait), and all of it from the start of the command to the end of the first frame.
#[derive(Serialize, Default)]
struct Startup {
    read: f64,
    adapter: f64,
    upload: f64,
    pipelines: f64,
    first_frame: f64,
    total: f64,
}

fn parse_vec3(flag: &str, s: &str) -> Result<Vec3, CliError> {
    let v: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|e| usage(flag, format!("'{s}': {e}")))?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Vec3::new(*x, *y, *z)),
        [_, _, _] => Err(bad(flag, format!("'{s}': the numbers must be finite"))),
        _ => Err(usage(flag, format!("'{s}': expected three numbers X,Y,Z"))),
    }
}

fn parse_spacing(s: &str) -> Result<Spacing, CliError> {
    let (mode, arg) = match s.split_once(':') {
        Some((m, a)) => (m.trim(), Some(a.trim())),
        None => (s.trim(), None),
    };
    let num = |a: &str| -> Result<f32, CliError> {
        let v: f32 = a
            .parse()
            .map_err(|e| usage("--spacing", format!("'{s}': {e}")))?;
        if !spacing_factor_ok(v) {
            return Err(bad("--spacing", format!("'{s}': must be > 0")));
        }
        Ok(v)
    };
    match (mode, arg) {
        ("adaptive", None) => Ok(Spacing::Adaptive { bias: 1.0 }),
        ("adaptive", Some(a)) => Ok(Spacing::Adaptive { bias: num(a)? }),
        ("uniform", Some(a)) => Ok(Spacing::Uniform { spacing: num(a)? }),
        _ => Err(usage(
            "--spacing",
            format!("'{s}': expected adaptive, adaptive:BIAS or uniform:WORLD"),
        )),
    }
}

/// `--particle-layer` and `--particle-mode` over the scene's own settings.
fn override_particles(
    scene: &mut billow_view::scene::SceneFile,
    args: &Args,
) -> Result<(), CliError> {
    use billow_view::particle_pass::LayerResolution as R;
    use billow_view::particles::BillboardMode as M;
    if let Some(f) = args.particle_layer.as_deref() {
        scene.particle_layer.resolution = match f {
            "full" | "1" => R::Full,
            "half" | "1/2" => R::Half,
            "quarter" | "1/4" => R::Quarter,
            "eighth" | "1/8" => R::Eighth,
            o => {
                return Err(usage(
                    "--particle-layer",
                    format!("'{o}': expected full, half, quarter or eighth"),
                ))
            }
        };
    }
    if let Some(m) = args.particle_mode.as_deref() {
        let mode = match m {
            "spherical" => M::Spherical,
            "planar" => M::Planar,
            o => {
                return Err(usage(
                    "--particle-mode",
                    format!("'{o}': expected spherical or planar"),
                ))
            }
        };
        for p in &mut scene.particles {
            p.mode = mode;
        }
    }
    Ok(())
}

fn view_err(e: ViewError) -> CliError {
    CliError::new(Code::from(&e), e)
}

/// Reads the scene and its assets with the flags that change them (`--shadows`,
/// `--particle-layer`, `--particle-mode`, `--dissolve`), refusing a screenshot that would
/// replace a file it read; returns them and how long the reading took.
fn load(
    args: &Args,
    steps: &mut Steps,
) -> Result<(SceneFile, Content, std::time::Duration), CliError> {
    steps.start("reading the scene and its assets");
    let mut scene = load_scene(&args.target)?;
    match args.shadows.as_deref() {
        None => {}
        Some("on") => scene.shadows = true,
        Some("off") => scene.shadows = false,
        Some(o) => return Err(usage("--shadows", format!("'{o}': expected on or off"))),
    }
    override_particles(&mut scene, args)?;
    let mut read = Vec::new();
    let mut content = load_content(&scene, &mut read)?;
    let read_time = steps.end();
    if let Some(o) = args.dissolve {
        for c in &mut content.clouds {
            c.dissolve = o;
        }
    }
    if let Some(shot) = &args.screenshot {
        refuse_clobbering_read(&args.target, &read, &[("--screenshot", shot)])?;
    }
    Ok((scene, content, read_time))
}

/// `--print-passes`: the passes a frame runs, one a line (or `--json`).
fn print_passes(args: &Args, passes: &[&'static str]) -> Result<(), CliError> {
    if args.json {
        #[derive(Serialize)]
        struct Passes<'a> {
            target: String,
            passes: &'a [&'static str],
        }
        return print_json(&Passes {
            target: args.target.display().to_string(),
            passes,
        });
    }
    for p in passes {
        outln!("{p}");
    }
    Ok(())
}

/// A [`ParamError`] as the command's error, after the flag it came from
/// (`--fov: 200: must be in (0, 180) degrees`, exit 8).
fn param_error(e: ParamError) -> CliError {
    let flag = match e {
        ParamError::Distance(_) => "--distance",
        ParamError::Fov(_) => "--fov",
        ParamError::LodDistance(_) => "--lod-distance",
        ParamError::Dissolve(_) => "--dissolve",
        ParamError::Time(_) => "--time",
        ParamError::Orbit(_) => "--orbit",
        ParamError::Frames => "--frames",
        ParamError::SlabMinSlices => "--slab-min-slices",
        ParamError::SweepFill(_) => "--sweep-fill",
        ParamError::Background(_) => "--background",
    };
    bad(flag, e)
}

/// The flags' values and combinations checked, in the order their errors are reported;
/// returns the frame size and the slice spacing.
fn check_flags(args: &Args) -> Result<((u32, u32), Spacing), CliError> {
    let size = parse_size(&args.size)?;
    let spacing = parse_spacing(&args.spacing)?;
    ViewParams {
        distance: args.distance,
        fov_deg: args.fov,
        lod_distance: args.lod_distance,
        dissolve: args.dissolve,
        time: args.time,
        orbit_deg: args.orbit,
        frames: args.frames,
        slab_min_slices: args.slab_min_slices,
        sweep_fill: args.sweep_fill,
    }
    .validate()
    .map_err(param_error)?;
    check_modes(args)?;
    Ok((size, spacing))
}

/// `--lod-sweep`, `--headless` and `--screenshot` together.
fn check_modes(args: &Args) -> Result<(), CliError> {
    if args.lod_sweep.is_some() && (args.screenshot.is_some() || args.lod_distance.is_some()) {
        return Err(usage(
            "--lod-sweep",
            "renders its own frames: drop --screenshot and --lod-distance",
        ));
    }
    if args.headless && args.screenshot.is_none() && args.lod_sweep.is_none() {
        return Err(usage(
            "--screenshot",
            "--headless needs --screenshot OUT.png",
        ));
    }
    if !args.headless && args.screenshot.is_some() {
        return Err(usage(
            "--screenshot",
            "screenshots are taken headless: add --headless",
        ));
    }
    Ok(())
}

/// `--eye`, `--look-at`, `--view` and `--background` (else the scene's, each in [0, 1]).
#[allow(clippy::type_complexity)]
fn view_flags(
    args: &Args,
    scene: &SceneFile,
) -> Result<(Option<Vec3>, Option<Vec3>, Vec3, Option<Vec3>), CliError> {
    let eye = args
        .eye
        .as_deref()
        .map(|s| parse_vec3("--eye", s))
        .transpose()?;
    let look_at = args
        .look_at
        .as_deref()
        .map(|s| parse_vec3("--look-at", s))
        .transpose()?;
    let view_dir = parse_direction(&args.view).ok_or_else(|| {
        usage(
            "--view",
            format!("'{}': expected a direction like -z or +x-y-z", args.view),
        )
    })?;
    let background = args
        .background
        .as_deref()
        .map(|s| parse_vec3("--background", s))
        .transpose()?
        .or(scene.background.map(Vec3::from));
    if let Some(b) = background {
        check_background(b.to_array()).map_err(param_error)?;
    }
    Ok((eye, look_at, view_dir, background))
}

/// The camera: `--eye`, else the scene's, else framed like the eval's views (`--view`,
/// `--distance`); `--look-at` overrides the target. Returns it with its eye and target.
fn camera(
    args: &Args,
    scene: &SceneFile,
    bounds: &Aabb,
    (eye, look_at, view_dir): (Option<Vec3>, Option<Vec3>, Vec3),
    (fov, width, height): (f32, u32, u32),
) -> (ViewCamera, Vec3, Vec3) {
    let framed = Camera::framed(bounds, view_dir, fov, width, height, args.distance);
    let radius = if bounds.is_empty() {
        1.0
    } else {
        (0.5 * bounds.size().length()).max(1e-6)
    };
    let centre = if bounds.is_empty() {
        Vec3::ZERO
    } else {
        bounds.center()
    };
    let look = |eye: Vec3, target: Vec3, up: Vec3, near: Option<f32>, far: Option<f32>| {
        let dist = (eye - centre).length();
        let near = near.unwrap_or(((dist - radius) * 0.5).max(radius * 1e-3));
        let far = far.unwrap_or((dist + radius) * 2.0);
        (
            ViewCamera::look_at(eye, target, up, fov, width, height, near, far),
            eye,
            target,
        )
    };
    match (eye, &scene.camera) {
        (Some(e), _) => look(e, look_at.unwrap_or(centre), Vec3::Y, None, None),
        (None, Some(c)) => look(
            Vec3::from(c.eye),
            look_at.unwrap_or(Vec3::from(c.target)),
            Vec3::from(c.up),
            c.near,
            c.far,
        ),
        (None, None) => {
            let mut c = framed;
            if let Some(t) = look_at {
                c.target = t;
            }
            (
                ViewCamera::from_parts(c.view(), c.fov_y, c.width, c.height, c.near, c.far),
                c.eye,
                c.target,
            )
        }
    }
}

/// Mesa's device-select Vulkan layer probes a Wayland display server and prints a
/// misleading "error: XDG_RUNTIME_DIR is invalid or not set" on stderr without one, in a
/// window as well as headless (the window needs no such probe: winit picks the display).
/// Skips the layer unless the user chose otherwise (no other thread reads the environment
/// here).
fn skip_device_select() {
    if std::env::var_os("NODEVICE_SELECT").is_none()
        && std::env::var_os("XDG_RUNTIME_DIR").is_none()
    {
        std::env::set_var("NODEVICE_SELECT", "1");
    }
}

pub fn run(args: Args, ctx: &Ctx) -> Result<(), CliError> {
    let started = Instant::now();
    if let Some(shot) = &args.screenshot {
        refuse_clobbering(&[&args.target], &[("--screenshot", shot)])?;
        crate::output::image_out("--screenshot", shot)?;
    }
    let mut steps = Steps::stderr(ctx.quiet || args.print_passes);
    let (scene, content, read_time) = load(&args, &mut steps)?;
    let passes = content.passes();
    if args.print_passes {
        return print_passes(&args, &passes);
    }
    let ((width, height), spacing) = check_flags(&args)?;
    let (eye, look_at, view_dir, background) = view_flags(&args, &scene)?;
    let params = SliceParams {
        spacing,
        partition: !args.no_partition,
        slab_min_slices: args.slab_min_slices,
        ..Default::default()
    };
    let bounds = match content.bounds() {
        Some((min, max)) => Aabb { min, max },
        None => Aabb::EMPTY,
    };
    let fov_deg = args
        .fov
        .or(scene.camera.as_ref().map(|c| c.fov_deg))
        .unwrap_or(45.0);
    let fov = fov_deg.to_radians();
    let views = (eye, look_at, view_dir);
    let (camera, cam_eye, cam_target) = camera(&args, &scene, &bounds, views, (fov, width, height));
    skip_device_select();
    if let Some(dir) = &args.lod_sweep {
        return run_sweep(
            &args,
            (ctx, &mut steps),
            &content,
            (params, fov),
            (width, height),
            view_dir,
            dir,
        );
    }
    if !args.headless {
        let bg = background.map_or([0.55, 0.62, 0.72], |b| b.to_array());
        return run_window(
            &args,
            content,
            (params, fov, bg),
            (width, height),
            (cam_eye, cam_target),
            (ctx, steps),
        );
    }
    let shot = Shot {
        content: &content,
        camera: &camera,
        target: cam_target,
        params: (params, fov),
        size: (width, height),
        background,
        passes,
    };
    run_headless(&args, ctx, shot, steps, (started, read_time))
}

/// What a headless frame shows and how.
struct Shot<'a> {
    content: &'a Content,
    camera: &'a ViewCamera,
    /// What `--orbit` turns about.
    target: Vec3,
    params: (SliceParams, f32),
    size: (u32, u32),
    background: Option<Vec3>,
    passes: Vec<&'static str>,
}

/// `--headless --screenshot OUT.png`: renders `--frames` frames, writes the last and
/// prints the summary.
fn run_headless(
    args: &Args,
    ctx: &Ctx,
    shot: Shot,
    mut steps: Steps,
    (started, read_time): (Instant, std::time::Duration),
) -> Result<(), CliError> {
    let out = args.screenshot.as_ref().expect("checked above");
    let frames = args.frames.unwrap_or(1);
    let (width, height) = shot.size;
    let (gpu, adapter_time) = steps.run("requesting the GPU adapter", Gpu::headless);
    let gpu = gpu.map_err(view_err)?;
    let adapter = gpu.describe();
    let (mut r, build) = build(shot.content, gpu, shot.params, &mut steps)?;
    r.lod_distance_override = args.lod_distance;
    r.set_wireframe(args.wireframe);
    r.time = args.time;
    let target = billow_view::target::Target::new(&r.gpu, width, height);
    let orbit = (shot.camera, shot.target, args.orbit);
    let timed = render_frames(&mut r, &target, orbit, frames, &mut steps, started)?;
    drop(steps);
    let startup = Startup {
        read: view_steps::ms(read_time),
        adapter: view_steps::ms(adapter_time),
        upload: view_steps::ms(build[0]),
        pipelines: view_steps::ms(build[1]),
        first_frame: 1e3 * timed.first.unwrap_or(0.0),
        total: view_steps::ms(timed.first_done.unwrap_or_default()),
    };
    let img = r.read(&target).map_err(view_err)?;
    let record = r.record();
    write_screenshot(img, shot.background, out)?;
    let summary = Summary {
        target: args.target.display().to_string(),
        screenshot: Some(out.display().to_string()),
        adapter,
        width,
        height,
        passes: shot.passes,
        record,
        frames,
        frame_ms_mean: 1e3 * timed.total / f64::from(frames),
        frame_ms_min: 1e3 * timed.min,
        frame_ms_first: 1e3 * timed.first.unwrap_or(0.0),
        startup_ms: startup,
        shadow_tiles_drawn: timed.tiles_drawn,
        shadow_texels_per_frame: timed.texels_drawn / f64::from(frames),
        stats: timed.stats,
    };
    if args.json {
        print_json(&summary)?;
    } else if !ctx.quiet {
        print_text(&summary, out);
    }
    Ok(())
}

/// The frames' times (seconds) and the last frame's statistics.
struct Timed {
    stats: FrameStats,
    /// Per cascade, the frames that drew its tile, and the cloud texels drawn.
    tiles_drawn: Vec<u32>,
    texels_drawn: f64,
    total: f64,
    min: f64,
    first: Option<f64>,
    /// When the first frame was done, from the start of the command.
    first_done: Option<std::time::Duration>,
}

/// Renders `frames` frames, each timed until the GPU is done; frame k from `camera`
/// turned by k × `degrees` about the vertical axis through `centre` (`--orbit`).
fn render_frames(
    r: &mut billow_view::Renderer,
    target: &billow_view::target::Target,
    (camera, centre, degrees): (&ViewCamera, Vec3, f32),
    frames: u32,
    steps: &mut Steps,
    started: Instant,
) -> Result<Timed, CliError> {
    let mut t = Timed {
        stats: FrameStats::default(),
        tiles_drawn: Vec::new(),
        texels_drawn: 0.0,
        total: 0.0,
        min: f64::INFINITY,
        first: None,
        first_done: None,
    };
    for k in 0..frames {
        steps.start(match k {
            0 => "rendering the first frame".to_string(),
            _ => format!("rendering frame {} of {frames}", k + 1),
        });
        let cam = if degrees == 0.0 {
            *camera
        } else {
            let turn = Mat4::from_translation(centre)
                * Mat4::from_rotation_y((k as f32 * degrees).to_radians())
                * Mat4::from_translation(-centre);
            camera.with_view(camera.view * turn)
        };
        let t0 = Instant::now();
        t.stats = r.render(target, &cam).map_err(view_err)?;
        let cascades = &t.stats.shadow_cascades;
        t.tiles_drawn
            .resize(t.tiles_drawn.len().max(cascades.len()), 0);
        for (n, c) in t
            .tiles_drawn
            .iter_mut()
            .zip(cascades)
            .filter(|(_, c)| c.drawn)
        {
            *n += 1;
            t.texels_drawn += c.cloud_texels;
        }
        r.gpu.wait().map_err(view_err)?;
        let s = t0.elapsed().as_secs_f64();
        steps.end();
        t.total += s;
        t.min = t.min.min(s);
        t.first.get_or_insert(s);
        t.first_done.get_or_insert_with(|| started.elapsed());
    }
    Ok(t)
}

/// Writes the frame to `out` (PNG or as its extension says), composited over `background`
/// when given, atomically.
fn write_screenshot(
    img: billow_view::RgbaImage,
    background: Option<Vec3>,
    out: &std::path::Path,
) -> Result<(), CliError> {
    let bg = background.map(|b| b.extend(1.0));
    let image = ImageF32 {
        width: img.width,
        height: img.height,
        data: img
            .data
            .iter()
            .map(|p| {
                let c = Vec4::from_array(*p);
                match bg {
                    // Premultiplied "over" an opaque background.
                    Some(b) => c + b * (1.0 - c.w.clamp(0.0, 1.0)),
                    None => c,
                }
            })
            .collect(),
    };
    let png = image
        .png_bytes(out)
        .map_err(|e| CliError::new(Code::Internal, e))?; // names the path
    let png =
        crate::output::encode_image(crate::output::image_out("--screenshot", out)?, png, out)?;
    let mut stage = crate::staged::Staged::new(out);
    stage
        .stage(out, &png)
        .map_err(|e| crate::staged::out_err(out, e))?;
    stage.commit_or_fail()
}

/// The headless summary on stderr.
fn print_text(summary: &Summary, out: &std::path::Path) {
    let s = &summary.stats;
    eprintln!(
        "{}: {}x{} on {}, {} slices in {} slabs, {} cells, {} draws, {:.1} ms/frame (min {:.1}, {} frames) -> {}",
        summary.target,
        summary.width,
        summary.height,
        summary.adapter,
        s.slices,
        s.slabs,
        s.cells,
        s.draw_calls,
        summary.frame_ms_mean,
        summary.frame_ms_min,
        summary.frames,
        out.display()
    );
}

/// `content` on `gpu`, its upload and pipeline steps told to `steps`; returns the
/// renderer and the steps' times (upload, pipelines).
fn build(
    content: &billow_view::content::Content,
    gpu: Gpu,
    (params, fov): (SliceParams, f32),
    steps: &mut Steps,
) -> Result<(billow_view::Renderer, [std::time::Duration; 2]), CliError> {
    use billow_view::content::{BuildProgress, BuildStep};
    let mut times = [std::time::Duration::ZERO; 2];
    let r = content
        .build_with(gpu, params, fov, &mut |p| match p {
            BuildProgress::Started(s) => steps.start(s.describe()),
            BuildProgress::Finished(s, d) => {
                steps.end();
                times[match s {
                    BuildStep::Upload => 0,
                    BuildStep::Pipelines => 1,
                }] = d;
            }
        })
        .map_err(view_err)?;
    Ok((r, times))
}

/// `--lod-sweep DIR` (bin/billow/lod_sweep.rs).
fn run_sweep(
    args: &Args,
    (ctx, steps): (&Ctx, &mut Steps),
    content: &billow_view::content::Content,
    (params, fov): (SliceParams, f32),
    size: (u32, u32),
    view_dir: Vec3,
    dir: &std::path::Path,
) -> Result<(), CliError> {
    if dir.is_file() {
        return Err(CliError::new(
            Code::OutputIo,
            format!(
                "{}: --lod-sweep needs a folder, this is a file",
                dir.display()
            ),
        ));
    }
    std::fs::create_dir_all(dir)
        .map_err(|e| CliError::new(Code::OutputIo, format!("{}: {e}", dir.display())))?;
    let (gpu, _) = steps.run("requesting the GPU adapter", Gpu::headless);
    let (mut r, _) = build(content, gpu.map_err(view_err)?, (params, fov), steps)?;
    let sweep =
        crate::lod_sweep::sweep(&mut r, size, (-view_dir, fov, args.sweep_fill), Some(dir))?;
    let table = crate::lod_sweep::table(&sweep);
    let json =
        serde_json::to_string_pretty(&sweep).map_err(|e| CliError::new(Code::Internal, e))?;
    for (name, text) in [("sweep.json", json + "\n"), ("sweep.md", table.clone())] {
        let p = dir.join(name);
        std::fs::write(&p, text)
            .map_err(|e| CliError::new(Code::OutputIo, format!("{}: {e}", p.display())))?;
    }
    if args.json {
        print_json(&sweep)?;
    } else if !ctx.quiet {
        out!("{table}");
    }
    Ok(())
}

/// Window mode: an orbit camera starting at the computed camera.
fn run_window(
    args: &Args,
    content: billow_view::content::Content,
    (params, fov, background): (SliceParams, f32, [f32; 3]),
    size: (u32, u32),
    (eye, target): (Vec3, Vec3),
    (ctx, mut steps): (&Ctx, Steps),
) -> Result<(), CliError> {
    let lod = args.lod_distance;
    let wire = args.wireframe;
    let t0 = args.time;
    let mut first = true;
    let opts = billow_view::window::WindowOptions {
        title: format!("billow view {}", args.target.display()),
        size,
        params,
        orbit: billow_view::window::Orbit::from_eye(eye, target, fov),
        background,
        max_frames: args.frames.map(u64::from),
        animate: Some(Box::new(move |t, r: &mut billow_view::Renderer| {
            if first {
                r.lod_distance_override = lod;
                r.set_wireframe(wire);
                first = false;
            }
            r.time = t0 + t;
        })),
        progress: Some(Box::new(move |p| match p {
            billow_view::content::BuildProgress::Started(s) => steps.start(s.describe()),
            billow_view::content::BuildProgress::Finished(..) => {
                steps.end();
            }
        })),
    };
    let stats = billow_view::window::run(content, opts).map_err(view_err)?;
    if args.json {
        print_json(&stats)?;
    } else if !ctx.quiet {
        eprintln!(
            "{}: window closed after the last frame's {} slices, {} cells",
            args.target.display(),
            stats.slices,
            stats.cells
        );
    }
    Ok(())
}
