//! glTF buffers and accessors, resolved and bounds-checked by hand.
//!
//! Every length is checked against the bytes actually present before anything is
//! allocated: an accessor can never produce more elements than its bufferView can hold
//! (accessors without a bufferView are capped at [`MAX_ZERO_FILLED`]).

use std::io::Read;
use std::path::{Path, PathBuf};

use ::gltf::json;
use glam::Vec4;
use json::accessor::{ComponentType, GenericComponentType, IndexComponentType, Type};
use json::validation::Checked;

use super::{images, percent_decode, resolve_relative, Ctx, ImportError};

/// Largest element count accepted for an accessor that has no bufferView (all zeros).
pub const MAX_ZERO_FILLED: u64 = 1 << 24;

pub(super) struct Buffers<'a> {
    root: &'a json::Root,
    blob: Option<Vec<u8>>,
    base: &'a Path,
    data: Vec<Option<Vec<u8>>>,
}

impl<'a> Buffers<'a> {
    pub fn new(root: &'a json::Root, blob: Option<Vec<u8>>, base: &'a Path) -> Self {
        Buffers {
            root,
            blob,
            base,
            data: vec![None; root.buffers.len()],
        }
    }

    /// The bytes of buffer `i` (loaded on first use), exactly `byteLength` long.
    fn get(&mut self, i: usize, ctx: &Ctx) -> Result<&[u8], ImportError> {
        let buf = self
            .root
            .buffers
            .get(i)
            .ok_or_else(|| ctx.invalid(format!("buffer {i} does not exist")))?;
        if self.data[i].is_none() {
            let declared = buf.byte_length.0;
            let mut bytes = match &buf.uri {
                None if i == 0 && self.blob.is_some() => self.blob.take().unwrap_or_default(),
                None => {
                    return Err(ctx.invalid(format!(
                        "buffer {i} has no uri and there is no GLB binary chunk"
                    )))
                }
                Some(uri) if uri.starts_with("data:") => {
                    images::parse_data_uri(uri)
                        .map_err(|e| ctx.invalid(format!("buffer {i}: {e}")))?
                        .1
                }
                Some(uri) if uri.contains("://") => {
                    return Err(
                        ctx.unsupported(format!("buffer {i}: external URI {uri} is not fetched"))
                    )
                }
                Some(uri) => {
                    let p: PathBuf = resolve_relative(self.base, &percent_decode(uri));
                    let mut v = Vec::new();
                    crate::import::open_input(&p)
                        .and_then(|(f, _)| f.take(declared).read_to_end(&mut v))
                        .map_err(|e| ctx.io(&p, e))?;
                    ctx.read_from(&p);
                    v
                }
            };
            if (bytes.len() as u64) < declared {
                return Err(ctx.invalid(format!(
                    "buffer {i} holds {} bytes but its byteLength is {declared}",
                    bytes.len()
                )));
            }
            bytes.truncate(declared as usize);
            self.data[i] = Some(bytes);
        }
        Ok(self.data[i].as_deref().unwrap_or_default())
    }
}

pub(super) struct Accessors<'a> {
    pub root: &'a json::Root,
    pub buffers: Buffers<'a>,
}

fn checked<T: Copy>(
    c: &Checked<T>,
    ctx: &Ctx,
    what: impl FnOnce() -> String,
) -> Result<T, ImportError> {
    match c {
        Checked::Valid(v) => Ok(*v),
        Checked::Invalid => Err(ctx.invalid(what())),
    }
}

/// `offset + stride * (count - 1) + elem <= len`, without overflow.
fn fits(offset: u64, stride: u64, count: u64, elem: u64, len: usize) -> bool {
    if count == 0 {
        return offset <= len as u64;
    }
    stride
        .checked_mul(count - 1)
        .and_then(|x| x.checked_add(offset))
        .and_then(|x| x.checked_add(elem))
        .is_some_and(|end| end <= len as u64)
}

/// An unsigned integer component (u8/u16/u32; other types read as u32).
fn index_value(b: &[u8], ct: ComponentType) -> u32 {
    match ct {
        ComponentType::U8 | ComponentType::I8 => b[0] as u32,
        ComponentType::U16 | ComponentType::I16 => u16::from_le_bytes([b[0], b[1]]) as u32,
        _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
    }
}

