#!/usr/bin/env python3
"""Where the firmware's control step spends its instructions, under QEMU.

Runs `sil-host pil` on the PIL image with QEMU's exec log on
(`-singlestep -d exec,nochain`: one log line per retired instruction, same
`-icount shift=0` virtual time), cuts the log into steps (the instructions
between the first and the last one inlined from `firmware::controller::Firmware::step`,
with every out-of-line function called in between), and attributes each
instruction of the worst step to a function with `llvm-addr2line -f -i` on the
ELF's debug info (the `qemu` profile keeps `debug = 2`).

Two breakdowns of the worst step (instructions):
- `by_function`: the innermost function of each instruction (inlined or not);
- `by_call`: the frame called from `Firmware::step`/`Firmware::control`, which
  lumps everything the law, the observer or the decoder does under one line.

Usage: scripts/step_profile.py [--controller hybrid|pid] [--duration S]
       [--image ELF] [--sil-host EXE] [--json]
Needs qemu-system-arm and llvm-addr2line (or llvm-addr2line-NN). Counts are
exact QEMU instructions (a step's `step_ticks` times 5.95 rounds them to the
SysTick's 168 MHz grain). Writes nothing but a temporary folder.
"""

import argparse
import collections
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
STEP = "firmware::controller::Firmware::step"
CALLERS = ("firmware::controller::Firmware::step", "firmware::controller::Firmware::control")


def tool(*names):
    for n in names:
        p = shutil.which(n)
        if p:
            return p
    sys.exit(f"step_profile: none of {names} found (Debian: apt-get install llvm)")


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


def run_traced(args, log_path):
    """Runs sil-host pil with QEMU logging every instruction's PC to `log_path` (a FIFO); returns the PCs in order."""
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
    cmd = [args.sil_host, "pil", "--image", args.image, "--qemu", wrapper, "--quiet", "--controller", args.controller]
    cmd += ["--duration", str(args.duration), "--answer-timeout", "60", "--out", out]
    done = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    reader.join()
    if done.returncode != 0:
        sys.exit(f"step_profile: {' '.join(cmd)} failed:\n{done.stderr}")
    return pcs


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


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--controller", default="hybrid", choices=["hybrid", "pid"])
    ap.add_argument("--duration", type=float, default=4.0, help="s of the default scenario (the move is 2 s)")
    ap.add_argument("--image", default=os.path.join(ROOT, "target/thumbv7em-none-eabihf/qemu/pil"))
    ap.add_argument("--sil-host", default=os.path.join(ROOT, "target/release/sil-host"))
    ap.add_argument("--top", type=int, default=25)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    addr2line = tool("llvm-addr2line", "llvm-addr2line-14", "llvm-addr2line-15", "llvm-addr2line-16")
    nm = tool("llvm-nm", "llvm-nm-14", "llvm-nm-15", "llvm-nm-16")
    syms = symbols(args.image, nm)
    with tempfile.TemporaryDirectory(prefix="step-profile-") as tmp:
        pcs = run_traced(args, os.path.join(tmp, "exec.fifo"))
    chains = inline_chains(args.image, set(pcs), addr2line)
    marks = {pc for pc, ch in chains.items() if any(f.startswith(STEP) for f in ch) and any(f.endswith("::ticks") for f in ch)}
    eps = steps(pcs, marks.__contains__)
    if not eps:
        sys.exit("step_profile: no step found in the trace")
    lengths = sorted(len(e) for e in eps)
    worst = max(eps, key=len)
    by_function, by_call = collections.Counter(), collections.Counter()
    last_call = "?"
    for pc in worst:
        ch = chains[pc]
        if any(f.startswith(STEP) for f in ch):
            by_function[ch[0]] += 1
            # The frame right below step/control in the inline chain.
            idx = min((i for i, f in enumerate(ch) if f.startswith(CALLERS)), default=0)
            call = ch[idx - 1] if idx > 0 else ch[idx]
            last_call = call
            by_call[call] += 1
        else:
            name = short(symbol_of(syms, pc))
            by_function[name + " (out of line)"] += 1
            by_call[last_call] += 1
    n = len(lengths)
    report = {
        "controller": args.controller,
        "steps": n,
        "worst": lengths[-1],
        "median": lengths[n // 2],
        "p99": lengths[min(n - 1, (99 * n) // 100)],
        "by_function": dict(by_function.most_common(args.top)),
        "by_call": dict(by_call.most_common(args.top)),
    }
    if args.json:
        print(json.dumps(report, indent=1))
        return
    print(f"{args.controller}: {n} steps, instructions worst {report['worst']}, median {report['median']}, p99 {report['p99']}")
    for title, c in (("worst step by function", by_function), ("worst step by call from the step", by_call)):
        print(f"\n{title}:")
        for name, k in c.most_common(args.top):
            print(f"  {k:6d}  {name}")


if __name__ == "__main__":
    main()
