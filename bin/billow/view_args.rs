//! The arguments of `billow view` (bin/billow/view.rs runs the command) and the window's
//! controls its help ends with.

use std::path::PathBuf;

/// The window's controls, shown after `billow view --help`'s flags (docs/viewer.md).
pub const WINDOW_HELP: &str = "\
In the window:
  left drag        orbit
  right drag       pan (or shift + left drag)
  wheel            zoom
  A                adaptive <-> uniform slicing (one level-0 voxel apart)
  P                slab partitioning on/off
  W                cell wireframe on/off
  S                shadows on/off
  R                reset the camera
  Q, Esc           quit";

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A scene file (.ron), a volume asset (.billow) or a mesh (.gltf, .glb, .obj).
    pub(crate) target: PathBuf,
    /// Render without a window (no display needed); needs --screenshot.
    #[arg(long)]
    pub(crate) headless: bool,
    /// Write the frame here as an sRGB PNG (straight alpha), atomically.
    #[arg(long, value_name = "OUT.png")]
    pub(crate) screenshot: Option<PathBuf>,
    /// Image size WxH in pixels, each side 1–4096.
    #[arg(long, default_value = "512x512")]
    pub(crate) size: String,
    /// Camera position X,Y,Z (overrides the scene's camera); looks at --look-at.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub(crate) eye: Option<String>,
    /// Point the camera looks at (default: the centre of the content).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub(crate) look_at: Option<String>,
    /// Without --eye: the direction the camera looks along, named like eval's views
    /// (`-z`, `+x-y-z`); the content's bounding sphere just fills the image at distance 1.
    #[arg(long, default_value = "+x-y-z", allow_hyphen_values = true)]
    pub(crate) view: String,
    /// Without --eye: multiple of the framed distance, > 0.
    #[arg(long, default_value_t = 1.0)]
    pub(crate) distance: f32,
    /// Vertical field of view in degrees, in (0, 180) (overrides the scene's).
    #[arg(long)]
    pub(crate) fov: Option<f32>,
    /// Slice spacing: adaptive (the paper: one pixel's footprint, never finer than a
    /// voxel), adaptive:BIAS, or uniform:WORLD (a constant world-space spacing).
    #[arg(long, default_value = "adaptive")]
    pub(crate) spacing: String,
    /// Turn slab partitioning off (every cell meets every slice: the paper's plain slicing).
    #[arg(long)]
    pub(crate) no_partition: bool,
    /// Fewest slices per slab when partitioning, ≥ 1.
    #[arg(long, default_value_t = 16)]
    pub(crate) slab_min_slices: u32,
    /// Shadows on or off, overriding the scene's `shadows`.
    #[arg(long, value_name = "on|off")]
    pub(crate) shadows: Option<String>,
    /// Resolution of the particle layer, overriding the scene's `particle_layer`:
    /// full, half, quarter or eighth of the frame.
    #[arg(long, value_name = "FRACTION")]
    pub(crate) particle_layer: Option<String>,
    /// Draw every particle system as spherical billboards or as flat (planar) ones,
    /// overriding each system's `mode`.
    #[arg(long, value_name = "spherical|planar")]
    pub(crate) particle_mode: Option<String>,
    /// Scene time in seconds (particle animation, animated cells); the window plays
    /// from here.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub(crate) time: f32,
    /// Choose cloud LODs as if every instance were this far from the eye (inspection), > 0.
    #[arg(long, value_name = "DISTANCE")]
    pub(crate) lod_distance: Option<f32>,
    /// Half-width, in octaves of distance, of the dithered dissolve around each cloud LOD
    /// switch, in [0, 4] (overrides the scene's `dissolve`; default 0.375; 0 = switch in
    /// one frame).
    #[arg(long, value_name = "OCTAVES")]
    pub(crate) dissolve: Option<f32>,
    /// Sweep the LOD switches of the scene's one billboard cloud: dolly along --view at
    /// constant screen size across every switch distance, write the frames on either side
    /// of each switch (DIR/switch_K.png), DIR/sweep.json and DIR/sweep.md, and print the
    /// table (docs/bbcloud.md, "LOD switches"); --size sets the frame. Exit 0 whether or not
    /// the targets are met (they are in the JSON's `pass` fields).
    #[arg(long, value_name = "DIR")]
    pub(crate) lod_sweep: Option<PathBuf>,
    /// With --lod-sweep: keep the cloud's bounding sphere at this fraction of the frame
    /// height at every switch, in (0, 4] (default: each switch at the size the viewer shows
    /// it at with --fov).
    #[arg(long, value_name = "F")]
    pub(crate) sweep_fill: Option<f32>,
    /// Print the passes a frame runs (one per line) and exit; needs no GPU.
    #[arg(long)]
    pub(crate) print_passes: bool,
    /// Render this many frames, ≥ 1 (timing: mean and minimum frame time are reported).
    /// Headless default 1; in a window: close after N frames (default: when closed).
    #[arg(long)]
    pub(crate) frames: Option<u32>,
    /// Headless: orbit the camera this many degrees a frame about the vertical axis
    /// through its target (frame k seen from k·DEG, the first from the camera given), so
    /// that no frame can reuse the last one's shadow atlas: what a moving camera pays.
    /// The screenshot is the last frame's.
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub(crate) orbit: f32,
    /// Composite the screenshot over this opaque linear colour R,G,B, each in [0, 1] (default: keep a
    /// transparent background).
    #[arg(long, value_name = "R,G,B")]
    pub(crate) background: Option<String>,
    /// Draw the edges of every volume cell over the frame (`W` in the window).
    #[arg(long)]
    pub(crate) wireframe: bool,
    /// Print a JSON summary on stdout.
    #[arg(long)]
    pub(crate) json: bool,
}
