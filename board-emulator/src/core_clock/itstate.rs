//! An exception taken inside an `IT` block resumes the block: the stacked
//! `xPSR` keeps `ITSTATE`, which rsemu 0.0.7's exception entry drops.
//!
//! The architecture stacks `xPSR<31:10>` whole, `ITSTATE` (bits 15:10 and
//! 26:25) among them, clears `ITSTATE` for the handler, and restores it from
//! the frame at the exception return (ARM DDI 0403E B1.5.6 `PushStack`,
//! B1.5.8 `PopStack`): the interrupted block goes on with its conditions.
//! rsemu's entry masks those bits out of the frame (its `exception_entry`
//! stacks `xpsr & !(EXCEPTION | 0x0600_fc00)`) while its return restores them,
//! so every instruction of the block left after the interrupt ran
//! unconditionally. Found on the `arm` image (issue 56): TIM2's interrupt
//! between `it eq` and `popeq {r7, pc}` in postcard's `try_take_n_temp` made
//! the pop run, and a valid `Restore` frame was dropped as one that does not
//! decode.
//!
//! The repair, per step: the core steps one instruction or one exception
//! entry at a time ([`Core::step_keeping_itstate`]); when a step that began
//! with `ITSTATE` set entered an exception, the frame it pushed (the return
//! address at offset 24 is the interrupted instruction) gets the bits back at
//! offset 28, before any handler instruction runs. Nothing else of the frame
//! or the core changes: the handler sees what the part's would.

use rsemu::core::{space::MemAttrs, value::Width};

use super::Core;

/// `xPSR`'s `ITSTATE` (`IT[7:2]` at bits 15:10, `IT[1:0]` at bits 26:25; the
/// same bits hold `ICI` outside a block, which rsemu never sets: its multiple
/// loads and stores are not interruptible).
pub const IT_BITS: u32 = 0x0600_fc00;

/// Offsets in an exception frame (basic or extended: the first eight words
/// are the same): the return address and the stacked `xPSR`.
const FRAME_RETURN_ADDRESS: u32 = 24;
const FRAME_XPSR: u32 = 28;
/// `CONTROL.SPSEL`: thread mode runs on the process stack.
const CONTROL_SPSEL: u32 = 1 << 1;

impl Core {
    /// `step`: one instruction or one exception entry of rsemu's core (its
    /// `step`, or a `run_budget(1)` that owes nothing), with the frame of an
    /// exception taken inside an `IT` block repaired (module documentation).
    /// Returns what `step` returns: the cycles or ticks charged, 0 when the
    /// core cannot run.
    pub(super) fn step_keeping_itstate(&self, step: impl FnOnce() -> u64) -> u64 {
        let c = &*self.cpu;
        let it = c.xpsr() & IT_BITS;
        if it == 0 {
            return step();
        }
        let before = c.regs();
        let exception = c.current_exception();
        let n = step();
        if c.current_exception() != exception {
            self.restore_stacked_itstate(&before, it);
        }
        n
    }

