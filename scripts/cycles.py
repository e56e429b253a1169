#!/usr/bin/env python3
"""The firmware's control step under QEMU: instructions and a Cortex-M4 cycle estimate.

Runs `sil-host pil` on the PIL image with QEMU's exec log on
(`-singlestep -d exec,nochain`: one log line per retired instruction, the same
`-icount shift=0` virtual time as `sil-host pil`), cuts the log into steps (from
the first to the second clock read inlined in `firmware::controller::Firmware::step`,
what the image's `step_ticks` measures, with every function called in between)
and gives, per step:
- instructions: exact (the image's own SysTick figure rounds them to 5.95);
- cycles: each retired instruction costed from the Cortex-M4 Technical Reference
  Manual (ARM DDI 0439B, Table 3-1 "Cortex-M4 instruction set summary" and
  Table 7-1 "FPU instruction set"), on the path the step really took (taken
  branches cost the pipeline refill, not-taken ones do not). Two bounds:
  `cycles_max` (P = 3 refill cycles per taken branch, loads and stores never
  pipelined, divides at their worst) and `cycles_min` (P = 1, a load or store
  right after another load or store pipelined to 1 cycle, divides at 2).
  Flash wait states are taken as hidden by the STM32F4's ART accelerator
  (prefetch and instruction cache): a cold cache adds up to 5 cycles per miss.

The path is the one QEMU executed, so the estimate needs no worst-case path
analysis: it is "static" per instruction (TRM tables), dynamic per path.

Also `--profile`: where the worst step's instructions go, from `llvm-addr2line
-f -i` on the ELF's debug info (the `qemu` profile keeps `debug = 2`):
- by function: the innermost function of each instruction (inlined or not);
- by call: the frame called from `Firmware::step`/`Firmware::control`.

Usage:
  scripts/cycles.py [--controller hybrid|hybrid-FRICTION|pid|both|all] [--duration S] [--image ELF]
                    [--sil-host EXE] [--json] [--profile] [--max-cycles N] [--jobs J]
                    [--random N [--seed S] [--case I]...]
  `all` (the default): the hybrid law with every friction term (`hybrid`: the
  default `commanded`; `hybrid-estimated`, issue 41; `hybrid-measured`,
  `hybrid-measured_normal`, `hybrid-none`: `controller.friction`), and the PID.
  --json prints {"hybrid": {...}, "pid": {...}} with worst/median/p99 of
  instructions and cycles, the share of a 1 kHz period and the highest control
  rate at which the worst step fits 5 % of the period at 168 MHz (HARDWARE.md).
  --max-cycles N exits 1 when a worst step's `cycles_max` is above N (CI gate).
  --random N: a bound stated for the default scenario holds for every scenario of
  its kind, so N random admissible scenarios instead (`draw_case`: the ranges of
  board-link's `random_scenarios`, the initial condition, friction, belt, force
  and position references, sensor seed and control rate, 250 Hz to 10 kHz), reproducible from --seed, the terms of --controller in turn, each
  --duration x 1000 periods; it prints every case's worst step with its
  `--set`s, the worst per term and overall (--json: {"seed", "worst_per_term",
  "worst", "cases": [...]}), and --max-cycles applies to every case. A case
  whose firmware enters its safe state is measured up to there (its `outcome`
  says so); a scenario `sil-host pil` refuses is a bug of the draw (exit 2).
Needs qemu-system-arm, llvm-objdump, llvm-nm and llvm-addr2line (Debian: llvm).
Exit status: 0, 1 over the ceiling, 2 bad arguments or a failed run.
"""

import argparse
import collections
import concurrent.futures
import json
import os
import random
import shutil
import subprocess
import sys
import tempfile
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
STEP = "firmware::controller::Firmware::step"
CALLERS = ("firmware::controller::Firmware::step", "firmware::controller::Firmware::control")


def tool(*names):
    for n in names:
        p = shutil.which(n)
        if p:
            return p
    print(f"cycles: none of {names} found (Debian: apt-get install llvm)", file=sys.stderr)
    sys.exit(2)