fn component(b: &[u8], ct: ComponentType, normalized: bool) -> f32 {
    match ct {
        ComponentType::I8 => {
            let v = b[0] as i8 as f32;
            if normalized {
                (v / 127.0).max(-1.0)
            } else {
                v
            }
        }
        ComponentType::U8 => {
            let v = b[0] as f32;
            if normalized {
                v / 255.0
            } else {
                v
            }
        }
        ComponentType::I16 => {
            let v = i16::from_le_bytes([b[0], b[1]]) as f32;
            if normalized {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
        ComponentType::U16 => {
            let v = u16::from_le_bytes([b[0], b[1]]) as f32;
            if normalized {
                v / 65535.0
            } else {
                v
            }
        }
        ComponentType::U32 => {
            let v = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            if normalized {
                (v as f64 / u32::MAX as f64) as f32
            } else {
                v as f32
            }
        }
        ComponentType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
    }
}

impl Accessors<'_> {
    /// The bytes of bufferView `v` and its byteStride.
    fn view(&mut self, v: usize, ctx: &Ctx) -> Result<(&[u8], Option<usize>), ImportError> {
        let view = self
            .root
            .buffer_views
            .get(v)
            .ok_or_else(|| ctx.invalid(format!("bufferView {v} does not exist")))?;
        let data = self.buffers.get(view.buffer.value(), ctx)?;
        let off = view.byte_offset.map_or(0, |o| o.0);
        let len = view.byte_length.0;
        match off.checked_add(len) {
            Some(end) if end <= data.len() as u64 => Ok((
                &data[off as usize..end as usize],
                view.byte_stride.map(|s| s.0),
            )),
            _ => Err(ctx.invalid(format!(
                "bufferView {v} (offset {off}, length {len}) exceeds buffer {} ({} bytes)",
                view.buffer.value(),
                data.len()
            ))),
        }
    }

    /// The bytes of bufferView `v` (for embedded images).
    pub fn view_bytes(&mut self, v: usize, ctx: &Ctx) -> Result<&[u8], ImportError> {
        Ok(self.view(v, ctx)?.0)
    }

    /// Reads accessor `i` as up to four float components per element (missing ones are
    /// `(0, 0, 0, 1)`), applying `normalized` and sparse substitution. `types` lists the
    /// accepted accessor types.
    pub fn read(
        &mut self,
        i: usize,
        types: &[Type],
        ctx: &Ctx,
        what: &str,
        label: &str,
    ) -> Result<Vec<Vec4>, ImportError> {
        let a =
            self.root.accessors.get(i).ok_or_else(|| {
                ctx.invalid(format!("{what}: {label} accessor {i} does not exist"))
            })?;
        let ty = checked(&a.type_, ctx, || {
            format!("{what}: {label} accessor {i} has an invalid type")
        })?;
        if !types.contains(&ty) {
            return Err(ctx.invalid(format!(
                "{what}: {label} accessor {i} is {ty:?}, expected one of {types:?}"
            )));
        }
        let GenericComponentType(ct) = checked(&a.component_type, ctx, || {
            format!("{what}: {label} accessor {i} has an invalid componentType")
        })?;
        let comps = ty.multiplicity();
        let elem = comps * ct.size();
        let count = a.count.0;
        let decode = |b: &[u8]| {
            let mut v = [0.0, 0.0, 0.0, 1.0];
            for (c, out) in v.iter_mut().enumerate().take(comps) {
                *out = component(&b[c * ct.size()..], ct, a.normalized);
            }
            Vec4::from_array(v)
        };
        let mut out = match a.buffer_view {
            Some(v) => {
                let (bytes, stride) = self.view(v.value(), ctx)?;
                let stride = stride.unwrap_or(elem);
                let off = a.byte_offset.map_or(0, |o| o.0);
                if stride < elem {
                    return Err(ctx.invalid(format!("{what}: {label} accessor {i}: byteStride {stride} is smaller than the element ({elem} bytes)")));
                }
                if !fits(off, stride as u64, count, elem as u64, bytes.len()) {
                    return Err(ctx.invalid(format!(
                        "{what}: {label} accessor {i} ({count} elements, offset {off}, stride {stride}) exceeds bufferView {} ({} bytes)",
                        v.value(),
                        bytes.len()
                    )));
                }
                let off = off as usize;
                (0..count as usize)
                    .map(|k| decode(&bytes[off + k * stride..off + k * stride + elem]))
                    .collect()
            }
            None if count <= MAX_ZERO_FILLED => {
                let zero = vec![0u8; elem];
                vec![decode(&zero); count as usize]
            }
            None => {
                return Err(ctx.invalid(format!(
                    "{what}: {label} accessor {i} has no bufferView and {count} elements"
                )));
            }
        };
        if let Some(sp) = &a.sparse {
            let sc = sp.count.0;
            if sc > count {
                return Err(ctx.invalid(format!(
                    "{what}: {label} accessor {i}: sparse count {sc} exceeds count {count}"
                )));
            }
            let IndexComponentType(ict) = checked(&sp.indices.component_type, ctx, || {
                format!("{what}: {label} accessor {i}: invalid sparse index type")
            })?;
            let (ibytes, _) = self.view(sp.indices.buffer_view.value(), ctx)?;
            let ioff = sp.indices.byte_offset.0;
            let isz = ict.size();
            if !fits(ioff, isz as u64, sc, isz as u64, ibytes.len()) {
                return Err(ctx.invalid(format!(
                    "{what}: {label} accessor {i}: sparse indices exceed their bufferView"
                )));
            }
            let idx: Vec<u64> = (0..sc as usize)
                .map(|k| index_value(&ibytes[ioff as usize + k * isz..], ict) as u64)
                .collect();
            let (vbytes, _) = self.view(sp.values.buffer_view.value(), ctx)?;
            let voff = sp.values.byte_offset.0;
            if !fits(voff, elem as u64, sc, elem as u64, vbytes.len()) {
                return Err(ctx.invalid(format!(
                    "{what}: {label} accessor {i}: sparse values exceed their bufferView"
                )));
            }
            for (k, &j) in idx.iter().enumerate() {
                if j >= count {
                    return Err(ctx.invalid(format!("{what}: {label} accessor {i}: sparse index {j} out of range ({count} elements)")));
                }
                let s = voff as usize + k * elem;
                out[j as usize] = decode(&vbytes[s..s + elem]);
            }
        }
        Ok(out)
    }

    /// Reads an index accessor (SCALAR of u8/u16/u32, not sparse).
    pub fn read_indices(
        &mut self,
        i: usize,
        ctx: &Ctx,
        what: &str,
    ) -> Result<Vec<u32>, ImportError> {
        let a = self
            .root
            .accessors
            .get(i)
            .ok_or_else(|| ctx.invalid(format!("{what}: index accessor {i} does not exist")))?;
        let ty = checked(&a.type_, ctx, || {
            format!("{what}: index accessor {i} has an invalid type")
        })?;
        let GenericComponentType(ct) = checked(&a.component_type, ctx, || {
            format!("{what}: index accessor {i} has an invalid componentType")
        })?;
        if ty != Type::Scalar
            || !matches!(
                ct,
                ComponentType::U8 | ComponentType::U16 | ComponentType::U32
            )
        {
            return Err(ctx.invalid(format!("{what}: index accessor {i} must be SCALAR of unsigned integers, is {ty:?} of {ct:?}")));
        }
        let Some(v) = a.buffer_view.filter(|_| a.sparse.is_none()) else {
            // Zero-filled and/or sparse: the generic path (exact below 2^24).
            let vals = self.read(i, &[Type::Scalar], ctx, what, "indices")?;
            return Ok(vals.iter().map(|v| v.x as u32).collect());
        };
        let (bytes, _) = self.view(v.value(), ctx)?;
        let sz = ct.size();
        let off = a.byte_offset.map_or(0, |o| o.0);
        let count = a.count.0;
        if !fits(off, sz as u64, count, sz as u64, bytes.len()) {
            return Err(ctx.invalid(format!("{what}: index accessor {i} ({count} indices, offset {off}) exceeds bufferView {} ({} bytes)", v.value(), bytes.len())));
        }
        let off = off as usize;
        Ok((0..count as usize)
            .map(|k| index_value(&bytes[off + k * sz..], ct))
            .collect())
    }
}
