//! A counting global allocator, for the tests that prove a real-time path allocates
//! nothing: register it in the test binary
//!
//! ```text
//! #[global_allocator]
//! static GLOBAL: rigtwin_device::testing::alloc::Counting = rigtwin_device::testing::alloc::Counting;
//! ```
//!
//! and compare [`allocations`] before and after the loop. The count is per thread (a
//! `const` thread-local, which itself never allocates), so the test harness's other
//! threads, which may allocate at any moment, cannot be mistaken for the loop. Every
//! call forwards unchanged to the system allocator.
// A global allocator is an `unsafe impl`; this one only forwards to `System`.
#![allow(unsafe_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

/// The system allocator, counting this thread's allocations and reallocations.
#[derive(Debug, Clone, Copy, Default)]
pub struct Counting;

thread_local! {
    /// Allocations (and reallocations) made by this thread.
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

fn note_allocation() {
    // `try_with`: a thread being torn down has no counter left; nothing to note then.
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

/// Allocations and reallocations made by the calling thread so far (zero unless
/// [`Counting`] is the binary's global allocator).
#[must_use]
pub fn allocations() -> u64 {
    ALLOCATIONS.with(Cell::get)
}

// SAFETY: every method forwards its arguments unchanged to the system allocator, which
// upholds `GlobalAlloc`'s contract; counting touches only a thread-local `Cell`.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note_allocation();
        // SAFETY: the caller's contract for `alloc` is passed on unchanged.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the caller's contract for `dealloc` is passed on unchanged.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note_allocation();
        // SAFETY: the caller's contract for `realloc` is passed on unchanged.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}
