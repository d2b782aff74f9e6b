//! The wgpu instance, adapter, device and queue.
//!
//! The viewer makes its buffers, bind groups and textures through [`Gpu::buffer`],
//! [`Gpu::empty_buffer`], [`Gpu::bind_group`] and [`Gpu::texture`], which count what they
//! make ([`Gpu::resources_created`]): a frame that makes none shows as a count that stops
//! growing (`viewer/tests/frame_resources.rs`). The cloud pass keeps its own count
//! ([`crate::Renderer::cloud_resources_created`]).
//!
//! It also keeps the [`RenderRecord`]: what the renderer built at load (pipelines, LUT
//! bakes, the shadow map) and which passes the last frame encoded, written where each is
//! made or encoded, so tests compare what *runs* with `--print-passes` (issue 25).

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

use crate::ViewError;

/// A device and its queue, with what adapter they came from.
pub struct Gpu {
    pub instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    /// Whether compressed textures (volumes, cloud atlases and normal maps) keep their
    /// BC7 blocks on the GPU where the device can ([`Gpu::block_upload`]): on by default
    /// on hardware adapters (a quarter of RGBA8's memory; volumes are then filtered by
    /// loads in the shader, [`crate::volume_pass::VolumeStorage::Blocks`]); off on
    /// software rasterisers (`DeviceType::Cpu`, e.g. lavapipe), which decode a BC7 block
    /// at every texel fetch and memory is the host's anyway: lavapipe drew the oak demo's
    /// volume 2.6× slower from blocks than decoded, and the `oak_clouds` gallery scene in
    /// 3.1 s a frame against 0.4 s (docs/performance.md). Tests set it to draw both
    /// paths.
    pub sample_blocks: bool,
    /// Buffers, bind groups and textures made through this wrapper so far.
    created: AtomicU64,
    /// Bytes of the assets' textures made so far ([`Gpu::asset_texture`]).
    asset_texture_bytes: AtomicU64,
    record: Mutex<RenderRecord>,
}

/// What the renderer built and encoded, as it did it ([`Gpu::record`]).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct RenderRecord {
    /// Made once, in the order made: `bake:…` (the particle tables and noise),
    /// `pipeline:…` (each render pipeline), `texture:shadow-map`.
    pub built: Vec<&'static str>,
    /// The passes the last frame encoded, in order, each once (`animate:cells`, `shadow`,
    /// `mesh`, `cloud`, `volume`, `particles`, `motion-blur`, `shimmer`, `composite`),
    /// then `resolve` once the frame was read back or shown.
    pub passes: Vec<&'static str>,
}

impl RenderRecord {
    /// The bakes, then the frame's passes: the form of `--print-passes`.
    pub fn pass_list(&self) -> Vec<&'static str> {
        self.built
            .iter()
            .copied()
            .filter(|b| b.starts_with("bake:"))
            .chain(self.passes.iter().copied())
            .collect()
    }

    pub fn built(&self, what: &str) -> bool {
        self.built.contains(&what)
    }
}

impl Gpu {
    /// A device without a window (headless rendering, tests). Backends: the primary ones
    /// (Vulkan, Metal, DX12) unless `WGPU_BACKEND` says otherwise — the GL fallback is not
    /// used by default (through llvmpipe it is ~100× slower than lavapipe and noisy); on
    /// Linux without a GPU, Mesa's lavapipe is the Vulkan adapter.
    ///
    /// Block-compressed textures (BC7, format 1.2) are uploaded as blocks when the adapter
    /// has the BC features and is not a software rasteriser ([`Gpu::block_upload`],
    /// [`Gpu::sample_blocks`]); `BILLOW_VIEW_BC=decode` leaves the features off, so every
    /// compressed texture is decoded on load instead.
    pub fn headless() -> Result<Gpu, ViewError> {
        let decode = std::env::var("BILLOW_VIEW_BC").is_ok_and(|v| v == "decode");
        Self::headless_with(!decode)
    }

