//! The flash's wait states behind the STM32F4's adaptive real-time memory
//! accelerator (ART), costed on the instructions the image really executed:
//! what rsemu's zero-wait cost model leaves out ([`crate::core_clock`]).
//!
//! At 168 MHz the flash answers a 128-bit read in `LATENCY + 1` cycles
//! (`FLASH_ACR.LATENCY` = 5, RM0090 rev 21 §3.5.1 table 10). The ART hides most
//! of it (RM0090 §3.5.2, "Adaptive real-time memory accelerator"):
//! - **I-code:** a read brings a 128-bit line (four to eight Thumb
//!   instructions). With `PRFTEN` the next sequential line is read while the
//!   current one executes; with `ICEN` a 64-line instruction cache keeps the
//!   lines that missed ("each time a miss occurs ... the line read is copied
//!   into the instruction cache memory"), so loops and calls hit.
//! - **D-code:** literal pools, jump tables and `.rodata` are read over the
//!   D-code bus; with `DCEN` an 8-line data cache keeps them.
//!
//! The model, per executed instruction, in the core's cycles plus the stalls
//! so far (its own time line):
//! - a fetch of the line being executed costs nothing;
//! - the next sequential line, prefetched: the stall until its read (started
//!   when the current line arrived, `LATENCY + 1` cycles long) completes;
//! - a line in the instruction cache: nothing;
//! - any other line (a taken branch, a call, an exception's handler, a return
//!   outside the cache): `LATENCY` cycles (a `LATENCY + 1`-cycle read against
//!   the one cycle the zero-wait model charged), the line then cached;
//! - a D-code read of flash ([`crate::flash_reads`]): `LATENCY` cycles unless
//!   the line is in the data cache, the line then cached.
//!
//! Assumptions, stated because RM0090 does not fix them: both caches are fully
//! associative with least-recently-used replacement; a conditional load in an
//! `IT` block whose condition fails is costed as if it read (an over-estimate);
//! the vector fetch of an exception entry is taken as cached (the vector table's
//! line is read at every interrupt). I-code and D-code contention for the flash
//! is not modelled. The result is an estimate, within these rules, of the
//! cycles a real STM32F405 adds to rsemu's zero-wait figures.

use std::collections::VecDeque;

/// The flash's address range (the STM32F405's 1 MiB at `0x0800_0000`, RM0090 §3.3).
pub const FLASH: std::ops::Range<u32> = 0x0800_0000..0x0810_0000;
/// Lines of the instruction cache (RM0090 §3.5.2).
pub const ICACHE_LINES: usize = 64;
/// Lines of the data cache (RM0090 §3.5.2).
pub const DCACHE_LINES: usize = 8;

/// `FLASH_ACR` as the image set it (RM0090 §3.9.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Acr {
    /// Wait states (`LATENCY`, bits 2:0).
    pub latency: u32,
    /// Prefetch enabled (`PRFTEN`, bit 8).
    pub prefetch: bool,
    /// Instruction cache enabled (`ICEN`, bit 9).
    pub icache: bool,
    /// Data cache enabled (`DCEN`, bit 10).
    pub dcache: bool,
}

impl Acr {
    /// Decodes the register's value.
    pub fn from_bits(v: u32) -> Self {
        Acr { latency: v & 0x7, prefetch: v & (1 << 8) != 0, icache: v & (1 << 9) != 0, dcache: v & (1 << 10) != 0 }
    }
}

/// A fully associative cache of 128-bit lines with LRU replacement.
#[derive(Debug, Clone)]
struct Lines {
    lines: VecDeque<u32>,
    capacity: usize,
}

impl Lines {
    fn new(capacity: usize) -> Self {
        Lines { lines: VecDeque::with_capacity(capacity), capacity }
    }
    /// Whether `line` is held; a hit becomes the most recently used.
    fn hit(&mut self, line: u32) -> bool {
        match self.lines.iter().position(|&l| l == line) {
            Some(i) => {
                let l = self.lines.remove(i).unwrap_or(line);
                self.lines.push_back(l);
                true
            }
            None => false,
        }
    }
    fn insert(&mut self, line: u32) {
        if self.lines.len() == self.capacity {
            self.lines.pop_front();
        }
        self.lines.push_back(line);
    }
}

/// The accelerator's state over a run.
#[derive(Debug, Clone)]
pub struct Accelerator {
    acr: Acr,
    icache: Lines,
    dcache: Lines,
    /// The I-code line being executed.
    current: Option<u32>,
    /// When the prefetch of `current + 1` completes (own time line).
    prefetch_ready: u64,
    /// Stall cycles so far (the own time line is core cycles plus these).
    stalls: u64,
}

impl Accelerator {
    /// A cold accelerator configured by `acr`.
    pub fn new(acr: Acr) -> Self {
        Accelerator { acr, icache: Lines::new(ICACHE_LINES), dcache: Lines::new(DCACHE_LINES), current: None, prefetch_ready: 0, stalls: 0 }
    }

    /// The configuration it models.
    pub fn acr(&self) -> Acr {
        self.acr
    }

    fn line(addr: u32) -> u32 {
        addr >> 4
    }

    fn fetch_line(&mut self, line: u32, now: u64) -> u64 {
        if self.current == Some(line) {
            return 0;
        }
        let l = u64::from(self.acr.latency);
        let stall = if self.acr.prefetch && self.current.is_some_and(|c| c.wrapping_add(1) == line) {
            self.prefetch_ready.saturating_sub(now)
        } else if self.acr.icache && self.icache.hit(line) {
            0
        } else {
            if self.acr.icache {
                self.icache.insert(line);
            }
            l
        };
        self.current = Some(line);
        self.prefetch_ready = now + stall + l + 1;
        stall
    }

