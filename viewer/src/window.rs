//! Window mode (winit): an orbit camera around the content, a stats line drawn on the
//! frame, and keys for the renderer's switches.
//!
//! Mouse: left drag orbits, right (or shift + left) drag pans, the wheel zooms.
//! Keys: `A` adaptive ↔ uniform slicing (one level-0 voxel), `P` slab partitioning,
//! `W` cell wireframe, `S` shadows, `R` reset the camera, `Esc`/`Q` quit.
//! The stats line: frame time, slices, slabs (empty ones skipped), cells, cell × slice
//! instances, draws, the LOD (and morph factor) of each cloud instance, and the switches.
//!
//! Frames: the CPU builds frame N + 1 while the GPU draws frame N (after submitting a
//! frame the loop waits only for the one before it, so at most two are in flight), and
//! the window sleeps when nothing moves: a frame is drawn on input (orbit, keys,
//! resize) and continuously only while the scene animates (particles, swaying cells) or
//! a frame count was asked for. The frame time shown is the mean interval between
//! frames over the last half second (and the CPU's share of it), so the stats texture
//! changes at most twice a second.

use std::sync::Arc;
use std::time::Instant;

use glam::Vec3;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key, ModifiersState, NamedKey};
use winit::window::{Window, WindowId};

use crate::content::Content;
use crate::overlay::Resolve;
use crate::target::Target;
use crate::{FrameStats, Gpu, Renderer, SliceParams, ViewCamera, ViewError};
use billow_core::slicing::Spacing;

/// An orbit camera: `target`, `distance`, `yaw` about +Y, `pitch` above the horizon.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    pub target: Vec3,
    pub distance: f32,
    pub yaw: f32,
    pub pitch: f32,
    pub fov_y: f32,
}

impl Orbit {
    /// The orbit that puts the eye at `eye` looking at `target`.
    pub fn from_eye(eye: Vec3, target: Vec3, fov_y: f32) -> Orbit {
        let d = eye - target;
        let distance = d.length().max(1e-6);
        Orbit {
            target,
            distance,
            yaw: d.x.atan2(d.z),
            pitch: (d.y / distance).clamp(-1.0, 1.0).asin(),
            fov_y,
        }
    }

    pub fn eye(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + self.distance * Vec3::new(cp * sy, sp, cp * cy)
    }

    /// The camera for a `w`×`h` frame; near/far from the content's bounding sphere.
    pub fn camera(&self, w: u32, h: u32, centre: Vec3, radius: f32) -> ViewCamera {
        let eye = self.eye();
        let dist = (eye - centre).length();
        let near = ((dist - radius) * 0.5).max(radius * 1e-3).max(1e-4);
        let far = (dist + radius) * 2.0;
        ViewCamera::look_at(eye, self.target, Vec3::Y, self.fov_y, w, h, near, far)
    }

    fn pan(&mut self, dx: f32, dy: f32, h: u32) {
        let eye = self.eye();
        let f = (self.target - eye).normalize_or(Vec3::NEG_Z);
        let right = f.cross(Vec3::Y).normalize_or(Vec3::X);
        let up = right.cross(f);
        let k = 2.0 * self.distance * (0.5 * self.fov_y).tan() / h.max(1) as f32;
        self.target += (-dx * right + dy * up) * k;
    }
}

/// Called before each frame with the seconds since the window opened.
pub type AnimateFn = Box<dyn FnMut(f32, &mut Renderer)>;

/// What the window starts with.
pub struct WindowOptions {
    pub title: String,
    pub size: (u32, u32),
    pub params: SliceParams,
    pub orbit: Orbit,
    /// Linear RGB behind everything.
    pub background: [f32; 3],
    /// Close after this many frames (smoke tests); `None`: until the user quits.
    pub max_frames: Option<u64>,
    /// Called before each frame with the time since start (animation).
    pub animate: Option<AnimateFn>,
    /// Told the steps of building the renderer ([`crate::content::Content::build_with`]).
    pub progress: Option<ProgressFn>,
}

/// [`WindowOptions::progress`].
pub type ProgressFn = Box<dyn FnMut(crate::content::BuildProgress)>;

