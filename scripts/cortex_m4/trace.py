"""The control step's trace under QEMU, for scripts/cycles.py: `sil-host pil` run with
QEMU's exec log on (one line per retired instruction), the image's symbols and inline
chains (llvm-nm, llvm-addr2line), and the log cut into steps between the two clock reads
of `firmware::controller::Firmware::step`."""

import json
import functools
import os
import shutil
import subprocess
import sys
import threading

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# The step and its body as the debug info names them: `Firmware<L>` is generic over
# its control law since issue 70 (`Firmware<L>::step`; before, `Firmware::step`).
# Since issue 83 the step and the body are methods of an impl in `controller/step.rs`,
# which the names carry (`firmware::controller::step::<impl ...Firmware<L>>::step`, or
# mangled `..._$LT$impl$u20$firmware..controller..Firmware$LT$L$GT$$GT$::step`).
_FIRMWARE = (
    "firmware::controller::Firmware",
    "firmware::controller::Firmware<L>",
    "firmware::controller::Firmware$LT$L$GT$",
    "firmware::controller::step::<impl firmware::controller::Firmware<L>>",
    "firmware::controller::step::_$LT$impl$u20$firmware..controller..Firmware$LT$L$GT$$GT$",
)
STEP = tuple(f + "::step" for f in _FIRMWARE)
CALLERS = STEP + tuple(f + "::control" for f in _FIRMWARE)


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


@functools.lru_cache(maxsize=None)  # the same few hundred names, asked for tens of thousands of times
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
    scenario = ["--scenario", args.scenario] if args.scenario else []
    cmd = [args.sil_host, "pil", "--image", args.image, "--qemu", wrapper, "--quiet", *scenario, *case["argv"]]
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
