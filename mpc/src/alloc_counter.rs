//! A global allocator that counts heap allocations, to show that a controller step allocates
//! nothing: install it with `#[global_allocator] static A: mpc::alloc_counter::Counting =
//! mpc::alloc_counter::Counting;` and read [`allocations`] around the code in question.
//!
//! The count is per thread: another thread's allocations (the test harness registering the test
//! it has just spawned, a progress bar's ticker) are not the code's, and on a loaded machine they
//! land in the middle of the measured steps.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

thread_local! {
    // A const-initialised `Cell<u64>` has no destructor: reading it never allocates, so the
    // allocator may use it.
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

fn count() {
    // `try_with`: during a thread's teardown the slot may be gone; such an allocation is nobody's step.
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

/// The system allocator, counting every allocation and reallocation.
pub struct Counting;

// SAFETY: every call is forwarded unchanged to the system allocator.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// Allocations so far on the calling thread (0 unless [`Counting`] is the global allocator).
pub fn allocations() -> u64 {
    ALLOCATIONS.try_with(Cell::get).unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn another_threads_allocations_are_not_counted() {
        // Without `Counting` installed the count stays 0 on every thread: what this checks is that
        // the count is read from the calling thread's own slot.
        let before = allocations();
        std::thread::spawn(count).join().unwrap();
        assert_eq!(allocations(), before);
        count();
        assert_eq!(allocations(), before + 1);
    }
}