/// The stats line of a frame.
pub fn stats_line(ms: f64, s: &FrameStats, r: &Renderer) -> String {
    let lods: Vec<String> = s
        .cloud_lods
        .iter()
        .take(6)
        .map(|(l, a)| {
            if *a > 0.0 {
                format!("{l}>{a:.2}")
            } else {
                format!("{l}")
            }
        })
        .collect();
    let adaptive = matches!(r.params.spacing, Spacing::Adaptive { .. });
    let on = |b: bool| if b { "on" } else { "off" };
    format!(
        "{ms:.1} ms  slices {}  slabs {} (+{} empty)  cells {}  inst {}  draws {}{}\n[A]daptive {}  [P]artition {}  [W]ire {}  [S]hadows {}  [R]eset  [Q]uit",
        s.slices,
        s.slabs,
        s.empty_slabs,
        s.cells,
        s.instances,
        s.draw_calls,
        if lods.is_empty() {
            String::new()
        } else {
            format!("  LOD {}", lods.join(","))
        },
        on(adaptive),
        on(r.params.partition),
        on(r.wireframe()),
        on(r.shadows()),
    )
}

struct State {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    renderer: Renderer,
    target: Target,
    resolve: Resolve,
    srgb: bool,
}

struct App {
    content: Content,
    opts: WindowOptions,
    state: Option<State>,
    error: Option<ViewError>,
    home: Orbit,
    orbit: Orbit,
    sphere: (Vec3, f32),
    drag: Option<(MouseButton, f64, f64)>,
    cursor: (f64, f64),
    modifiers: ModifiersState,
    frames: u64,
    start: Instant,
    last_stats: FrameStats,
    /// The last frame's submission: waited for after the next one is submitted.
    in_flight: Option<wgpu::SubmissionIndex>,
    timing: FrameTiming,
    /// The window title last set (set again only when it changes).
    title: String,
}

/// Frame times averaged over about half a second: the interval between frames (what the
/// user sees) and the CPU time of a frame (render, encode, submit).
#[derive(Default)]
struct FrameTiming {
    last_frame: Option<Instant>,
    window_start: Option<Instant>,
    frames: u32,
    interval_s: f64,
    cpu_s: f64,
    /// Shown: (frame ms, CPU ms).
    shown: (f64, f64),
}

impl FrameTiming {
    /// Records a frame that began at `start` and spent `cpu` seconds on the CPU.
    fn record(&mut self, start: Instant, cpu: f64) {
        if let Some(prev) = self.last_frame {
            self.interval_s += (start - prev).as_secs_f64();
            self.cpu_s += cpu;
            self.frames += 1;
        }
        self.last_frame = Some(start);
        let w = *self.window_start.get_or_insert(start);
        if self.frames > 0 && (start - w).as_secs_f64() >= 0.5 {
            let n = f64::from(self.frames);
            self.shown = (1e3 * self.interval_s / n, 1e3 * self.cpu_s / n);
            *self = FrameTiming {
                last_frame: self.last_frame,
                window_start: Some(start),
                shown: self.shown,
                ..Default::default()
            };
        }
    }

    /// After a pause (no frame while idle) the next interval is not a frame time.
    fn idle(&mut self) {
        self.last_frame = None;
        self.window_start = None;
    }
}