    /// The stall cycles of one instruction: fetched from `pc` (`width` bytes,
    /// 2 or 4) at core cycle `tick`, reading flash at `data` over the D-code
    /// bus. Addresses outside [`FLASH`] cost nothing (SRAM has no wait states).
    pub fn instruction(&mut self, pc: u32, width: u32, data: &[u32], tick: u64) -> u64 {
        let mut stall = 0;
        if FLASH.contains(&pc) {
            let now = tick + self.stalls;
            stall += self.fetch_line(Self::line(pc), now);
            let last = Self::line(pc + width - 1);
            if last != Self::line(pc) {
                stall += self.fetch_line(last, now + stall);
            }
        }
        let mut last_line = None;
        for &a in data.iter().filter(|a| FLASH.contains(a)) {
            let line = Self::line(a);
            if last_line == Some(line) {
                continue;
            }
            last_line = Some(line);
            if self.acr.dcache && self.dcache.hit(line) {
                continue;
            }
            if self.acr.dcache {
                self.dcache.insert(line);
            }
            stall += u64::from(self.acr.latency);
        }
        self.stalls += stall;
        stall
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ON: Acr = Acr { latency: 5, prefetch: true, icache: true, dcache: true };
    const BASE: u32 = 0x0800_1000;

    #[test]
    fn acr_bits_decode_as_rm0090_3_9_1() {
        // The image's value: LATENCY 5, PRFTEN, ICEN, DCEN.
        assert_eq!(Acr::from_bits(0x705), ON);
        assert_eq!(Acr::from_bits(0), Acr { latency: 0, prefetch: false, icache: false, dcache: false });
    }

    #[test]
    fn zero_wait_states_cost_nothing() {
        let mut a = Accelerator::new(Acr { latency: 0, ..ON });
        for i in 0..1000 {
            assert_eq!(a.instruction(BASE + (i * 36) % 4096, 4, &[0x0800_8000 + i * 64], u64::from(i)), 0);
        }
    }

    #[test]
    fn straight_line_code_pays_the_first_line_and_the_prefetch_shortfall() {
        // Eight 16-bit one-cycle instructions a line: each line takes 8 cycles,
        // longer than the 6-cycle prefetch, so only the first line misses.
        let mut a = Accelerator::new(ON);
        let mut total = 0;
        for i in 0..64u32 {
            total += a.instruction(BASE + 2 * i, 2, &[], u64::from(i));
        }
        assert_eq!(total, 5);
        // Four 32-bit instructions a line: 4 cycles a line against the 6-cycle
        // read: 2 cycles of stall on each sequential line after the first.
        let mut a = Accelerator::new(ON);
        let mut total = 0;
        for i in 0..32u32 {
            total += a.instruction(0x0800_4000 + 4 * i, 4, &[], u64::from(i));
        }
        assert_eq!(total, 5 + 7 * 2);
    }

    #[test]
    fn a_loop_misses_once_then_hits_the_instruction_cache() {
        let mut a = Accelerator::new(ON);
        let body = |a: &mut Accelerator, t: &mut u64| -> u64 {
            // A jump back to the loop's start and a call far away.
            let mut s = 0;
            for pc in [BASE, BASE + 2, 0x0800_9000, 0x0800_9002] {
                s += a.instruction(pc, 2, &[], *t);
                *t += 3;
            }
            s
        };
        let mut t = 0;
        assert_eq!(body(&mut a, &mut t), 10, "two cold lines");
        for _ in 0..10 {
            assert_eq!(body(&mut a, &mut t), 0, "both lines cached");
        }
        // Without the cache every jump pays the full latency.
        let mut a = Accelerator::new(Acr { icache: false, ..ON });
        let mut t = 0;
        body(&mut a, &mut t);
        assert_eq!(body(&mut a, &mut t), 10);
    }

    #[test]
    fn the_instruction_cache_holds_64_lines_lru() {
        let mut a = Accelerator::new(ON);
        let far = |i: u32| 0x0800_0000 + i * 0x100;
        for i in 0..65 {
            assert_eq!(a.instruction(far(i), 2, &[], u64::from(i) * 10), 5);
        }
        // Line 0 was evicted by the 65th; line 1 is still there.
        assert_eq!(a.instruction(far(1), 2, &[], 1000), 0);
        assert_eq!(a.instruction(far(0), 2, &[], 1010), 5);
    }

    #[test]
    fn literal_reads_hit_the_8_line_data_cache_and_sram_is_free() {
        let mut a = Accelerator::new(ON);
        let lit = |i: u32| 0x0800_6000 + i * 16;
        let mut t = 0;
        let mut cost = |a: &mut Accelerator, d: u32| {
            t += 2;
            a.instruction(0x2000_0100, 2, &[d], t)
        };
        for i in 0..8 {
            assert_eq!(cost(&mut a, lit(i)), 5);
        }
        for i in 0..8 {
            assert_eq!(cost(&mut a, lit(i) + 4), 0, "same lines");
        }
        assert_eq!(cost(&mut a, lit(8)), 5);
        assert_eq!(cost(&mut a, lit(0)), 5, "evicted, least recently used");
        assert_eq!(cost(&mut a, 0x2000_0000), 0, "SRAM");
    }

    #[test]
    fn an_instruction_across_two_lines_fetches_both() {
        let mut a = Accelerator::new(Acr { prefetch: false, ..ON });
        assert_eq!(a.instruction(BASE + 14, 4, &[], 0), 10);
    }
}
