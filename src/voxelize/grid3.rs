//! The voxel storage every stage shares: [`Texel`] (f32 or f16 RGBA), the dense
//! [`Grid3`], and `Disjoint`, a slice that parallel tasks write at indices no two
//! share. A leaf: it imports no other voxelize module.

use std::marker::PhantomData;

use half::f16;

/// Storage of one RGBA (or normal) voxel; the arithmetic is always f32/f64.
pub trait Texel: Copy + Send + Sync + Default + 'static {
    fn load(self) -> [f32; 4];
    fn store(v: [f32; 4]) -> Self;
}

impl Texel for [f32; 4] {
    #[inline]
    fn load(self) -> [f32; 4] {
        self
    }
    #[inline]
    fn store(v: [f32; 4]) -> Self {
        v
    }
}

impl Texel for [f16; 4] {
    #[inline]
    fn load(self) -> [f32; 4] {
        self.map(f16::to_f32)
    }
    #[inline]
    fn store(v: [f32; 4]) -> Self {
        v.map(f16::from_f32)
    }
}

/// A dense 3D array, x fastest, then y, then z.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid3<T> {
    pub dims: [usize; 3],
    pub data: Vec<T>,
}

impl<T: Texel> Grid3<T> {
    pub fn new(dims: [usize; 3]) -> Self {
        Grid3 {
            dims,
            data: vec![T::default(); dims[0] * dims[1] * dims[2]],
        }
    }
    #[inline]
    pub fn index(&self, p: [usize; 3]) -> usize {
        p[0] + self.dims[0] * (p[1] + self.dims[1] * p[2])
    }
    #[inline]
    pub fn get(&self, p: [usize; 3]) -> [f32; 4] {
        self.data[self.index(p)].load()
    }
}

/// A slice that parallel tasks write at indices no two tasks share.
/// Borrows the slice for `'a`, so no write can outlive it.
pub(crate) struct Disjoint<'a, T> {
    ptr: *mut T,
    len: usize,
    _slice: PhantomData<&'a mut [T]>,
}

// SAFETY: writers promise disjoint indices (see `write`).
unsafe impl<T: Send> Sync for Disjoint<'_, T> {}
unsafe impl<T: Send> Send for Disjoint<'_, T> {}

impl<'a, T> Disjoint<'a, T> {
    pub(crate) fn new(data: &'a mut [T]) -> Self {
        Disjoint {
            ptr: data.as_mut_ptr(),
            len: data.len(),
            _slice: PhantomData,
        }
    }
    /// # Safety
    /// No other task may write or read index `i` at the same time (the borrow keeps the
    /// slice alive).
    #[inline]
    pub(crate) unsafe fn write(&self, i: usize, v: T) {
        assert!(i < self.len);
        unsafe { self.ptr.add(i).write(v) };
    }
    /// # Safety
    /// No other task may write or read `[start, start + len)` at the same time.
    #[inline]
    #[allow(clippy::mut_from_ref)]
    pub(crate) unsafe fn slice_mut(&self, start: usize, len: usize) -> &'a mut [T] {
        assert!(start + len <= self.len);
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(start), len) }
    }
}
