//! The wrapped core's runs ([`super`] documentation): what a sleeping core may
//! skip, the functional run with the host's edges at exact core positions, and
//! the counted run through TIM2's handler.

use std::sync::atomic::Ordering::Relaxed;

use rsemu::{core::sched::TickCursor, cpu::arm::v7m::sys::Exception};

use super::{CONTROL_EXCEPTION, Core, HandlerRun, TIM2_IRQ, lock};
use crate::{accelerator::FLASH, flash_reads};

impl Core {
    /// Ticks of `ticks` that may be charged without a step (0: the core must
    /// step): the core sleeps, owes nothing, nothing is pending or could pend.
    fn sleepable(&self, ticks: u64) -> u64 {
        let c = &*self.cpu;
        if self.reset_seen.swap(false, Relaxed) {
            // The next step takes the reset.
            return 0;
        }
        if !c.is_asleep() || self.owed() != 0 || c.reset_pending() || c.is_locked_up() || c.nmi_asserted() {
            return 0;
        }
        c.with_sys(|s| {
            // As Exec::step's merge_external: an asserted line pends unless
            // active. Only enabled lines can wake the core; a disabled line's
            // pending bit is folded in by the next step, which nothing reads
            // before (the image reads no NVIC pending bits). Only the lines
            // wired to the core can be asserted ([`Core::set_wired_irqs`]).
            for &irq in self.wake_lines() {
                let e = Exception(irq + 16);
                if s.is_enabled(e) && c.irq_asserted(irq) && !s.is_active(e) {
                    s.set_pending(e, true);
                }
            }
            if s.highest_pending().is_some() {
                return 0;
            }
            let mut n = ticks;
            if s.syst_csr & 0b11 == 0b11 && s.syst_rvr & 0xFF_FFFF != 0 {
                let current = u64::from(s.syst_cvr & 0xFF_FFFF);
                if current == 0 {
                    return 0;
                }
                n = n.min(current);
            }
            s.tick_cyccnt(n);
            if s.tick_systick(n) && s.syst_csr & 0b10 != 0 {
                s.set_pending(Exception::SYSTICK, true);
            }
            n
        })
    }

    /// The cycles the core owes from its last instruction: [`Mode::Functional`]'s
    /// own debt, rsemu's for the counted core.
    fn owed(&self) -> u64 {
        match self.mode {
            super::Mode::Functional => self.debt.load(Relaxed),
            super::Mode::Counted => self.cpu.cycle_debt(),
        }
    }

    /// The functional run: the core stepped one instruction (or exception
    /// entry) at a time (`super::itstate`), its position published before each
    /// (the scheduler's cursor at `anchor + used`: a device read inside the
    /// instruction sees the instant it began), a sleeping core's idle ticks
    /// skipped ([`Core::sleepable`]), the host's edges driven at their ticks,
    /// and the last instruction's overshoot carried into the next run as debt.
    pub(super) fn run_functional(&self, ticks: u64) -> u64 {
        let c = &*self.cpu;
        let cursor = lock(&self.cursor).clone();
        let anchor = cursor.as_ref().map_or(0, TickCursor::anchor);
        let mut edges = lock(&self.edges);
        let pins = lock(&self.pins).clone();
        // Once a round, as rsemu's own runs do (its spin detector's arming).
        c.run(0);
        let mut used = 0;
        while used < ticks {
            let mut rest = ticks - used;
            // A debt first: the last instruction's cycles past the last run.
            let owed = self.debt.load(Relaxed);
            if owed > 0 {
                let d = owed.min(rest);
                self.debt.store(owed - d, Relaxed);
                used += d;
                continue;
            }
            // A host edge: the core owes nothing, so its position is exactly
            // anchor + used.
            if let (Some(e), Some(cur), Some(pins)) = (edges.front().copied(), cursor.as_ref(), pins.as_ref()) {
                let pos = anchor + used;
                if e.at <= pos {
                    if e.at < pos {
                        self.late_edges.fetch_add(1, Relaxed);
                    }
                    edges.pop_front();
                    cur.set(pos);
                    pins.drive(e.line, e.high);
                    continue;
                }
                if c.is_asleep() {
                    rest = rest.min(e.at - pos);
                }
            }
            let n = self.sleepable(rest);
            if n > 0 {
                used += n;
                continue;
            }
            // Awake: one instruction (or exception entry) at a time, so that an
            // exception taken inside an `IT` block keeps it (`super::itstate`).
            if let Some(cur) = cursor.as_ref() {
                cur.set(anchor + used);
            }
            let n = self.step_keeping_itstate(|| c.step());
            if n == 0 {
                // No address space: nothing more to run.
                break;
            }
            // The whole instruction is charged to the budget; what runs past its
            // end is owed (an edge's `rest` does not cut an instruction).
            let left = ticks - used;
            if n > left {
                self.debt.store(n - left, Relaxed);
            }
            used += n.min(left);
        }
        self.end_tick.store(anchor + used, Relaxed);
        used
    }

