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
import sys
import tempfile
import time

from cortex_m4.cases import HYBRID_VARIANTS, TERMS, draw_case, named_case
from cortex_m4.timing import disassemble, spread, step_cycles
from cortex_m4.trace import CALLERS, ROOT, STEP, inline_chains, run_traced, short, steps, symbol_of, symbols, tool

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
    # Most steps retrace an earlier step's path exactly: each distinct path costed once.
    paths = {tuple(e) for e in eps}
    by_path = {p: (step_cycles(p, disasm, "max"), step_cycles(p, disasm, "min")) for p in paths}
    cmax = spread([by_path[tuple(e)][0] for e in eps])
    cmin = spread([by_path[tuple(e)][1] for e in eps])
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
        choices=["hybrid", *HYBRID_VARIANTS, "pid", "both", "all", "law"],
        help="the controllers and friction terms to measure (with --random: the terms the cases take in turn); "
        "`law`: the --scenario's own `[law]`, on a law's PIL image (--image; docs/board.md \"Your own law\")",
    )
    ap.add_argument(
        "--scenario",
        default=None,
        metavar="FILE.toml",
        help="the scenario every run starts from (default: sil-host's embedded default); a law of one's own's "
        "`[law]` table goes here",
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
    if args.controller == "law" and not args.scenario:
        ap.error("--controller law measures the --scenario's own [law]: give --scenario FILE.toml")
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
