//! The process allocator: the system one, with large blocks backed by transparent huge
//! pages where the kernel offers them on request (Linux `madvise` mode).
//!
//! Voxelizing streams through a few hundred MB of freshly allocated buffers (sparse slice
//! stacks, MIP levels, accumulators, the output); with 4 KiB pages every first touch is a
//! page fault (~230 k of them at 256³, a fifth of the CPU time spent in the kernel). Huge
//! pages cut the faults by ~10× and change nothing else: same allocations, same contents.
//! Small blocks are untouched, and where the kernel refuses the advice it is ignored.

use std::alloc::{GlobalAlloc, Layout, System};

/// The allocator of the `billow` binary (see the module docs).
pub struct Allocator;

/// Blocks at least this large are advised; smaller ones gain little.
#[cfg(target_os = "linux")]
const HUGE_MIN: usize = 4 << 20;

#[cfg(target_os = "linux")]
#[inline]
fn advise(ptr: *mut u8, size: usize) {
    if ptr.is_null() || size < HUGE_MIN {
        return;
    }
    // The whole pages inside the block (it may share its first and last page with others).
    const PAGE: usize = 4096;
    let start = (ptr as usize).next_multiple_of(PAGE);
    let end = (ptr as usize + size) & !(PAGE - 1);
    if end > start {
        // SAFETY: the range lies inside a block this process owns; the advice changes how
        // the memory is backed, not its contents or validity (failures are ignored).
        unsafe {
            libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
        }
    }
}

#[cfg(not(target_os = "linux"))]
#[inline]
fn advise(_ptr: *mut u8, _size: usize) {}

// SAFETY: every call is forwarded to `System`; `advise` only adds a hint.
unsafe impl GlobalAlloc for Allocator {
    #[inline]
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        advise(p, layout.size());
        p
    }
    #[inline]
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc_zeroed(layout) };
        advise(p, layout.size());
        p
    }
    #[inline]
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    #[inline]
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        advise(p, new_size);
        p
    }
}

/// Hands the memory the allocator holds free back to the system. glibc keeps the freed
/// blocks of its heaps for reuse, so after a stage that freed a lot in small blocks (the
/// level-0 accumulator of `voxelize --prune`, a few MB per z plane) the next stage's large
/// allocations would come on top of them.
pub fn release_free_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: `malloc_trim` only returns free pages of the allocator's own heaps.
    unsafe {
        libc::malloc_trim(0);
    }
}
