//! The resolve pass and the on-screen stats line, shared by the window (and usable
//! off-screen): the Rgba16Float frame (premultiplied linear) is composited over a
//! background colour and written to an 8-bit target; a line of text (an 8×8 bitmap
//! font, `font8x8`) is blended on top. The uniforms and bind groups are kept from frame
//! to frame; the text is rasterised again only when it changes.

use font8x8::UnicodeFonts;

use crate::layout::{color_target, entry, sampler, shader, texture, uniform, Pipeline};
use crate::Gpu;

/// Rasterizes `text` (ASCII; other characters show as `?`; `\n` starts a line) into
/// straight-alpha RGBA8, `scale`× the 8×8 glyphs, white on a translucent black band.
/// Returns (w, h, texels).
pub fn text_image(text: &str, scale: u32) -> (u32, u32, Vec<u8>) {
    let lines: Vec<Vec<char>> = text.lines().map(|l| l.chars().collect()).collect();
    let cols = lines.iter().map(Vec::len).max().unwrap_or(0).max(1) as u32;
    let rows = lines.len().max(1) as u32;
    let s = scale.max(1);
    let (w, h) = ((cols * 8 + 4) * s, (rows * 10 + 2) * s);
    let mut img = vec![0u8; (w * h * 4) as usize];
    for px in img.chunks_exact_mut(4) {
        px.copy_from_slice(&[0, 0, 0, 150]);
    }
    for (li, line) in lines.iter().enumerate() {
        for (i, ch) in line.iter().enumerate() {
            let glyph = font8x8::BASIC_FONTS
                .get(*ch)
                .or_else(|| font8x8::BASIC_FONTS.get('?'))
                .unwrap_or([0; 8]);
            for (gy, row) in glyph.iter().enumerate() {
                for gx in 0..8 {
                    if row & (1 << gx) == 0 {
                        continue;
                    }
                    for dy in 0..s {
                        for dx in 0..s {
                            let x = (2 + i as u32 * 8 + gx) * s + dx;
                            let y = (2 + li as u32 * 10 + gy as u32) * s + dy;
                            let o = ((y * w + x) * 4) as usize;
                            img[o..o + 4].copy_from_slice(&[255, 255, 255, 255]);
                        }
                    }
                }
            }
        }
    }
    (w, h, img)
}

/// `text` with every line longer than `cols` characters broken at the last field gap
/// (two spaces) that fits, else at the last space, else at `cols`: the stats line stays
/// whole on a narrow window (at 480 px, 58 columns of the 8-px font).
pub fn wrap(text: &str, cols: usize) -> String {
    let cols = cols.max(8);
    let mut out: Vec<String> = Vec::new();
    for line in text.lines() {
        let mut rest: Vec<char> = line.chars().collect();
        while rest.len() > cols {
            let head: String = rest[..=cols].iter().collect();
            let cut = head
                .rfind("  ")
                .filter(|&i| i > 0)
                .or_else(|| head.rfind(' ').filter(|&i| i > 0))
                .map_or(cols, |i| head[..i].chars().count());
            let (a, b) = rest.split_at(cut);
            out.push(a.iter().collect::<String>().trim_end().to_string());
            rest = b.iter().skip_while(|c| **c == ' ').copied().collect();
            if rest.is_empty() {
                break;
            }
        }
        out.push(rest.into_iter().collect());
    }
    out.join("\n")
}

/// The resolve + overlay pipelines for one output format, and what they draw with,
/// kept from frame to frame.
pub struct Resolve {
    pipeline: wgpu::RenderPipeline,
    overlay: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    /// The two uniforms (the frame's, the text's), made once.
    uniforms: [wgpu::Buffer; 2],
    cache: std::cell::RefCell<Cache>,
}

/// The frame's bind group (for the frame view it was made with) and the stats texture:
/// re-rasterised only when the text or its scale changes, written into the same
/// texture while its size stays, made again otherwise.
#[derive(Default)]
struct Cache {
    frame: Option<(wgpu::TextureView, wgpu::BindGroup)>,
    text: Option<TextTexture>,
}