    /// The frame the step from `before` pushed, if it pushed one: `ITSTATE`
    /// `it` written back into its stacked `xPSR`.
    fn restore_stacked_itstate(&self, before: &rsemu::cpu::arm::v7m::Regs, it: u32) {
        let c = &*self.cpu;
        let after = c.regs();
        // The frame went on the interrupted context's stack: the process stack
        // for thread code running on it, the main stack otherwise.
        let on_psp = before.xpsr & 0x1ff == 0 && before.control & CONTROL_SPSEL != 0;
        let base = if on_psp { after.psp } else { after.msp };
        let Some(space) = c.space() else { return };
        let read = |a: u32| space.read(u64::from(a), Width::U32, MemAttrs::DEBUG).ok().map(|v| v as u32);
        // An entry stacks the interrupted instruction's address; a return (a
        // `bx lr` inside a block) pushes nothing and is left alone.
        if read(base.wrapping_add(FRAME_RETURN_ADDRESS)) != Some(before.r[15]) {
            return;
        }
        if let Some(xpsr) = read(base.wrapping_add(FRAME_XPSR)) {
            let _ = space.write(u64::from(base.wrapping_add(FRAME_XPSR)), Width::U32, u64::from(xpsr | it), MemAttrs::DEBUG);
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::{
        core_clock::Mode,
        device::{RegisterModel, Result2},
        machine::BoardMachine,
    };

    /// A peripheral the program never touches (the board's models need a bench).
    struct Untouched;

    impl RegisterModel for Untouched {
        fn read(&mut self, _offset: u32) -> Result2<u32> {
            Ok(0)
        }
        fn write(&mut self, _offset: u32, _value: u32) -> Result2<()> {
            Ok(())
        }
        fn reset(&mut self) {}
    }

    /// A program whose thread loops on `cmp r0, #0; itt eq; adds r1, #1;
    /// adds r1, #1` with r0 = 1 (the block's two additions never run), SysTick
    /// interrupting every 41 cycles (an empty handler): over 2 ms the interrupt
    /// lands on every instruction of the loop, inside the block too, thousands
    /// of times.
    fn it_block_under_interrupts() -> Vec<u8> {
        let mut flash = vec![0u8; 0x64];
        let mut word = |at: usize, w: u32| flash[at..at + 4].copy_from_slice(&w.to_le_bytes());
        word(0x00, 0x2000_1000); // initial SP
        word(0x04, 0x0800_0041); // reset
        for v in [0x08, 0x0C, 0x10, 0x14, 0x18] {
            word(v, 0x0800_005F); // NMI, HardFault, MemManage, BusFault, UsageFault: a `b .`
        }
        word(0x3C, 0x0800_005D); // SysTick
        word(0x60, 0xE000_E010); // literal: SYST_CSR
        let code: [u16; 16] = [
            0x4A07, // 0x40 ldr r2, [pc, #28]  (SYST_CSR)
            0x2328, // 0x42 movs r3, #40
            0x6053, // 0x44 str r3, [r2, #4]  (SYST_RVR: every 41 cycles)
            0x2300, // 0x46 movs r3, #0
            0x6093, // 0x48 str r3, [r2, #8]  (SYST_CVR)
            0x2307, // 0x4A movs r3, #7
            0x6013, // 0x4C str r3, [r2, #0]  (SYST_CSR: enable, interrupt, core clock)
            0x2001, // 0x4E movs r0, #1
            0x2100, // 0x50 movs r1, #0
            0x2800, // 0x52 loop: cmp r0, #0
            0xBF04, // 0x54 itt eq
            0x3101, // 0x56 addeq r1, #1
            0x3101, // 0x58 addeq r1, #1
            0xE7FA, // 0x5A b loop
            0x4770, // 0x5C SysTick: bx lr
            0xE7FE, // 0x5E faults: b .
        ];
        for (i, h) in code.iter().enumerate() {
            flash[0x40 + 2 * i..0x42 + 2 * i].copy_from_slice(&h.to_le_bytes());
        }
        flash
    }

    #[test]
    fn an_interrupt_inside_an_it_block_leaves_the_block_conditional_in_both_modes() {
        for mode in [Mode::Functional, Mode::Counted] {
            let mut m = BoardMachine::build(
                it_block_under_interrupts(),
                ["spi1", "adc1", "usart1"].map(|role| (role, Box::new(Untouched) as Box<dyn RegisterModel>)).into(),
                mode,
            )
            .unwrap();
            m.run_until(2_000_000).unwrap();
            let cpu = &m.core.cpu;
            let r = cpu.regs().r;
            // The loop ran (r0 still 1, the core in the loop or the handler),
            // no fault, and the block's additions never ran.
            assert_eq!(r[0], 1, "{mode:?}");
            assert!((0x0800_0052..0x0800_005E).contains(&cpu.pc()), "{mode:?}: pc {:#x}", cpu.pc());
            assert_eq!(r[1], 0, "{mode:?}: the block ran {} additions it was not to", r[1]);
        }
    }
}
