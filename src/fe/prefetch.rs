//! Software prefetch for the element loops that stream every element's data
//! through memory once per series order (shell::series): while one element
//! is computed, the next one's data are requested, so that the loop waits
//! less on memory latency. A hint only: it changes no result.

/// Asks the processor to bring `data` into cache (every 64-byte line).
/// No effect off x86_64.
#[inline(always)]
pub fn prefetch<T>(data: &[T]) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let start = data.as_ptr().cast::<i8>();
        for offset in (0..std::mem::size_of_val(data)).step_by(64) {
            // SAFETY: SSE is part of every x86_64 target; a prefetch is a
            // hint that never faults, and the address stays inside `data`.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(start.wrapping_add(offset)) };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = data;
}
