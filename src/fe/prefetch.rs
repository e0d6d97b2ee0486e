//! Software prefetch for the element loops that stream every element's data
//! through memory once per series order (shell::series): while one element
//! is computed, the next one's data are requested, so that the loop waits
//! less on memory latency. A hint only: it changes no result.

/// Asks the processor to bring `data` into cache (every 64-byte line).
/// No effect off x86_64.
#[inline(always)]
pub fn prefetch<T>(data: &[T]) {
    prefetch_bytes(data.as_ptr().cast(), std::mem::size_of_val(data));
}

/// Asks the processor to bring the slots of the next `n` pushes onto `v`
/// (its spare capacity) into cache: a store to a line not in cache waits
/// for that line as a load would (measured on the series' pass of the
/// 140×14 strip: 1.30 → 0.94 ms of element work per order).
#[inline(always)]
pub fn prefetch_spare<T>(v: &Vec<T>, n: usize) {
    let n = n.min(v.capacity() - v.len());
    prefetch_bytes(
        v.as_ptr().wrapping_add(v.len()).cast(),
        n * std::mem::size_of::<T>(),
    );
}

/// A growing list: its values and the slot of its next push.
#[inline(always)]
pub fn prefetch_growing<T>(v: &Vec<T>) {
    prefetch(v);
    prefetch_spare(v, 1);
}

/// Every 64-byte line of `len` bytes from `start`.
#[inline(always)]
fn prefetch_bytes(start: *const i8, len: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        for offset in (0..len).step_by(64) {
            // SAFETY: SSE is part of every x86_64 target; a prefetch is a
            // hint that never faults, whatever the address.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(start.wrapping_add(offset)) };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (start, len);
}
