#!/usr/bin/env python3
"""The import-cycle gate (scripts/import_cycles.py) can fail: planted crates, each with
one defect the gate must name, and one clean crate it must pass.

- a cycle through a crate root's re-export (`crate::Type`, `pub use b::Type` in lib.rs),
  the kind the gate's first version dropped;
- a cycle through a `mod.rs` facade, a glob re-export and an alias;
- a `super::` path out of an inline module that does resolve (no false alarm), and one
  that names nothing (unresolved);
- an import through the crate root's re-export (`crate::Thing` for `thing::Thing`);
- the same crate as the first, untied (the type in a third file, named there): clean.

Usage: import_cycles_test.py (exit 0 when every case gives the expected verdict).
"""
import os
import subprocess
import sys
import tempfile

GATE = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'import_cycles.py')

CASES = {
    'root_reexport_cycle': ({
        'lib.rs': 'pub mod a;\npub mod b;\npub use b::Thing;\n',
        'a.rs': 'pub struct A;\npub fn f(_: crate::Thing) {}\n',
        'b.rs': 'use crate::a::A;\npub struct Thing(pub A);\n',
    }, ['CYCLE', 'a.rs', 'b.rs'], 1),
    'facade_glob_alias_cycle': ({
        'lib.rs': 'pub mod m;\npub mod user;\n',
        'm/mod.rs': 'mod inner;\npub use inner::*;\n',
        'm/inner.rs': 'use crate::user::Helper as H;\npub struct Deep(pub H);\n',
        'user.rs': 'pub struct Helper;\npub fn g(_: crate::m::Deep) {}\n',
    }, ['CYCLE', 'm/inner.rs', 'user.rs'], 1),
    'inline_module_paths': ({
        'lib.rs': 'pub mod p;\n',
        'p.rs': 'pub const N: usize = 3;\nmod helper {\n    use super::N;\n    pub fn k() -> usize { N }\n}\n'
                'pub fn bad() { let _ = super::nothing::here(); }\n',
    }, ['UNRESOLVED', 'super::nothing::here'], 1),
    'through_the_root': ({
        'lib.rs': 'pub mod a;\npub mod thing;\npub use thing::Thing;\n',
        'a.rs': 'pub fn f(_: crate::Thing) {}\n',
        'thing.rs': 'pub struct Thing;\n',
    }, ['THROUGH THE ROOT', 'a.rs: crate::Thing', 'imports through a crate root: 1'], 1),
    'untied': ({
        'lib.rs': 'pub mod a;\npub mod b;\npub mod thing;\npub use thing::Thing;\n',
        'a.rs': 'pub struct A;\npub fn f(_: crate::thing::Thing) {}\n',
        'b.rs': 'use crate::a::A;\npub fn h(_: A) {}\n',
        'thing.rs': 'pub struct Thing;\n',
    }, ['import cycles between files: 0; unresolved paths: 0; imports through a crate root: 0'], 0),
}


def main():
    failed = 0
    for name, (files, expected, status) in CASES.items():
        with tempfile.TemporaryDirectory() as d:
            for rel, text in files.items():
                os.makedirs(os.path.dirname(os.path.join(d, rel)), exist_ok=True)
                with open(os.path.join(d, rel), 'w', encoding='utf-8') as fh:
                    fh.write(text)
            run = subprocess.run([sys.executable, GATE, d], capture_output=True, text=True, check=False)
            out = run.stdout + run.stderr
            ok = run.returncode == status and all(e in out for e in expected)
            print(f"{'ok' if ok else 'FAILED'}: {name} (exit {run.returncode})")
            if not ok:
                failed += 1
                print(out)
    print(f'import-cycle gate self-test: {len(CASES) - failed} of {len(CASES)} cases as expected')
    return 1 if failed else 0


if __name__ == '__main__':
    sys.exit(main())