def symbols(elf, nm):
    """(start, end, name) of the ELF's functions, sorted."""
    out = subprocess.run([nm, "-C", "-S", "--defined-only", elf], capture_output=True, text=True, check=True).stdout
    syms = []
    for line in out.splitlines():
        parts = line.split(maxsplit=3)
        if len(parts) == 4 and parts[2] in "tTwW":
            start, size = int(parts[0], 16), int(parts[1], 16)
            syms.append((start & ~1, (start & ~1) + size, parts[3]))
    syms.sort()
    return syms


def symbol_of(syms, pc):
    lo, hi = 0, len(syms)
    while lo < hi:
        mid = (lo + hi) // 2
        if syms[mid][0] <= pc:
            lo = mid + 1
        else:
            hi = mid
    if lo and syms[lo - 1][0] <= pc < syms[lo - 1][1]:
        return syms[lo - 1][2]
    return "?"


def short(name):
    """A function name without generic arguments and hash (`a::b::<T>::c<U>` -> `a::b::c`)."""
    out, depth = [], 0
    for ch in name:
        if ch == "<":
            depth += 1
        elif ch == ">":
            depth -= 1
        elif depth == 0:
            out.append(ch)
    s = "".join(out).replace("::::", "::")
    if s.startswith("::"):  # `<f32 as core::ops::Mul>::mul`: keep the type
        s = name.split(" as ")[0].lstrip("<") + s
    if "::h" in s and len(s.rsplit("::h", 1)[1]) == 16:
        s = s.rsplit("::h", 1)[0]
    return s