impl App {
    fn init(&mut self, el: &ActiveEventLoop) -> Result<State, ViewError> {
        let gpu_err = |e: String| ViewError::Gpu(e);
        let attrs = Window::default_attributes()
            .with_title(self.opts.title.clone())
            .with_inner_size(winit::dpi::PhysicalSize::new(
                self.opts.size.0,
                self.opts.size.1,
            ));
        let window = Arc::new(
            el.create_window(attrs)
                .map_err(|e| gpu_err(format!("cannot open a window: {e}")))?,
        );
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::PRIMARY;
        let instance = wgpu::Instance::new(desc.with_env());
        let surface = instance
            .create_surface(window.clone())
            .map_err(|e| gpu_err(format!("cannot create a surface: {e}")))?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            compatible_surface: Some(&surface),
            ..Default::default()
        }))
        .map_err(|e| ViewError::NoAdapter(e.to_string()))?;
        let gpu = Gpu::from_adapter(instance, adapter)?;
        let size = window.inner_size();
        let (w, h) = (size.width.max(1), size.height.max(1));
        let mut config = surface
            .get_default_config(&gpu.adapter, w, h)
            .ok_or_else(|| gpu_err("the surface does not support this adapter".into()))?;
        let caps = surface.get_capabilities(&gpu.adapter);
        if let Some(f) = caps.formats.iter().find(|f| f.is_srgb()) {
            config.format = *f;
        }
        let srgb = config.format.is_srgb();
        surface.configure(&gpu.device, &config);
        let resolve = Resolve::new(&gpu, config.format);
        let progress = &mut self.opts.progress;
        let renderer =
            self.content
                .build_with(gpu, self.opts.params, self.orbit.fov_y, &mut |p| {
                    if let Some(f) = progress {
                        f(p)
                    }
                })?;
        let target = Target::new(&renderer.gpu, w, h);
        Ok(State {
            window,
            surface,
            config,
            renderer,
            target,
            resolve,
            srgb,
        })
    }

    fn redraw(&mut self) -> Result<(), ViewError> {
        let continuous = self.continuous();
        let Some(st) = &mut self.state else {
            return Ok(());
        };
        if let Some(f) = &mut self.opts.animate {
            f(self.start.elapsed().as_secs_f32(), &mut st.renderer);
        }
        let t = Instant::now();
        let (w, h) = (st.config.width, st.config.height);
        let cam = self.orbit.camera(w, h, self.sphere.0, self.sphere.1);
        let frame = match st.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f)
            | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                st.surface.configure(&st.renderer.gpu.device, &st.config);
                return Ok(());
            }
            _ => return Ok(()),
        };
        let stats = st.renderer.render(&st.target, &cam)?;
        let view = frame.texture.create_view(&Default::default());
        let mut enc = st
            .renderer
            .gpu
            .device
            .create_command_encoder(&Default::default());
        let line = stats_line(self.timing.shown.0, &stats, &st.renderer);
        let line = line.replacen(
            " ms ",
            &format!(" ms (CPU {:.1})  ", self.timing.shown.1),
            1,
        );
        st.resolve.draw(
            &st.renderer.gpu,
            &mut enc,
            &st.target.color_view,
            &view,
            (w, h),
            st.srgb,
            self.opts.background,
            Some(&line),
        );
        st.renderer.gpu.note_pass("resolve");
        let submitted = st.renderer.gpu.queue.submit([enc.finish()]);
        st.window.pre_present_notify();
        st.renderer.gpu.queue.present(frame);
        let cpu = t.elapsed().as_secs_f64();
        // Overlap: wait only for the previous frame, not for this one.
        if let Some(prev) = self.in_flight.replace(submitted) {
            st.renderer.gpu.wait_for(prev)?;
        }
        self.timing.record(t, cpu);
        if !continuous {
            self.timing.idle();
        }
        let title = format!("{} — {}", self.opts.title, line.replace('\n', "  "));
        if title != self.title {
            st.window.set_title(&title);
            self.title = title;
        }
        self.last_stats = stats;
        self.frames += 1;
        Ok(())
    }

    /// Whether frames follow one another without input: the scene animates, or a frame
    /// count was asked for (smoke tests).
    fn continuous(&self) -> bool {
        let animated = self.opts.animate.is_some()
            && self.state.as_ref().is_some_and(|s| s.renderer.animated());
        animated || self.opts.max_frames.is_some()
    }

    fn key(&mut self, el: &ActiveEventLoop, key: &Key) {
        let Some(st) = &mut self.state else {
            return;
        };
        let r = &mut st.renderer;
        match key {
            Key::Named(NamedKey::Escape) => el.exit(),
            Key::Character(c) => match c.to_ascii_lowercase().as_str() {
                "q" => el.exit(),
                "a" => {
                    r.params.spacing = match r.params.spacing {
                        Spacing::Adaptive { .. } => Spacing::Uniform {
                            spacing: self.last_stats.voxel_size.max(1e-6),
                        },
                        Spacing::Uniform { .. } => Spacing::Adaptive { bias: 1.0 },
                    }
                }
                "p" => r.params.partition = !r.params.partition,
                "w" => {
                    let on = !r.wireframe();
                    r.set_wireframe(on);
                }
                "s" => {
                    let on = !r.shadows();
                    r.set_shadows(on);
                }
                "r" => self.orbit = self.home,
                _ => {}
            },
            _ => {}
        }
        st.window.request_redraw();
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.state.is_some() {
            return;
        }
        match self.init(el) {
            Ok(s) => {
                s.window.request_redraw();
                self.state = Some(s);
            }
            Err(e) => {
                self.error = Some(e);
                el.exit();
            }
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => el.exit(),
            WindowEvent::Resized(size) => {
                if let Some(st) = &mut self.state {
                    st.config.width = size.width.max(1);
                    st.config.height = size.height.max(1);
                    st.surface.configure(&st.renderer.gpu.device, &st.config);
                    st.target = Target::new(&st.renderer.gpu, st.config.width, st.config.height);
                    st.window.request_redraw();
                }
            }
            WindowEvent::ModifiersChanged(m) => self.modifiers = m.state(),
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                self.key(el, &event.logical_key)
            }
            WindowEvent::MouseInput { state, button, .. } => {
                self.drag = (state == ElementState::Pressed).then_some((
                    button,
                    self.cursor.0,
                    self.cursor.1,
                ));
            }
            WindowEvent::CursorMoved { position, .. } => {
                self.cursor = (position.x, position.y);
                if let (Some((button, x0, y0)), Some(st)) = (self.drag, &self.state) {
                    let (dx, dy) = ((position.x - x0) as f32, (position.y - y0) as f32);
                    let pan = button == MouseButton::Right
                        || (button == MouseButton::Left && self.modifiers.shift_key());
                    if pan {
                        self.orbit.pan(dx, dy, st.config.height);
                    } else if button == MouseButton::Left {
                        self.orbit.yaw -= dx * 0.01;
                        self.orbit.pitch = (self.orbit.pitch + dy * 0.01).clamp(-1.55, 1.55);
                    }
                    self.drag = Some((button, position.x, position.y));
                    st.window.request_redraw();
                }
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                self.orbit.distance = (self.orbit.distance * 0.9f32.powf(steps)).max(1e-4);
                if let Some(st) = &self.state {
                    st.window.request_redraw();
                }
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw() {
                    self.error = Some(e);
                    el.exit();
                    return;
                }
                if self.opts.max_frames.is_some_and(|n| self.frames >= n) {
                    el.exit();
                } else if let (true, Some(st)) = (self.continuous(), &self.state) {
                    // Animations play; a still scene waits for input.
                    st.window.request_redraw();
                }
            }
            _ => {}
        }
    }
}

/// Opens a window showing `content` until the user closes it (or `max_frames`).
/// Returns the stats of the last frame.
pub fn run(content: Content, opts: WindowOptions) -> Result<FrameStats, ViewError> {
    let el = EventLoop::new().map_err(|e| ViewError::NoDisplay(e.to_string()))?;
    let sphere = match content.bounds() {
        Some((lo, hi)) => (0.5 * (lo + hi), (0.5 * (hi - lo).length()).max(1e-6)),
        None => (Vec3::ZERO, 1.0),
    };
    let mut app = App {
        content,
        home: opts.orbit,
        orbit: opts.orbit,
        opts,
        state: None,
        error: None,
        sphere,
        drag: None,
        cursor: (0.0, 0.0),
        modifiers: ModifiersState::empty(),
        frames: 0,
        start: Instant::now(),
        last_stats: FrameStats::default(),
        in_flight: None,
        timing: FrameTiming::default(),
        title: String::new(),
    };
    el.set_control_flow(ControlFlow::Wait);
    el.run_app(&mut app)
        .map_err(|e| ViewError::Gpu(format!("event loop: {e}")))?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(app.last_stats),
    }
}
