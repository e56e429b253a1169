"""A step's cycles on a Cortex-M4, for scripts/cycles.py: each retired instruction
costed from the Cortex-M4 Technical Reference Manual (ARM DDI 0439B, Table 3-1
"Cortex-M4 instruction set summary" and Table 7-1 "FPU instruction set") on the path
the step took, under the two bounds `max` and `min` (scripts/cycles.py's docstring);
the image's disassembly (llvm-objdump); the worst, median and 99th percentile."""

import functools
import subprocess

# Cortex-M4 TRM (DDI 0439B) Table 3-1 and Table 7-1: cycles of one instruction
# beyond the pipeline refill of a taken branch (added separately).
ALU1 = {
    "adc", "add", "addw", "adr", "and", "asr", "bfc", "bfi", "bic", "clz", "cmn", "cmp", "eor", "lsl", "lsr", "mov",
    "movt", "movw", "mvn", "nop", "orn", "orr", "pkhbt", "pkhtb", "rbit", "rev", "rev16", "revsh", "ror", "rrx", "rsb",
    "sbc", "sbfx", "ssat", "sub", "subw", "sxtb", "sxth", "sxtab", "sxtah", "teq", "tst", "ubfx", "usat", "uxtb",
    "uxth", "uxtab", "uxtah", "uxtb16", "mul", "smull", "umull", "smlal", "umlal", "umaal", "smmul", "uqadd8",
    "uqadd16", "uqsub8", "uqsub16", "cpsid", "cpsie", "it", "dmb", "dsb", "isb", "mrs", "msr",
}
ALU2 = {"mla", "mls"}  # multiply-accumulate: 2
LOADS = {"ldr", "ldrb", "ldrh", "ldrsb", "ldrsh", "ldrex", "str", "strb", "strh", "strex"}  # 2 (1 pipelined)
FP1 = {
    "vabs", "vadd", "vsub", "vmul", "vnmul", "vneg", "vcmp", "vcmpe", "vcvt", "vcvtr", "vmrs", "vmsr", "vmov",
    "vmaxnm", "vminnm", "vsel",
}
FP3 = {"vmla", "vmls", "vnmla", "vnmls", "vfma", "vfms", "vfnma", "vfnms"}
FP14 = {"vdiv", "vsqrt"}
BRANCHES = {"b", "bl", "blx", "bx", "cbz", "cbnz", "tbb", "tbh"}
CONDS = ("eq", "ne", "cs", "hs", "cc", "lo", "mi", "pl", "vs", "vc", "hi", "ls", "ge", "lt", "gt", "le", "al")
KNOWN = ALU1 | ALU2 | LOADS | FP1 | FP3 | FP14 | BRANCHES | {"ldm", "stm", "ldmia", "stmia", "ldmdb", "stmdb", "push", "pop",
         "ldrd", "strd", "vldr", "vstr", "vldm", "vstm", "vldmia", "vstmia", "vpush", "vpop", "udiv", "sdiv", "wfi", "bkpt", "udf"}


# Pure functions of an instruction's text, called once per retired instruction of every
# step (millions per run): cached, so each distinct mnemonic and operand is parsed once.
@functools.lru_cache(maxsize=None)
def base_mnemonic(m):
    """`ldr.w` -> `ldr`, `vmul.f32` -> `vmul`, `movne.w` -> `mov`, `itte` -> `it`, `bne` -> `b`."""
    m = m.split(".")[0]
    if m.startswith("it") and set(m[2:]) <= {"t", "e"}:
        return "it"
    known = KNOWN
    for cand in (m, m[:-1] if m.endswith("s") else None):
        if cand in known:
            return cand
    for c in CONDS:
        if m.endswith(c) and len(m) > len(c):
            b = m[: -len(c)]
            for cand in (b, b[:-1] if b.endswith("s") else None):
                if cand in known:
                    return cand
    return m


def register_count(ops):
    """Registers in a `{r4, r5, lr}` or `{d8-d9}` list (a D register is two words)."""
    inner = ops[ops.find("{") + 1 : ops.find("}")]
    n = 0
    for part in inner.split(","):
        part = part.strip()
        if "-" in part:
            a, b = part.split("-")
            k = int(b.strip()[1:]) - int(a.strip()[1:]) + 1
        else:
            k = 1
        n += 2 * k if part.startswith("d") else k
    return n


@functools.lru_cache(maxsize=None)
def cost(mn, ops, taken, after_memory, bound):
    """Cycles of one instruction: TRM figures; `bound` is "max" or "min" (see the module docs)."""
    b = base_mnemonic(mn)
    refill = (3 if bound == "max" else 1) if taken else 0
    pipelined = bound == "min" and after_memory
    if b in BRANCHES:
        return (2 if b in ("tbb", "tbh") else 1) + refill
    if b in ALU1:
        # A write to the PC (mov pc, add pc) is a branch.
        return 1 + (refill if ops.startswith("pc") else 0)
    if b in ALU2:
        return 2
    if b in ("udiv", "sdiv"):
        return 12 if bound == "max" else 2
    if b in LOADS:
        return (1 if pipelined else 2) + (refill if b == "ldr" and ops.startswith("pc") else 0)
    if b in ("ldrd", "strd"):
        return 3
    if b in ("ldm", "ldmia", "ldmdb", "stm", "stmia", "stmdb", "push", "pop", "vldm", "vldmia", "vstm", "vstmia", "vpush", "vpop"):
        loads_pc = "pc" in ops[ops.find("{") :]
        return 1 + register_count(ops) + (refill if loads_pc else 0)
    if b in ("vldr", "vstr"):
        return 1 if pipelined else 2
    if b in FP3:
        return 3
    if b in FP14:
        return 14
    if b == "vmov":
        # Two core registers to or from a double register or two singles: 2.
        return 2 if ops.count(",") >= 2 and not ops.split(",")[-1].strip().startswith("#") else 1
    if b in FP1:
        return 1
    return 1  # anything else (never in the step): one cycle


def disassemble(elf, objdump):
    """pc -> (mnemonic, operands, size in bytes) of every instruction of `.text`."""
    text = subprocess.run([objdump, "-d", "--no-show-raw-insn", "-j", ".text", elf], capture_output=True, text=True, check=True).stdout
    out = {}
    for line in text.splitlines():
        parts = line.strip().split(None, 1)
        if len(parts) < 2 or not parts[0].endswith(":"):
            continue
        try:
            pc = int(parts[0][:-1], 16)
        except ValueError:
            continue
        rest = parts[1].split("@")[0].split("\t") if "\t" in parts[1] else parts[1].split("@")[0].split(None, 1)
        mn = rest[0].strip()
        ops = rest[1].strip() if len(rest) > 1 else ""
        out[pc] = [mn, ops, 0]
    pcs = sorted(out)
    for a, b in zip(pcs, pcs[1:]):
        out[a][2] = b - a
    return {pc: tuple(v) for pc, v in out.items()}


def step_cycles(ep, disasm, bound):
    """Cycles of one step (a list of PCs) under `bound`."""
    total, after_memory = 0, False
    for i, pc in enumerate(ep):
        mn, ops, size = disasm.get(pc, ("?", "", 2))
        nxt = ep[i + 1] if i + 1 < len(ep) else pc + size
        taken = nxt != pc + size
        total += cost(mn, ops, taken, after_memory, bound)
        b = base_mnemonic(mn)
        after_memory = b in LOADS or b in ("vldr", "vstr")
    return total


def spread(values):
    v = sorted(values)
    n = len(v)
    return {"worst": v[-1], "median": v[n // 2], "p99": v[min(n - 1, (99 * n) // 100)]}