struct TextTexture {
    text: String,
    scale: u32,
    size: (u32, u32),
    texture: wgpu::Texture,
    bind: wgpu::BindGroup,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ResolveUniform {
    /// Background colour (linear), then x: 1 = encode sRGB in the shader (the output is
    /// a non-sRGB format), y..: overlay rectangle in NDC (x0, y0, x1, y1).
    background: [f32; 4],
    flags: [f32; 4],
    rect: [f32; 4],
}

impl Resolve {
    pub fn new(gpu: &Gpu, format: wgpu::TextureFormat) -> Resolve {
        let device = &gpu.device;
        let module = shader(
            device,
            "resolve.wgsl",
            &[
                include_str!("shaders/fullscreen.wgsl"),
                include_str!("shaders/resolve.wgsl"),
            ],
        );
        let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("resolve"),
            entries: &[
                entry(0, vf, uniform(false)),
                entry(1, vf, texture(wgpu::TextureViewDimension::D2)),
                entry(2, vf, sampler()),
            ],
        });
        let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("resolve"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let make = |vs, fs, blend| {
            Pipeline {
                vs,
                fs,
                target: color_target(format, blend),
                ..Pipeline::new("resolve", &pl, &module)
            }
            .build(device)
        };
        let pipeline = make("vs_full", "fs_resolve", None);
        let overlay = make(
            "vs_rect",
            "fs_overlay",
            Some(wgpu::BlendState::ALPHA_BLENDING),
        );
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("resolve"),
            ..Default::default()
        });
        let uniforms = ["resolve", "stats line"].map(|label| {
            gpu.empty_buffer(
                label,
                std::mem::size_of::<ResolveUniform>() as u64,
                wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            )
        });
        Resolve {
            pipeline,
            overlay,
            layout,
            sampler,
            uniforms,
            cache: Default::default(),
        }
    }

    /// The bind group of uniform `i` and `view`.
    fn bind(&self, gpu: &Gpu, i: usize, view: &wgpu::TextureView) -> wgpu::BindGroup {
        gpu.bind_group(&wgpu::BindGroupDescriptor {
            label: Some("resolve"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: self.uniforms[i].as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Sampler(&self.sampler),
                },
            ],
        })
    }

    /// The stats texture showing `text` at `scale` (straight alpha, sRGB, one level):
    /// kept when the text is the same, rewritten when only the text changed, made again
    /// when its size changed. Returns its size.
    fn text_texture(
        &self,
        gpu: &Gpu,
        cache: &mut Option<TextTexture>,
        text: &str,
        scale: u32,
    ) -> (u32, u32) {
        if let Some(t) = cache {
            if t.text == text && t.scale == scale {
                return t.size;
            }
        }
        let (w, h, texels) = text_image(text, scale);
        let same_size = cache.as_ref().is_some_and(|t| t.size == (w, h));
        if !same_size {
            let texture = gpu.texture(&crate::texture::desc_2d(
                "stats line",
                w,
                h,
                wgpu::TextureFormat::Rgba8UnormSrgb,
                wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            ));
            let bind = self.bind(gpu, 1, &texture.create_view(&Default::default()));
            *cache = Some(TextTexture {
                text: String::new(),
                scale,
                size: (w, h),
                texture,
                bind,
            });
        }
        let t = cache.as_mut().expect("made above");
        crate::texture::write_level(gpu, &t.texture, 0, &texels, (w, h));
        t.text = text.to_string();
        t.scale = scale;
        (w, h)
    }

    /// Composites `frame` over `background` into `out` (`srgb_out`: the output format
    /// encodes sRGB itself), then blends the text line `text` at the top left.
    #[allow(clippy::too_many_arguments)]
    pub fn draw(
        &self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        frame: &wgpu::TextureView,
        out: &wgpu::TextureView,
        out_size: (u32, u32),
        srgb_out: bool,
        background: [f32; 3],
        text: Option<&str>,
    ) {
        let flags = [f32::from(u8::from(!srgb_out)), 0.0, 0.0, 0.0];
        let u = ResolveUniform {
            background: [background[0], background[1], background[2], 1.0],
            flags,
            rect: [-1.0, -1.0, 1.0, 1.0],
        };
        let mut cache = self.cache.borrow_mut();
        let cache = &mut *cache;
        gpu.queue
            .write_buffer(&self.uniforms[0], 0, bytemuck::bytes_of(&u));
        if cache.frame.as_ref().is_none_or(|(v, _)| v != frame) {
            cache.frame = Some((frame.clone(), self.bind(gpu, 0, frame)));
        }
        let main = &cache.frame.as_ref().expect("made above").1;
        let overlay = match text {
            Some(t) => {
                let scale = if out_size.0 >= 1400 { 2 } else { 1 };
                // Wrapped to the frame's width (the text image is (cols × 8 + 4) × scale).
                let cols = (out_size.0 / scale).saturating_sub(4) / 8;
                let (w, h) =
                    self.text_texture(gpu, &mut cache.text, &wrap(t, cols as usize), scale);
                let (ow, oh) = (out_size.0.max(1) as f32, out_size.1.max(1) as f32);
                let rect = [
                    -1.0,
                    1.0 - 2.0 * h as f32 / oh,
                    -1.0 + 2.0 * w as f32 / ow,
                    1.0,
                ];
                gpu.queue.write_buffer(
                    &self.uniforms[1],
                    0,
                    bytemuck::bytes_of(&ResolveUniform { rect, ..u }),
                );
                cache.text.as_ref().map(|t| &t.bind)
            }
            None => None,
        };
        let mut rp = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("resolve"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: out,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        rp.set_pipeline(&self.pipeline);
        rp.set_bind_group(0, main, &[]);
        rp.draw(0..3, 0..1);
        if let Some(o) = overlay {
            rp.set_pipeline(&self.overlay);
            rp.set_bind_group(0, o, &[]);
            rp.draw(0..6, 0..1);
        }
    }
}