def inline_chains(elf, pcs, addr2line):
    """pc -> list of function names, innermost first (`llvm-addr2line -f -i -C`)."""
    pcs = sorted(pcs)
    text = subprocess.run(
        [addr2line, "-f", "-i", "-C", "-e", elf, "--output-style=LLVM"],
        input="\n".join(hex(p) for p in pcs) + "\n",
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    chains, blocks = {}, text.split("\n\n")
    for pc, block in zip(pcs, blocks):
        lines = [l for l in block.splitlines() if l.strip()]
        chains[pc] = [short(lines[i]) for i in range(0, len(lines), 2)]
    return chains


def run_traced(args, case, log_path):
    """Runs sil-host pil on `case` with QEMU logging every instruction's PC to
    `log_path` (a FIFO); returns the PCs in order and how the run ended (`ok`, or
    the firmware's safe state as `summary.json` words it: a random scenario may
    end there, its steps up to then measured)."""
    wrapper = os.path.join(os.path.dirname(log_path), "qemu-traced")
    with open(wrapper, "w") as f:
        f.write(f'#!/bin/sh\nexec {shutil.which("qemu-system-arm")} "$@" -singlestep -d exec,nochain -D {log_path}\n')
    os.chmod(wrapper, 0o755)
    os.mkfifo(log_path)
    pcs = []

    def read():
        with open(log_path) as f:
            for line in f:
                # "Trace 0: 0x7f.. [00800400/08000e3a/00000010/ff020201] symbol"
                if line.startswith("Trace "):
                    at = line.find("[")
                    fields = line[at + 1 : line.find("]", at)].split("/")
                    pcs.append(int(fields[1], 16))
                elif line.startswith("cpu_io_recompile: rewound") and pcs:
                    # The I/O instruction's first start was undone (icount): it retires once, on the rerun.
                    pcs.pop()

    reader = threading.Thread(target=read)
    reader.start()
    out = os.path.join(os.path.dirname(log_path), "out")
    cmd = [args.sil_host, "pil", "--image", args.image, "--qemu", wrapper, "--quiet", *case["argv"]]
    cmd += ["--answer-timeout", "60", "--out", out]
    done = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    reader.join()
    outcome = "ok"
    if done.returncode == 1 and case.get("random"):
        # Exit 1: the run stopped part way, everything up to then written. The
        # firmware's safe state is an outcome of the scenario, not a failure of the
        # measurement; anything else (QEMU lost, a hung image) is.
        try:
            with open(os.path.join(out, "summary.json")) as f:
                error = json.load(f).get("error") or ""
        except (OSError, ValueError):
            error = ""
        if error.startswith("the firmware entered its safe state"):
            outcome = error
    if done.returncode != 0 and outcome == "ok":
        hint = ""
        if done.returncode == 2 and case.get("random"):
            hint = "\n(a refused random scenario is a bug in scripts/cycles.py's draw: `draw_case` must keep to `Scenario::validate`'s ranges)"
        print(f"cycles: {case['name']}: {' '.join(cmd)} failed (exit {done.returncode}):\n{done.stderr}{hint}", file=sys.stderr)
        sys.exit(2)
    return pcs, outcome


def steps(pcs, is_mark):
    """Cuts the PC stream into steps: from the first of the step's two clock reads
    (`TickClock::ticks` inlined in `Firmware::step`) to the end of the second, what
    the image's `step_ticks` measures."""
    episodes, start, marks, prev = [], None, 0, False
    for i, pc in enumerate(pcs):
        m = is_mark(pc)
        if m and not prev:  # a clock read begins
            if marks == 0:
                start = i
            marks += 1
        elif prev and not m and marks == 2:  # the second read is over
            episodes.append(pcs[start:i])
            marks = 0
        prev = m
    return episodes


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


def base_mnemonic(m):
    """`ldr.w` -> `ldr`, `vmul.f32` -> `vmul`, `movne.w` -> `mov`, `itte` -> `it`, `bne` -> `b`."""
    m = m.split(".")[0]
    if m.startswith("it") and set(m[2:]) <= {"t", "e"}:
        return "it"
    known = ALU1 | ALU2 | LOADS | FP1 | FP3 | FP14 | BRANCHES | {"ldm", "stm", "ldmia", "stmia", "ldmdb", "stmdb", "push", "pop",
             "ldrd", "strd", "vldr", "vstr", "vldm", "vstm", "vldmia", "vstmia", "vpush", "vpop", "udiv", "sdiv", "wfi", "bkpt", "udf"}
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


# The hybrid law's friction terms besides the default (`commanded`): every one is
# gated (issue 56), as `controller.friction` names them (firmware::config::FrictionCompensation).
HYBRID_VARIANTS = ("hybrid-estimated", "hybrid-measured", "hybrid-measured_normal", "hybrid-none")

CORE_HZ = 168e6  # docs/hardware.md: the reference board's core clock
SHARE = 0.05  # HARDWARE.md: the step's budget is 5 % of the control period


def analyse(args, case, tools, syms, disasm):
    with tempfile.TemporaryDirectory(prefix="cycles-") as tmp:
        pcs, outcome = run_traced(args, case, os.path.join(tmp, "exec.fifo"))
    chains = inline_chains(args.image, set(pcs), tools["addr2line"])
    marks = {pc for pc, ch in chains.items() if any(f.startswith(STEP) for f in ch) and any(f.endswith("::ticks") for f in ch)}
    eps = steps(pcs, marks.__contains__)
    if not eps:
        print(f"cycles: no {case['name']} step found in the trace ({outcome})", file=sys.stderr)
        sys.exit(2)
    instr = spread([len(e) for e in eps])
    cmax = spread([step_cycles(e, disasm, "max") for e in eps])
    cmin = spread([step_cycles(e, disasm, "min") for e in eps])
    worst = max(eps, key=len)
    report = {
        "steps": len(eps),
        "instructions": instr,
        "cycles_max": cmax,
        "cycles_min": cmin,
        "worst_step_share_at_1khz": cmax["worst"] / (CORE_HZ / 1000.0),
        "max_rate_hz": CORE_HZ * SHARE / cmax["worst"],
        "max_rate_hz_instructions": CORE_HZ * SHARE / instr["worst"],
    }
    if case.get("random"):
        report.update({"case": case["index"], "term": case["term"], "period_us": case["period_us"], "set": case["sets"], "outcome": outcome})
    if args.profile:
        by_function, by_call = collections.Counter(), collections.Counter()
        last_call = "?"
        for pc in worst:
            ch = chains[pc]
            if any(f.startswith(STEP) for f in ch):
                by_function[ch[0]] += 1
                idx = min((i for i, f in enumerate(ch) if f.startswith(CALLERS)), default=0)
                last_call = ch[idx - 1] if idx > 0 else ch[idx]
                by_call[last_call] += 1
            else:
                by_function[short(symbol_of(syms, pc)) + " (out of line)"] += 1
                by_call[last_call] += 1
        report["by_function"] = dict(by_function.most_common(args.top))
        report["by_call"] = dict(by_call.most_common(args.top))
    return report


# --random: the terms the cases take in turn, and the ranges they are drawn from.
TERMS = ("hybrid", *HYBRID_VARIANTS, "pid")
# The PIL image's rates (firmware::Config::validate: 100 to 4000 us, 250 Hz to 10 kHz),
# drawn log-uniform as board-link's random_scenarios::log_uniform_period_us.
PERIOD_US = (100, 4000)


def draw_case(seed, i, term, periods):
    """Random admissible scenario `i` of `seed` under `term` (`hybrid`, `hybrid-FRICTION`
    or `pid`), `periods` periods long: the `--set KEY=VALUE`s of `sil-host pil`.

    The ranges are board-link's `random_scenarios::random_admissible` and
    `at_period` (the control handler's bound over random scenarios, issue 56): the
    paper's arm and gains, `plant.x0` the paper's d or u (from a, the hybrid law
    lifts off and the firmware enters its safe state by period 10), `plant.mu` 0.3 to 0.8 and `controller.mu_hat` the same, `plant.v_belt` -1 to
    -0.1 m/s, `controller.f_n_ref` 3 to 10 N, `controller.target_z_t` -0.05 to 0.14 m,
    any sensor seed, the period log-uniform over the image's 100 to 4000 us with the
    command's delay 0.2 ms or half the period when that is shorter; the move takes
    the scenario's 2 s (a move drawn short enough to end within a short run, 0.01 to
    0.4 s, trips the firmware's runaway limits within 20 to 100 periods: the run ends
    in the safe state, measuring little). Every case runs the same number of periods
    (the trace's cost), so its duration in seconds follows from its rate: past 2 s
    (a period past 2 ms at --duration 1) it holds too.

    Drawn from a generator seeded by (`seed`, `i`) alone: case `i` is the same
    whatever `--random N` and `--case` select."""
    r = random.Random(f"scripts/cycles.py {seed} {i}")
    kind, _, friction = term.partition("-")
    if kind == "hybrid" and not friction:
        friction = "commanded"
    us = round(PERIOD_US[0] * (PERIOD_US[1] / PERIOD_US[0]) ** r.random())
    duration = periods * us * 1e-6
    mu = round(0.3 + 0.5 * r.random(), 4)
    sets = [
        f"plant.x0={r.choice('du')}",
        f"plant.mu={mu}",
        f"controller.mu_hat={mu}",
        f"plant.v_belt={round(-1.0 + 0.9 * r.random(), 4)}",
        f"controller.f_n_ref={round(3.0 + 7.0 * r.random(), 4)}",
        f"controller.target_z_t={round(-0.05 + 0.19 * r.random(), 4)}",
        f"sensors.seed={r.randrange(1, 1 << 31)}",
        f"timing.rate_hz={1e6 / us!r}",
        f"timing.delta_s={min(0.0002, 0.5 * us * 1e-6):.6f}",
        f"timing.duration_s={duration:.6f}",
    ]
    if friction:
        sets.insert(0, f"controller.friction={friction}")
    argv = ["--controller", kind]
    for kv in sets:
        argv += ["--set", kv]
    return {"name": f"case {i} ({term}, {us} us)", "index": i, "term": term, "period_us": us, "sets": sets, "argv": argv, "random": True}


def named_case(term, duration):
    """The default scenario under `term`, `duration` s."""
    kind, _, friction = term.partition("-")
    argv = ["--controller", kind] + (["--set", f"controller.friction={friction}"] if friction else [])
    return {"name": term, "argv": argv + ["--duration", str(duration)]}


def print_report(name, r):
    i, hi, lo = r["instructions"], r["cycles_max"], r["cycles_min"]
    print(f"{name}: {r['steps']} steps")
    print(f"  instructions  worst {i['worst']:5d}  median {i['median']:5d}  p99 {i['p99']:5d}")
    print(f"  cycles (max)  worst {hi['worst']:5d}  median {hi['median']:5d}  p99 {hi['p99']:5d}")
    print(f"  cycles (min)  worst {lo['worst']:5d}  median {lo['median']:5d}  p99 {lo['p99']:5d}")
    print(f"  highest rate with the worst step in 5 % of the period at 168 MHz: {r['max_rate_hz']:.0f} Hz")
    for title in ("by_function", "by_call"):
        if title in r:
            print(f"  worst step, instructions {title.replace('_', ' ')}:")
            for fn, k in r[title].items():
                print(f"    {k:6d}  {fn}")


def random_summary(reports, args, wall_s):
    """The worst case per term and overall, from the cases' reports."""
    per_term = {}
    for r in reports:
        t = r["term"]
        if t not in per_term or r["cycles_max"]["worst"] > per_term[t]["cycles_max"]:
            per_term[t] = {"cycles_max": r["cycles_max"]["worst"], "instructions": r["instructions"]["worst"], "case": r["case"]}
    worst = max(reports, key=lambda r: r["cycles_max"]["worst"])
    return {
        "seed": args.seed,
        "periods_per_case": args.periods,
        "wall_s": round(wall_s, 1),
        "worst_per_term": per_term,
        "worst": {"cycles_max": worst["cycles_max"]["worst"], "instructions": worst["instructions"]["worst"], "case": worst["case"], "term": worst["term"], "set": worst["set"]},
        "cases": reports,
    }


def main():
    ap = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="Random mode: `--random 24 --seed 1 --duration 1` measures 24 random admissible scenarios "
        "(each of the six terms in turn), 1000 periods each; `--random 24 --seed 1 --case 7 --profile` "
        "runs case 7 of the same draw alone, with the breakdown of its worst step.",
    )
    ap.add_argument(
        "--controller",
        default="all",
        choices=["hybrid", *HYBRID_VARIANTS, "pid", "both", "all"],
        help="the controllers and friction terms to measure (with --random: the terms the cases take in turn)",
    )
    ap.add_argument(
        "--duration",
        type=float,
        default=2.5,
        help="s of the default scenario (its move takes 2 s); with --random, each case runs duration x 1000 periods "
        "(duration s at 1 kHz) at its own rate, so 0.1 s at 10 kHz to 4 s at 250 Hz for --duration 1",
    )
    ap.add_argument(
        "--random",
        type=int,
        metavar="N",
        help="instead of the default scenario, N random admissible scenarios (scripts/cycles.py's draw_case: the ranges "
        "of board-link's random_scenarios, the image's rates 250 Hz to 10 kHz), the terms of --controller in turn; "
        "reports each case's worst step, the worst per term and overall (--max-cycles applies to every case)",
    )
    ap.add_argument("--seed", type=int, default=None, help="with --random: the draw's seed, 1 by default (case i of a seed is the same whatever N)")
    ap.add_argument(
        "--case",
        type=int,
        action="append",
        metavar="I",
        help="with --random: only case I (0 to N-1) of the draw, repeatable (to rerun or --profile a case)",
    )
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="runs at once (default: the cores)")
    ap.add_argument("--image", default=os.path.join(ROOT, "target/thumbv7em-none-eabihf/qemu/pil"))
    ap.add_argument("--sil-host", default=os.path.join(ROOT, "target/release/sil-host"))
    ap.add_argument("--top", type=int, default=25)
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--profile", action="store_true", help="add the worst step's breakdown by function")
    ap.add_argument("--max-cycles", type=float, default=None, help="exit 1 when a worst step's cycles_max exceeds this")
    args = ap.parse_args()
    if args.duration <= 0 or args.duration > 60:
        ap.error("--duration must be in (0, 60] s")
    if args.jobs < 1:
        ap.error("--jobs must be at least 1")
    if args.random is None and (args.case is not None or args.seed is not None):
        ap.error("--seed and --case go with --random N")
    if args.seed is None:
        args.seed = 1
    if args.random is not None:
        if not 1 <= args.random <= 10000:
            ap.error(f"--random {args.random}: the number of cases must be in 1 to 10000")
        bad = [i for i in args.case or [] if not 0 <= i < args.random]
        if bad:
            ap.error(f"--case {bad[0]}: not a case of --random {args.random} (0 to {args.random - 1})")
        args.periods = round(args.duration * 1000)
    for f, what in ((args.image, "the PIL image (cargo build-pil)"), (args.sil_host, "sil-host (cargo build --release -p sil-host)")):
        if not os.path.isfile(f):
            ap.error(f"{f} not found: build {what}")
    tools = {
        "addr2line": tool("llvm-addr2line", "llvm-addr2line-14", "llvm-addr2line-15", "llvm-addr2line-16"),
        "nm": tool("llvm-nm", "llvm-nm-14", "llvm-nm-15", "llvm-nm-16"),
        "objdump": tool("llvm-objdump", "llvm-objdump-14", "llvm-objdump-15", "llvm-objdump-16"),
    }
    syms = symbols(args.image, tools["nm"])
    disasm = disassemble(args.image, tools["objdump"])
    controllers = {"both": ["hybrid", "pid"], "all": list(TERMS)}.get(args.controller, [args.controller])
    if args.random is not None:
        chosen = sorted(set(args.case)) if args.case else range(args.random)
        cases = [draw_case(args.seed, i, controllers[i % len(controllers)], args.periods) for i in chosen]
    else:
        cases = [named_case(c, args.duration) for c in controllers]
    # One process per case, as many at once as there are cores (--jobs): each traced
    # run is one QEMU and one Python parser, both single-threaded (a second of the
    # default scenario takes about 40 s on one core). The runs are independent: each
    # has its own PIL link, QEMU, virtual clock and temporary folder, so running them
    # side by side changes no figure.
    started = time.monotonic()
    with concurrent.futures.ProcessPoolExecutor(max_workers=max(1, min(len(cases), args.jobs))) as pool:
        futures = [pool.submit(analyse, args, c, tools, syms, disasm) for c in cases]
        reports = [f.result() for f in futures]
    wall_s = time.monotonic() - started
    if args.random is None:
        named = {c["name"]: r for c, r in zip(cases, reports)}
        if args.json:
            print(json.dumps(named, indent=1))
        else:
            for c, r in named.items():
                print_report(c, r)
        over = [(c, r) for c, r in named.items() if args.max_cycles is not None and r["cycles_max"]["worst"] > args.max_cycles]
        for c, r in over:
            print(
                f"cycles: the worst {c} step is estimated at {r['cycles_max']['worst']} cycles, over the ceiling of "
                f"{args.max_cycles:.0f} (scripts/cycles.py --profile --controller {c} shows where they go)",
                file=sys.stderr,
            )
    else:
        summary = random_summary(reports, args, wall_s)
        if args.json:
            print(json.dumps(summary, indent=1))
        else:
            print(f"{len(reports)} random scenarios of seed {args.seed}, {args.periods} periods each, {wall_s:.0f} s")
            print(" case  term                    period    steps  instr  cycles(max)  outcome  scenario")
            for r in reports:
                outcome = "ok" if r["outcome"] == "ok" else "safe state"
                sets = " ".join(kv for kv in r["set"] if not kv.startswith("controller.friction="))
                print(
                    f" {r['case']:4d}  {r['term']:23s} {r['period_us']:5d} us"
                    f" {r['steps']:6d} {r['instructions']['worst']:6d} {r['cycles_max']['worst']:12d}  {outcome:8s} {sets}"
                )
            print("worst per term (cycles_max, its instructions, its case):")
            for t, w in summary["worst_per_term"].items():
                print(f"  {t:23s} {w['cycles_max']:5d}  {w['instructions']:5d}  case {w['case']}")
            w = summary["worst"]
            print(f"overall worst: {w['cycles_max']} cycles (max), {w['instructions']} instructions, case {w['case']} ({w['term']}): {' '.join(w['set'])}")
            if args.profile:
                print_report(f"case {w['case']} ({w['term']})", next(r for r in reports if r["case"] == w["case"]))
        over = [(f"case {r['case']} ({r['term']})", r) for r in reports if args.max_cycles is not None and r["cycles_max"]["worst"] > args.max_cycles]
        for c, r in over:
            print(
                f"cycles: the worst step of random {c} is estimated at {r['cycles_max']['worst']} cycles, over the ceiling of "
                f"{args.max_cycles:.0f}: {' '.join(r['set'])} (scripts/cycles.py --random {args.random} --seed {args.seed} "
                f"--duration {args.duration:g} --case {r['case']} --profile shows where they go)",
                file=sys.stderr,
            )
    if over:
        sys.exit(1)


if __name__ == "__main__":
    main()