    /// [`Gpu::headless`] with the BC features requested (`bc`, when the adapter has them)
    /// or not (every compressed texture decoded on load).
    pub fn headless_with(bc: bool) -> Result<Gpu, ViewError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::PRIMARY;
        let instance = wgpu::Instance::new(desc.with_env());
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            ..Default::default()
        }))
        .map_err(|e| ViewError::NoAdapter(e.to_string()))?;
        Self::from_adapter_with(instance, adapter, bc)
    }

    /// A device on `adapter`, with the BC features when the adapter has them.
    pub fn from_adapter(
        instance: wgpu::Instance,
        adapter: wgpu::Adapter,
    ) -> Result<Gpu, ViewError> {
        Self::from_adapter_with(instance, adapter, true)
    }

    /// A device on `adapter`; `bc`: request the BC texture features the adapter has.
    pub fn from_adapter_with(
        instance: wgpu::Instance,
        adapter: wgpu::Adapter,
        bc: bool,
    ) -> Result<Gpu, ViewError> {
        let info = adapter.get_info();
        let limits = adapter.limits();
        if limits.max_storage_buffers_per_shader_stage < 2 || limits.max_texture_dimension_3d < 16 {
            return Err(ViewError::NoAdapter(format!(
                "adapter {} lacks storage buffers in vertex shaders or 3D textures",
                info.name
            )));
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("billow-view"),
            required_features: if bc {
                adapter.features()
                    & (wgpu::Features::TEXTURE_COMPRESSION_BC
                        | wgpu::Features::TEXTURE_COMPRESSION_BC_SLICED_3D)
            } else {
                wgpu::Features::empty()
            },
            required_limits: limits,
            ..Default::default()
        }))
        .map_err(|e| ViewError::Gpu(format!("cannot create a device on {}: {e}", info.name)))?;
        Ok(Gpu {
            instance,
            adapter,
            device,
            queue,
            sample_blocks: info.device_type != wgpu::DeviceType::Cpu,
            info,
            created: AtomicU64::new(0),
            asset_texture_bytes: AtomicU64::new(0),
            record: Mutex::new(RenderRecord::default()),
        })
    }

    /// Whether a BC7 texture of `dims` (`d3`: a 3D texture) is uploaded as its blocks:
    /// blocks are wanted ([`Gpu::sample_blocks`]), the device has
    /// `TEXTURE_COMPRESSION_BC` (and `TEXTURE_COMPRESSION_BC_SLICED_3D` for 3D) and level
    /// 0's width and height are multiples of the 4×4 block. Otherwise the viewer uploads
    /// the decoded texels.
    pub fn block_upload(&self, dims: [u32; 3], d3: bool) -> bool {
        let f = self.device.features();
        self.sample_blocks
            && f.contains(wgpu::Features::TEXTURE_COMPRESSION_BC)
            && (!d3 || f.contains(wgpu::Features::TEXTURE_COMPRESSION_BC_SLICED_3D))
            && dims[0].is_multiple_of(4)
            && dims[1].is_multiple_of(4)
    }

    /// "name (backend, device type)".
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {:?})",
            self.info.name, self.info.backend, self.info.device_type
        )
    }

    /// Buffers, bind groups and textures made through [`Gpu::buffer`],
    /// [`Gpu::empty_buffer`], [`Gpu::bind_group`], [`Gpu::texture`] (and the helpers built
    /// on them) since the device was made.
    pub fn resources_created(&self) -> u64 {
        self.created.load(Ordering::Relaxed)
    }

    fn count(&self) {
        self.created.fetch_add(1, Ordering::Relaxed);
    }

    /// What was built and what the last frame encoded ([`RenderRecord`]).
    pub fn record(&self) -> RenderRecord {
        self.record
            .lock()
            .map_or_else(|e| e.into_inner().clone(), |r| r.clone())
    }

    fn with_record(&self, f: impl FnOnce(&mut RenderRecord)) {
        match self.record.lock() {
            Ok(mut r) => f(&mut r),
            Err(e) => f(&mut e.into_inner()),
        }
    }

    /// Notes something built once (a pipeline, a bake, the shadow map).
    pub fn note_built(&self, what: &'static str) {
        self.with_record(|r| r.built.push(what));
    }

    /// Starts the record of a frame's passes.
    pub fn note_frame_start(&self) {
        self.with_record(|r| r.passes.clear());
    }

    /// Notes that the frame encoded `pass` (once per frame: cascades and time samples
    /// repeat it).
    pub fn note_pass(&self, pass: &'static str) {
        self.with_record(|r| {
            if !r.passes.contains(&pass) {
                r.passes.push(pass)
            }
        });
    }

    /// An uninitialised buffer of `size` bytes (at least 4) for `usage`.
    pub fn empty_buffer(&self, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
        self.count();
        self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: size.max(4).next_multiple_of(4),
            usage,
            mapped_at_creation: false,
        })
    }

    /// A bind group (counted).
    pub fn bind_group(&self, desc: &wgpu::BindGroupDescriptor<'_>) -> wgpu::BindGroup {
        self.count();
        self.device.create_bind_group(desc)
    }

    /// A texture (counted).
    pub fn texture(&self, desc: &wgpu::TextureDescriptor<'_>) -> wgpu::Texture {
        self.count();
        self.device.create_texture(desc)
    }

    /// A texture of an asset (a volume's colour or normals, a cloud's atlas, normal map or
    /// mesh texture), counted and its bytes added to [`Gpu::asset_texture_bytes`].
    pub fn asset_texture(&self, desc: &wgpu::TextureDescriptor<'_>) -> wgpu::Texture {
        self.asset_texture_bytes
            .fetch_add(texture_bytes(desc), Ordering::Relaxed);
        self.texture(desc)
    }

    /// Bytes of every asset texture made so far, all MIP levels (what
    /// `billow_core::gpu_memory` predicts for the assets uploaded).
    pub fn asset_texture_bytes(&self) -> u64 {
        self.asset_texture_bytes.load(Ordering::Relaxed)
    }

    /// A buffer holding `contents`, for `usage`.
    pub fn buffer(&self, label: &str, contents: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
        use wgpu::util::DeviceExt;
        self.count();
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
    }

    /// A bind group of a uniform buffer made from `uniform` (binding 0), a texture
    /// (binding 1) and a sampler (binding 2): the mesh and cloud materials
    /// ([`crate::layout::material_layout`]) and the resolve pass.
    pub fn uniform_texture_bind_group(
        &self,
        label: &str,
        layout: &wgpu::BindGroupLayout,
        uniform: &[u8],
        view: &wgpu::TextureView,
        sampler: &wgpu::Sampler,
    ) -> wgpu::BindGroup {
        let buf = self.buffer(label, uniform, wgpu::BufferUsages::UNIFORM);
        self.bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: buf.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Sampler(sampler),
                },
            ],
        })
    }

    /// Blocks until submission `index` has finished.
    pub fn wait_for(&self, index: wgpu::SubmissionIndex) -> Result<(), ViewError> {
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(index),
                timeout: None,
            })
            .map(|_| ())
            .map_err(|e| ViewError::Gpu(e.to_string()))
    }

    /// Blocks until the queue is idle.
    pub fn wait(&self) -> Result<(), ViewError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| ViewError::Gpu(e.to_string()))
    }

    /// Maps `buffer` (`MAP_READ`, its copies already submitted) once the queue is idle,
    /// hands its bytes to `read` and unmaps it.
    pub fn read_mapped<T>(
        &self,
        buffer: &wgpu::Buffer,
        read: impl FnOnce(&[u8]) -> T,
    ) -> Result<T, ViewError> {
        let slice = buffer.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.wait()?;
        rx.recv()
            .map_err(|e| ViewError::Gpu(e.to_string()))?
            .map_err(|e| ViewError::Gpu(format!("read-back: {e}")))?;
        let out = {
            let bytes = slice
                .get_mapped_range()
                .map_err(|e| ViewError::Gpu(format!("read-back: {e}")))?;
            read(&bytes)
        };
        buffer.unmap();
        Ok(out)
    }
}

