//! What the particle layer is and what it needs (scene file `particle_layer`), and the
//! tables and textures baked for it — only those its systems need ([`ParticleNeeds`]):
//! the phase LUT with dust or smoke, the black-body LUT with fire, the detail noise when
//! some system has `detail > 0` or with heat shimmer. A LUT a scene does not need is a
//! 1×1 stand-in, never sampled; the noise is not made at all without it.

use serde::Deserialize;
use wgpu::util::DeviceExt;

use crate::particles::{blackbody, noise, phase, ParticleKind, ParticleSystemDesc};
use crate::texture::desc_2d;
use crate::Gpu;

/// Resolution of the particle layer relative to the frame (the paper's Figure 7).
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
pub enum LayerResolution {
    #[default]
    Full,
    Half,
    Quarter,
    Eighth,
}

impl LayerResolution {
    pub fn divisor(self) -> u32 {
        match self {
            LayerResolution::Full => 1,
            LayerResolution::Half => 2,
            LayerResolution::Quarter => 4,
            LayerResolution::Eighth => 8,
        }
    }
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MotionBlur {
    /// Seconds before the frame's time covered by the samples.
    pub shutter: f32,
    /// Time samples averaged (≥ 2).
    pub samples: u32,
}

/// How the particle layer is made (scene file `particle_layer`).
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ParticleLayerDesc {
    #[serde(default)]
    pub resolution: LayerResolution,
    /// Heat shimmer: the largest offset, in layer pixels; absent: none.
    #[serde(default)]
    pub shimmer: Option<f32>,
    #[serde(default)]
    pub motion_blur: Option<MotionBlur>,
}

impl ParticleLayerDesc {
    pub fn validate(&self) -> Result<(), String> {
        if let Some(s) = self.shimmer {
            if !(0.0..=64.0).contains(&s) {
                return Err(format!("shimmer: {s} must be in [0, 64] pixels"));
            }
        }
        if let Some(m) = self.motion_blur {
            if !(m.shutter > 0.0 && m.shutter.is_finite() && (2..=32).contains(&m.samples)) {
                return Err(format!(
                    "motion_blur: shutter {} must be > 0 and samples {} from 2 to 32",
                    m.shutter, m.samples
                ));
            }
        }
        Ok(())
    }
}

/// What a set of particle systems needs built.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ParticleNeeds {
    pub any: bool,
    /// Dust or smoke: the phase LUT.
    pub scattering: bool,
    pub fire: bool,
    pub shimmer: bool,
    pub motion_blur: bool,
    /// The detail noise: some system has `detail > 0`, or heat shimmer (its offsets are
    /// noise). Without it the noise is neither baked nor bound, and the particle shader
    /// is built without the code that samples it.
    pub detail: bool,
}

impl ParticleNeeds {
    pub fn of(systems: &[ParticleSystemDesc], layer: &ParticleLayerDesc) -> ParticleNeeds {
        let fire = systems.iter().any(|s| s.kind == ParticleKind::Fire);
        let shimmer = fire && layer.shimmer.is_some_and(|s| s > 0.0);
        ParticleNeeds {
            any: !systems.is_empty(),
            scattering: systems.iter().any(|s| s.kind != ParticleKind::Fire),
            fire,
            shimmer,
            motion_blur: !systems.is_empty() && layer.motion_blur.is_some(),
            detail: shimmer || systems.iter().any(|s| s.detail > 0.0),
        }
    }
}

/// The baked tables and textures the particle shader samples.
pub(crate) struct Bakes {
    /// Only with [`ParticleNeeds::detail`].
    pub detail: Option<wgpu::TextureView>,
    pub phase: wgpu::TextureView,
    pub blackbody: wgpu::TextureView,
    pub dummy: wgpu::TextureView,
}

impl Bakes {
    pub fn new(gpu: &Gpu, needs: ParticleNeeds) -> Bakes {
        let detail = needs.detail.then(|| {
            gpu.note_built("bake:detail-noise");
            gpu.device
                .create_texture_with_data(
                    &gpu.queue,
                    &wgpu::TextureDescriptor {
                        label: Some("detail noise"),
                        size: wgpu::Extent3d {
                            width: noise::SIDE as u32,
                            height: noise::SIDE as u32,
                            depth_or_array_layers: noise::FRAMES as u32,
                        },
                        mip_level_count: 1,
                        sample_count: 1,
                        dimension: wgpu::TextureDimension::D3,
                        format: wgpu::TextureFormat::R8Unorm,
                        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                        view_formats: &[],
                    },
                    wgpu::util::TextureDataOrder::LayerMajor,
                    &noise::detail_texture(7),
                )
                .create_view(&Default::default())
        });
        let dummy = texture_2d(gpu, 1, 1, wgpu::TextureFormat::Rgba16Float, &[0; 8]);
        let phase = if needs.scattering {
            gpu.note_built("bake:phase-lut");
            let lut = phase::lut();
            texture_2d(
                gpu,
                phase::MU as u32,
                phase::G as u32,
                wgpu::TextureFormat::R16Float,
                &f16_bytes(lut.into_iter()),
            )
        } else {
            texture_2d(gpu, 1, 1, wgpu::TextureFormat::R16Float, &[0; 2])
        };
        let blackbody = if needs.fire {
            gpu.note_built("bake:blackbody-lut");
            let lut = blackbody::lut();
            texture_2d(
                gpu,
                blackbody::N as u32,
                1,
                wgpu::TextureFormat::Rgba16Float,
                &f16_bytes(lut.iter().flat_map(|c| [c[0], c[1], c[2], 1.0])),
            )
        } else {
            texture_2d(gpu, 1, 1, wgpu::TextureFormat::Rgba16Float, &[0; 8])
        };
        Bakes {
            detail,
            phase,
            blackbody,
            dummy,
        }
    }
}

fn texture_2d(
    gpu: &Gpu,
    w: u32,
    h: u32,
    format: wgpu::TextureFormat,
    data: &[u8],
) -> wgpu::TextureView {
    let t = gpu.device.create_texture_with_data(
        &gpu.queue,
        &desc_2d(
            "particle LUT",
            w,
            h,
            format,
            wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        ),
        wgpu::util::TextureDataOrder::LayerMajor,
        data,
    );
    t.create_view(&Default::default())
}

fn f16_bytes(v: impl Iterator<Item = f32>) -> Vec<u8> {
    v.flat_map(|x| half::f16::from_f32(x).to_le_bytes())
        .collect()
}