#[cfg(test)]
mod tests {
    /// The window's stats line (two lines, ~95 and ~80 columns) at 480 px: every line
    /// fits 58 columns and nothing is lost. Before, the lines were drawn whole and cut off
    /// at the window's edge.
    #[test]
    fn stats_line_wraps_to_a_narrow_window() {
        let line = "16.7 ms  slices 412  slabs 12 (+3 empty)  cells 96  inst 4800  draws 14  LOD 0,1>0.35,2\n\
                    [A]daptive on  [P]artition on  [W]ire off  [S]hadows on  [R]eset  [Q]uit";
        let cols = (480 - 4) / 8;
        let w = super::wrap(line, cols);
        for l in w.lines() {
            assert!(l.chars().count() <= cols, "{l:?} is wider than {cols}");
        }
        let words = |s: &str| s.split_whitespace().map(str::to_owned).collect::<Vec<_>>();
        assert_eq!(words(&w), words(line));
        assert!(w.lines().count() >= 3);
        let (tw, _, _) = super::text_image(&w, 1);
        assert!(tw <= 480, "text image {tw} px wide");
        // A wide window keeps the lines as they are.
        assert_eq!(super::wrap(line, 200), line);
    }

    #[test]
    fn text_is_drawn_in_white_on_a_band() {
        let (w, h, img) = super::text_image("A1", 1);
        assert_eq!((w, h), (20, 12));
        let white = img
            .chunks_exact(4)
            .filter(|p| p == &[255, 255, 255, 255])
            .count();
        assert!(white > 10, "glyph pixels: {white}");
        assert_eq!(&img[0..4], &[0, 0, 0, 150]);
        // Two lines, doubled: the band grows by a line, the width follows the longest.
        let (w2, h2, _) = super::text_image("A1\nBCD", 2);
        assert_eq!((w2, h2), (56, 44));
    }
}