    pub(super) fn run_counted(&self, ticks: u64) -> u64 {
        let c = &*self.cpu;
        let anchor = lock(&self.cursor).as_ref().map_or(0, TickCursor::anchor);
        let mut tr = lock(&self.track);
        let mut used = 0;
        while used < ticks {
            let n = self.sleepable(ticks - used);
            if n > 0 {
                used += n;
                tr.tick += n;
                continue;
            }
            // The latency runs from TIM2's last rising edge (the tick, whose
            // update starts the acquisition) to the control handler's start.
            let level = c.irq_asserted(TIM2_IRQ);
            if level && !tr.tim2_level {
                tr.irq_seen = Some(tr.tick);
            }
            tr.tim2_level = level;
            let debt = c.cycle_debt();
            let before = c.current_exception().0;
            let now = tr.tick;
            let pc = if debt == 0 { c.regs().r[15] } else { tr.last_pc };
            let stall = match (debt, tr.accel.as_mut()) {
                (0, Some(a)) => {
                    let r = c.regs().r;
                    match flash_reads::instruction_at(&a.code, FLASH.start, pc) {
                        Some((width, insn)) => {
                            a.reads.clear();
                            flash_reads::data_reads(&insn, pc, &r, &mut a.reads);
                            a.art.instruction(pc, width, &a.reads, now)
                        }
                        None => 0,
                    }
                }
                _ => 0,
            };
            let n = if debt == 0 { self.step_keeping_itstate(|| c.run_budget(1)) } else { c.run_budget(1) };
            if n == 0 {
                break;
            }
            if before == CONTROL_EXCEPTION
                && let Some(p) = tr.profile.as_mut()
            {
                let e = p.entry(pc & !1).or_default();
                e.cycles += n + stall;
                e.instructions += u64::from(debt == 0);
            }
            if debt == 0 && before == CONTROL_EXCEPTION {
                tr.last_pc = pc;
                tr.instructions += 1;
                tr.wait += stall;
                let tick = tr.tick;
                if tr.first.is_none() {
                    // At the first instruction: the last TIM2 edge before it is
                    // the tick's update (the deadline's edge comes later).
                    tr.latency = tr.irq_seen.map_or(0, |s| tick.saturating_sub(s));
                }
                let start = *tr.first.get_or_insert(tick);
                if !c.with_sys(|s| s.is_active(Exception(CONTROL_EXCEPTION))) {
                    // Returned (a preempting handler leaves the control active).
                    let end = tr.tick + 1 + c.cycle_debt();
                    let latency = std::mem::take(&mut tr.latency);
                    let run = HandlerRun {
                        latency_cycles: latency,
                        instructions: std::mem::take(&mut tr.instructions),
                        cycles: end - start,
                        wait_cycles: std::mem::take(&mut tr.wait),
                        started_at: start,
                    };
                    tr.first = None;
                    lock(&self.handlers).push(run);
                }
            }
            used += n;
            tr.tick += n;
        }
        self.end_tick.store(anchor + used, Relaxed);
        used
    }
}
