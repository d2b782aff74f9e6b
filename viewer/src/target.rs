//! The offscreen render target (Rgba16Float colour, Depth32Float) and its read-back.

use crate::texture::desc_2d;
use crate::{Gpu, ViewError};

pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Premultiplied linear RGBA, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbaImage {
    pub width: u32,
    pub height: u32,
    pub data: Vec<[f32; 4]>,
}

pub struct Target {
    pub width: u32,
    pub height: u32,
    pub color: wgpu::Texture,
    pub color_view: wgpu::TextureView,
    pub depth_view: wgpu::TextureView,
    /// The volume pass's bind group of `depth_view` (made on first use, kept with the
    /// target so a frame allocates none).
    pub scene_depth: std::cell::OnceCell<wgpu::BindGroup>,
}

impl Target {
    pub fn new(gpu: &Gpu, width: u32, height: u32) -> Target {
        let make = |format, usage, label| {
            gpu.device
                .create_texture(&desc_2d(label, width, height, format, usage))
        };
        let color = make(
            COLOR_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::TEXTURE_BINDING,
            "colour",
        );
        // Sampled by the particle pass (spherical billboards clip against it) and the
        // volume pass (slices fade at it).
        let depth = make(
            DEPTH_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            "depth",
        );
        Target {
            width,
            height,
            color_view: color.create_view(&Default::default()),
            depth_view: depth.create_view(&Default::default()),
            scene_depth: std::cell::OnceCell::new(),
            color,
        }
    }

    /// Copies the colour target back to the CPU (waits for the GPU).
    pub fn read(&self, gpu: &Gpu) -> Result<RgbaImage, ViewError> {
        let row = u64::from(self.width) * 8;
        let align = u64::from(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let padded = row.div_ceil(align) * align;
        let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("read-back"),
            size: padded * u64::from(self.height),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.color,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded as u32),
                    rows_per_image: Some(self.height),
                },
            },
            wgpu::Extent3d {
                width: self.width,
                height: self.height,
                depth_or_array_layers: 1,
            },
        );
        gpu.queue.submit([enc.finish()]);
        let (width, height) = (self.width as usize, self.height as usize);
        let data = gpu.read_mapped(&buffer, |bytes| {
            let mut data = Vec::with_capacity(width * height);
            for y in 0..height {
                let r = &bytes[y * padded as usize..y * padded as usize + row as usize];
                for px in r.chunks_exact(8) {
                    let h =
                        |i: usize| half::f16::from_le_bytes([px[2 * i], px[2 * i + 1]]).to_f32();
                    data.push([h(0), h(1), h(2), h(3)]);
                }
            }
            data
        })?;
        Ok(RgbaImage {
            width: self.width,
            height: self.height,
            data,
        })
    }
}
