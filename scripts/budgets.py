#!/usr/bin/env python3
"""Flash and static-RAM budgets of the MCU image (docs/hardware.md: flash <= 64 KiB,
static RAM <= 16 KiB, no heap). Reads the ELF's section headers and symbol table
with the standard library only. Usage: scripts/budgets.py ELF [--json]
Exit status 1 when a budget is exceeded or an allocator is linked."""
import json
import struct
import sys

FLASH_BUDGET = 64 * 1024
RAM_BUDGET = 16 * 1024
FLASH_SECTIONS = (".vector_table", ".text", ".rodata", ".data", ".defmt")
RAM_SECTIONS = (".data", ".bss", ".uninit")
ALLOC_SYMBOLS = ("__rust_alloc", "__rdl_alloc", "__rg_alloc", "malloc")


def sections(elf):
    if elf[:4] != b"\x7fELF" or elf[4] != 1:
        raise SystemExit("not a 32-bit ELF file")
    e_shoff, = struct.unpack_from("<I", elf, 0x20)
    e_shentsize, e_shnum, e_shstrndx = struct.unpack_from("<HHH", elf, 0x2E)
    hdrs = [struct.unpack_from("<IIIIIIIIII", elf, e_shoff + i * e_shentsize) for i in range(e_shnum)]
    strtab = hdrs[e_shstrndx]
    def name(off):
        start = strtab[4] + off
        return elf[start:elf.index(b"\0", start)].decode()
    return [(name(h[0]), h) for h in hdrs]


def main():
    if len(sys.argv) < 2:
        raise SystemExit(__doc__)
    elf = open(sys.argv[1], "rb").read()
    secs = sections(elf)
    size = {n: h[5] for n, h in secs}
    # SHF_ALLOC sections only count; .defmt is not loaded (info only) so it is excluded.
    flash = sum(size.get(n, 0) for n in FLASH_SECTIONS if n != ".defmt")
    ram = sum(size.get(n, 0) for n in RAM_SECTIONS)
    symbols = set()
    for n, h in secs:
        if h[1] == 2:  # SHT_SYMTAB
            link = secs[h[6]][1]
            for i in range(h[5] // 16):
                st_name, = struct.unpack_from("<I", elf, h[4] + i * 16)
                s = link[4] + st_name
                symbols.add(elf[s:elf.index(b"\0", s)].decode(errors="replace"))
    allocators = sorted(s for s in symbols if s in ALLOC_SYMBOLS)
    report = {
        "flash_bytes": flash, "flash_budget_bytes": FLASH_BUDGET,
        "static_ram_bytes": ram, "static_ram_budget_bytes": RAM_BUDGET,
        "sections": {n: size[n] for n in FLASH_SECTIONS + RAM_SECTIONS if n in size},
        "heap_allocator_symbols": allocators,
        "ok": flash <= FLASH_BUDGET and ram <= RAM_BUDGET and not allocators,
    }
    if "--json" in sys.argv:
        print(json.dumps(report, indent=2))
    else:
        print(f"flash: {flash} bytes ({flash / 1024:.1f} KiB) of {FLASH_BUDGET // 1024} KiB")
        print(f"static RAM: {ram} bytes ({ram / 1024:.1f} KiB) of {RAM_BUDGET // 1024} KiB")
        print("heap: " + ("none linked" if not allocators else "ALLOCATOR LINKED: " + ", ".join(allocators)))
        print("budgets: " + ("ok" if report["ok"] else "EXCEEDED"))
    sys.exit(0 if report["ok"] else 1)


main()
