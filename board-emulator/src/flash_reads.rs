//! The data reads an instruction is about to make, as addresses: what the
//! accelerator model ([`crate::accelerator`]) needs to cost the D-code bus's
//! reads of flash (literal pools, jump tables, `.rodata`).
//!
//! The instruction is decoded by rsemu's own decoder (`rsemu::cpu::arm::v7m::isa`,
//! `fpisa`), so nothing here decodes Thumb; the addresses follow the
//! pseudocode of ARM DDI 0403 (ARMv7-M ARM) A7.7 for each load: `PC` reads as
//! the instruction's address plus four, `Align(PC, 4)` for literals.
//! Stores are not reads; a load's address is computed from the registers as
//! they stand before the instruction executes.

use rsemu::cpu::arm::v7m::{
    fpisa::FpInsn,
    isa::{Insn, MemOffset, decode, is_32bit},
};

/// The instruction at `pc`, read from `code` (the flash image from
/// `code_base`): its width in bytes (2 or 4), and its decoding. `None` when
/// `pc` is outside the image.
pub fn instruction_at(code: &[u8], code_base: u32, pc: u32) -> Option<(u32, Insn)> {
    let at = pc.checked_sub(code_base)? as usize;
    let half = |i: usize| code.get(i..i + 2).map(|b| u16::from_le_bytes([b[0], b[1]]));
    let first = half(at)?;
    let second = half(at + 2).unwrap_or(0);
    Some((if is_32bit(first) { 4 } else { 2 }, decode(first, second)))
}

/// The addresses `insn`, at `pc`, reads (one per word or narrower access; a
/// multiple load gives each word), pushed onto `out`. `r` holds R0 to R15
/// before the instruction.
pub fn data_reads(insn: &Insn, pc: u32, r: &[u32; 16], out: &mut Vec<u32>) {
    let pc_read = pc.wrapping_add(4);
    let base = |rn: u8| if rn == 15 { pc_read & !3 } else { r[usize::from(rn & 15)] };
    let offset_addr = |b: u32, off: u32, add: bool| if add { b.wrapping_add(off) } else { b.wrapping_sub(off) };
    match *insn {
        Insn::LoadStore { load: true, rn, offset, index, add, .. } => {
            let off = match offset {
                MemOffset::Imm(v) => v,
                MemOffset::Reg { rm, lsl } => r[usize::from(rm & 15)] << lsl,
            };
            let b = base(rn);
            out.push(if index { offset_addr(b, off, add) } else { b });
        }
        Insn::LoadLiteral { imm, add, .. } => out.push(offset_addr(pc_read & !3, imm, add)),
        Insn::LoadStoreDual { load: true, rn, imm, index, add, .. } => {
            let b = base(rn);
            let a = if index { offset_addr(b, imm, add) } else { b };
            out.extend([a, a.wrapping_add(4)]);
        }
        Insn::LoadStoreExclusive { load: true, rn, imm, .. } => out.push(base(rn).wrapping_add(imm)),
        Insn::LoadStoreMultiple { load: true, rn, list, before, .. } => {
            let n = list.count_ones();
            let start = if before { base(rn).wrapping_sub(4 * n) } else { base(rn) };
            out.extend((0..n).map(|i| start.wrapping_add(4 * i)));
        }
        Insn::TableBranch { rn, rm, half } => {
            let b = if rn == 15 { pc_read } else { r[usize::from(rn & 15)] };
            let i = r[usize::from(rm & 15)];
            out.push(b.wrapping_add(if half { i << 1 } else { i }));
        }
        Insn::Fp(FpInsn::Mem { load: true, rn, imm, add, double, .. }) => {
            let a = offset_addr(base(rn), imm, add);
            out.push(a);
            if double {
                out.push(a.wrapping_add(4));
            }
        }
        Insn::Fp(FpInsn::Multi { load: true, rn, count, add, .. }) => {
            let n = u32::from(count);
            let start = if add { base(rn) } else { base(rn).wrapping_sub(4 * n) };
            out.extend((0..n).map(|i| start.wrapping_add(4 * i)));
        }
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reads(code: &[u16], pc: u32, r: [u32; 16]) -> (u32, Vec<u32>) {
        let bytes: Vec<u8> = code.iter().flat_map(|h| h.to_le_bytes()).collect();
        let (w, insn) = instruction_at(&bytes, pc, pc).expect("in the image");
        let mut out = Vec::new();
        data_reads(&insn, pc, &r, &mut out);
        (w, out)
    }

    #[test]
    fn a_literal_load_reads_from_the_aligned_pc() {
        // LDR r0, [pc, #8] (0x4802) at 0x0800_0102: Align(0x0800_0106, 4) + 8.
        assert_eq!(reads(&[0x4802], 0x0800_0102, [0; 16]), (2, vec![0x0800_010C]));
        // VLDR s0, [pc, #-16] (0xED1F 0x0A04) at 0x0800_0200: 0x0800_0204 - 16.
        assert_eq!(reads(&[0xED1F, 0x0A04], 0x0800_0200, [0; 16]), (4, vec![0x0800_01F4]));
    }

    #[test]
    fn register_loads_and_pops_use_the_registers_before_the_instruction() {
        let mut r = [0u32; 16];
        r[1] = 0x0800_5000;
        r[2] = 3;
        r[13] = 0x2000_0F00;
        // LDR r0, [r1, r2, LSL #2] (0xF851 0x0022).
        assert_eq!(reads(&[0xF851, 0x0022], 0x0800_0000, r).1, vec![0x0800_500C]);
        // LDRB r0, [r1, #5] (0x7948).
        assert_eq!(reads(&[0x7948], 0x0800_0000, r).1, vec![0x0800_5005]);
        // POP {r4, r5, pc} (0xBD30): three words from SP.
        assert_eq!(reads(&[0xBD30], 0x0800_0000, r).1, vec![0x2000_0F00, 0x2000_0F04, 0x2000_0F08]);
        // STR r0, [r1] (0x6008) reads nothing.
        assert_eq!(reads(&[0x6008], 0x0800_0000, r).1, Vec::<u32>::new());
        // TBB [pc, r2] (0xE8DF 0xF002) at 0x0800_0300: the table after the instruction.
        assert_eq!(reads(&[0xE8DF, 0xF002], 0x0800_0300, r).1, vec![0x0800_0307]);
    }
}