/// A buffer kept from frame to frame and written with `queue.write_buffer`; made again,
/// bigger (a power of two of bytes, at least 256), only when the data outgrows it.
pub struct GrowBuffer {
    pub buffer: wgpu::Buffer,
    capacity: u64,
    label: &'static str,
    usage: wgpu::BufferUsages,
}

impl GrowBuffer {
    /// An empty buffer of 256 bytes for `usage` (`COPY_DST` is added).
    pub fn new(gpu: &Gpu, label: &'static str, usage: wgpu::BufferUsages) -> GrowBuffer {
        let usage = usage | wgpu::BufferUsages::COPY_DST;
        GrowBuffer {
            buffer: gpu.empty_buffer(label, 256, usage),
            capacity: 256,
            label,
            usage,
        }
    }

    /// Writes `bytes` at the start (a multiple of 4 bytes long); returns whether the
    /// buffer was made again (bind groups holding the old one must be remade).
    pub fn write(&mut self, gpu: &Gpu, bytes: &[u8]) -> bool {
        let n = bytes.len() as u64;
        let grown = n > self.capacity;
        if grown {
            self.capacity = n.next_power_of_two().max(256);
            self.buffer = gpu.empty_buffer(self.label, self.capacity, self.usage);
        }
        if n > 0 {
            gpu.queue.write_buffer(&self.buffer, 0, bytes);
        }
        grown
    }
}

/// Bytes of a texture made from `desc`, every MIP level (block formats by whole blocks).
pub fn texture_bytes(desc: &wgpu::TextureDescriptor<'_>) -> u64 {
    let (bw, bh) = desc.format.block_dimensions();
    let block = u64::from(desc.format.block_copy_size(None).unwrap_or(4));
    let s = desc.size;
    (0..desc.mip_level_count)
        .map(|l| {
            let w = (s.width >> l).max(1);
            let h = (s.height >> l).max(1);
            let d = match desc.dimension {
                wgpu::TextureDimension::D3 => (s.depth_or_array_layers >> l).max(1),
                _ => s.depth_or_array_layers,
            };
            u64::from(w.div_ceil(bw)) * u64::from(h.div_ceil(bh)) * u64::from(d) * block
        })
        .sum()
}
