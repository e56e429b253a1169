//! Stack high-water mark: the free stack is painted with a pattern at start-up
//! and the lowest overwritten word found later (a painted-stack probe). With
//! flip-link the stack sits below the static data, at the bottom of RAM, so an
//! overflow faults instead of corrupting statics; without it, above them.

/// The paint.
const PAINT: u32 = 0xC0FF_EE11;
/// Words left unpainted below the stack pointer while painting.
const MARGIN: usize = 64;
/// RAM's start (memory.x).
const RAM_START: usize = 0x2000_0000;

unsafe extern "C" {
    static _stack_start: u32;
    static __sdata: u32;
    static __euninit: u32;
}

/// `[low, top)` of the stack region.
fn region() -> (usize, usize) {
    // Linker symbols: only their addresses are taken.
    let (top, sdata, euninit) = (&raw const _stack_start as usize, &raw const __sdata as usize, &raw const __euninit as usize);
    // flip-link puts the statics above the stack: the stack then starts at RAM's start.
    let low = if top <= sdata { RAM_START } else { euninit };
    (low, top)
}

/// Paints the free stack below the current stack pointer (call first thing in `main`).
pub fn paint() {
    let (low, _) = region();
    let sp = cortex_m::register::msp::read() as usize;
    let mut p = low;
    while p + 4 * MARGIN < sp {
        // SAFETY: `[low, sp - margin)` is stack nobody uses yet (below the pointer).
        unsafe { core::ptr::write_volatile(p as *mut u32, PAINT) };
        p += 4;
    }
}

/// The deepest the stack has been, bytes (from its top to the lowest overwritten word).
pub fn high_water_bytes() -> u32 {
    let (low, top) = region();
    let mut p = low;
    // SAFETY: reads of the stack region, word-aligned.
    while p < top && unsafe { core::ptr::read_volatile(p as *const u32) } == PAINT {
        p += 4;
    }
    (top - p) as u32
}

/// The stack region's size, bytes.
pub fn size_bytes() -> u32 {
    let (low, top) = region();
    (top - low) as u32
}
