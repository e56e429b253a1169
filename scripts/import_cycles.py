#!/usr/bin/env python3
"""Import cycles between the files of each crate (docs/architecture.md, "One concept
per module"), every path resolved to the file that defines what it names.

Usage: import_cycles.py [--verbose] SRC_DIR...

Each crate's files make a graph: an arrow from a file to the file that defines each
item it names through a `use` statement or an inline `crate::`, `super::` or `self::`
path (tests, comments and string literals left out). A name re-exported by another
module (`pub use inner::Type` in a crate root or a `mod.rs`, a glob `pub use x::*`, an
alias `use a::B as C`) is followed to the file that defines it, so an import through a
crate root's re-export is an arrow to the defining file, not to the root. A path that
names a type and then one of its variants or associated items (`crate::Mode::Sliding`)
ends at the type's file. A bare path (`use child::Item`, Rust 2018) names a child module
(the module tree's own arrow: a parent re-exporting its children is their facade, not an
import) or another crate: neither is an arrow. Any cycle is an error, and so is any
`crate::`, `super::` or `self::` path that does not resolve to a file of the crate
(`unresolved`): the gate must read every path, not drop what it cannot place.

Exit status: 0 when there are no cycles and no unresolved paths, 1 otherwise.
"""
import glob
import os
import re
import sys

ITEM = re.compile(
    r'(?m)^\s*(?:#\[[^\]]*\]\s*)*(?:pub(?:\s*\([^)]*\))?\s+)?(?:(?:const|async|unsafe|extern\s+"[^"]*"|default)\s+)*'
    r'(fn|struct|enum|trait|type|const|static|union|mod)\s+([A-Za-z_][A-Za-z0-9_]*)'
)
MACRO_RULES = re.compile(r'(?m)^\s*(?:#\[[^\]]*\]\s*)*macro_rules!\s*([A-Za-z_][A-Za-z0-9_]*)')
USE = re.compile(r'(?ms)^\s*(pub(?:\s*\([^)]*\))?\s+)?use\s+([^;]+);')
PATH_ATTR = re.compile(r'#\[path\s*=\s*"([^"]+)"\]\s*(?:#\[[^\]]*\]\s*)*(?:pub(?:\s*\([^)]*\))?\s+)?mod\s+(\w+)\s*;')
INLINE = re.compile(r'(?<![A-Za-z_0-9:$])((?:\$?crate|self|super)(?:::(?:super|[A-Za-z_][A-Za-z0-9_]*))+)')
TEST_DECL = re.compile(r'#\[cfg\([^\]]*\btest\b[^\]]*\)\]\s*(?:#\[[^\]]*\]\s*)*(?:pub(?:\s*\([^)]*\))?\s+)?mod\s+\w+\s*;')
TEST_INLINE = re.compile(r'#\[cfg\([^\]]*\btest\b[^\]]*\)\]\s*(?:#\[[^\]]*\]\s*)*(?:pub(?:\s*\([^)]*\))?\s+)?mod\s+\w+\s*\{')


def strip(text):
    """The code of a file without comments, string and char literals, test modules."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith('//', i):
            j = text.find('\n', i)
            i = n if j < 0 else j
        elif text.startswith('/*', i):
            depth, i = 1, i + 2
            while i < n and depth:
                if text.startswith('/*', i):
                    depth, i = depth + 1, i + 2
                elif text.startswith('*/', i):
                    depth, i = depth - 1, i + 2
                else:
                    i += 1
        elif c == 'r' and re.match(r'r#*"', text[i:i + 8]) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == '_')):
            m = re.match(r'r(#*)"', text[i:])
            end = text.find('"' + m.group(1), i + len(m.group(0)))
            out.append('""')
            i = n if end < 0 else end + 1 + len(m.group(1))
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == '\\' else 1
            out.append('""')
            i = j + 1
        elif c == "'" and re.match(r"'(?:\\.|[^\\'])'|'\\u\{[0-9a-fA-F]+\}'", text[i:i + 12]):
            m = re.match(r"'(?:\\.|[^\\'])'|'\\u\{[0-9a-fA-F]+\}'", text[i:i + 12])
            out.append("' '")
            i += len(m.group(0))
        else:
            out.append(c)
            i += 1
    code = ''.join(out)
    # A test module's declaration (its file is a test file, which imports what it tests),
    # and an inline test module to the end of the file, where it conventionally stands.
    code = TEST_DECL.sub('', code)
    return TEST_INLINE.split(code)[0]


def expand(stmt, prefix=''):
    """`a::{b, c::{d as e}, f::*}` as [(path, alias)]: ('a::b', 'b'), ('a::c::d', 'e'), ('a::f::*', None)."""
    stmt = re.sub(r'\s+', ' ', stmt).strip()
    if '{' not in stmt:
        path = prefix + stmt
        m = re.match(r'(.*?)\s+as\s+(\w+)$', path)
        if m:
            path, alias = m.group(1).strip(), m.group(2)
        else:
            alias = path.split('::')[-1]
        if path.endswith('::self'):
            path = path[:-len('::self')]
            alias = path.split('::')[-1] if not m else alias
        if path.endswith('*'):
            alias = None
        return [(path.replace(' ', ''), alias)]
    j = stmt.index('{')
    pre, inner = stmt[:j].replace(' ', ''), stmt[j + 1:stmt.rindex('}')]
    items, cur, depth = [], '', 0
    for ch in inner:
        if ch == '{':
            depth += 1
        elif ch == '}':
            depth -= 1
        if ch == ',' and depth == 0:
            items.append(cur)
            cur = ''
        else:
            cur += ch
    items.append(cur)
    res = []
    for it in items:
        if it.strip():
            res += expand(it.strip(), prefix + pre)
    return res


class Crate:
    """The files of one crate: their modules, items, imports and paths."""

    def __init__(self, src):
        self.src = os.path.abspath(src)
        self.files = {}  # abs path -> stripped code
        raw = {}
        for f in sorted(glob.glob(os.path.join(self.src, '**', '*.rs'), recursive=True)):
            with open(f, encoding='utf-8') as fh:
                raw[os.path.abspath(f)] = fh.read()
        # Test files (declared `#[cfg(test)] mod name;`, with or without `#[path]`) are
        # left out: a test imports what it tests.
        tests = set()
        for f, text in raw.items():
            for m in TEST_DECL.finditer(text):
                attr = re.search(r'#\[path\s*=\s*"([^"]+)"\]', m.group(0))
                name = re.search(r'mod\s+(\w+)\s*;', m.group(0)).group(1)
                d = os.path.dirname(f)
                if os.path.basename(f) not in ('lib.rs', 'main.rs', 'mod.rs'):
                    d = os.path.join(d, os.path.basename(f)[:-3])
                cands = [os.path.join(os.path.dirname(f), attr.group(1))] if attr else [os.path.join(d, name + '.rs'), os.path.join(d, name, 'mod.rs')]
                tests.update(os.path.abspath(c) for c in cands)
        for f, text in raw.items():
            if f not in tests:
                self.files[f] = strip(text)
        # `#[macro_export]` macros live at the crate root, whichever file defines them.
        self.exported_macros = {}
        for f, text in raw.items():
            if f not in tests:
                for m in re.finditer(r'#\[macro_export\]\s*(?:#\[[^\]]*\]\s*)*macro_rules!\s*(\w+)', text):
                    self.exported_macros[m.group(1)] = f
        roots = [os.path.join(self.src, r) for r in ('lib.rs', 'main.rs')]
        self.root = next((r for r in roots if r in self.files), None)
        self.items = {f: set(m.group(2) for m in ITEM.finditer(c)) | set(MACRO_RULES.findall(c)) for f, c in self.files.items()}
        self.uses = {f: self._uses(c) for f, c in self.files.items()}
        self.spans = {f: self.inline_mods(c) for f, c in self.files.items()}
        self.via_root = []  # (file, path): imports through the crate root's re-exports
        self.path_mods = {f: {name: os.path.abspath(os.path.join(os.path.dirname(f), p)) for p, name in PATH_ATTR.findall(c)}
                          for f, c in self.files.items()}

    @staticmethod
    def _uses(code):
        out = []
        for m in USE.finditer(code):
            for path, alias in expand(m.group(2)):
                out.append((path, alias, m.start()))
        return out

    @staticmethod
    def inline_mods(code):
        """The spans (start, end) of the inline modules (`mod name { ... }`) of a file."""
        spans = []
        for m in re.finditer(r'\bmod\s+\w+\s*\{', code):
            depth, i = 1, m.end()
            while i < len(code) and depth:
                depth += {'{': 1, '}': -1}.get(code[i], 0)
                i += 1
            spans.append((m.start(), i))
        return spans

    def depth(self, f, pos):
        """How many inline modules of file `f` enclose position `pos`."""
        return sum(1 for a, b in self.spans[f] if a < pos < b)

    def unwind(self, f, segs, depth):
        """A path written `depth` inline modules deep in `f`: its leading `super`s that
        stay inside the file dropped (they name the file's own module, approximately:
        the inline modules' items count as the file's), `self` likewise."""
        k = 0
        while k < len(segs) and segs[k] == 'super':
            k += 1
        if depth and k:
            stay = min(k, depth)
            segs = ['self'] + segs[stay:] if stay == k else segs[stay:]
        return segs

    def child(self, f, name):
        """The file of module `name` declared in file `f` (None when there is none)."""
        if name in self.path_mods.get(f, {}):
            p = self.path_mods[f][name]
            return p if p in self.files else None
        d = os.path.dirname(f)
        if os.path.basename(f) not in ('lib.rs', 'main.rs', 'mod.rs'):
            d = os.path.join(d, os.path.basename(f)[:-3])
        for p in (os.path.join(d, name + '.rs'), os.path.join(d, name, 'mod.rs')):
            if p in self.files and re.search(r'\bmod\s+' + name + r'\s*;', self.files[f]):
                return p
        return None

    def parent(self, f):
        """The file of the module that declares `f`'s module."""
        if f == self.root:
            return None
        d = os.path.dirname(f)
        if os.path.basename(f) == 'mod.rs':
            d = os.path.dirname(d)
        for g, mods in self.path_mods.items():
            if f in mods.values():
                return g
        for cand in (os.path.join(d, 'lib.rs'), os.path.join(d, 'main.rs'), os.path.join(d, 'mod.rs'), d + '.rs'):
            if cand in self.files and cand != f:
                return cand
        return None

    def lookup(self, f, name, seen):
        """What `name` is in module file `f`: ('mod', file), ('item', file) or None."""
        key = (f, name)
        if key in seen:
            return None
        seen = seen | {key}
        c = self.child(f, name)
        if c:
            return ('mod', c)
        if name in self.items[f]:
            return ('item', f)
        for path, alias, _ in self.uses[f]:
            if alias == name:
                r = self.resolve(f, path.split('::'), seen, in_use=True)
                if r:
                    return r
        if f == self.root and name in self.exported_macros:
            return ('item', self.exported_macros[name])
        extern_glob = False
        for path, alias, _ in self.uses[f]:
            if alias is None and path.endswith('*'):
                base = self.resolve(f, path.split('::')[:-1], seen, in_use=True)
                if base == 'extern':
                    extern_glob = True
                elif base and base[0] == 'mod':
                    r = self.lookup(base[1], name, seen)
                    if r:
                        return r
        # A name neither defined nor imported here, with a glob import from another
        # crate: that crate's (which this script does not read).
        return 'extern' if extern_glob else None

    def resolve(self, f, segs, seen=frozenset(), in_use=False):
        """The file a path written in `f` names: ('mod' | 'item', file), 'extern' or None."""
        segs = [s for s in segs if s]
        if not segs:
            return ('mod', f)
        head = segs[0]
        if head in ('crate', '$crate'):
            cur, rest = self.root, segs[1:]
        elif head == 'self':
            cur, rest = f, segs[1:]
        elif head == 'super':
            cur, rest = f, segs
            while rest and rest[0] == 'super':
                cur, rest = self.parent(cur), rest[1:]
                if cur is None:
                    return None
        else:
            # A bare path: a name in scope in `f` (a child module, an item, an import),
            # else another crate.
            r = self.lookup(f, head, seen)
            if r is None or r == 'extern':
                return 'extern'
            if r[0] == 'item':
                return r
            cur, rest = r[1], segs[1:]
        if cur is None:
            return None
        kind = 'mod'
        for s in rest:
            r = self.lookup(cur, s, seen)
            if r is None:
                return None
            if r == 'extern':
                return r
            kind, cur = r
            if kind == 'item':
                return r
        return (kind, cur)

    def graph(self):
        """Arrows file -> defining files, and the unresolved paths as (file, path)."""
        edges, unresolved = {}, []
        for f, code in self.files.items():
            deps = set()
            paths = [(p, pos) for p, _, pos in self.uses[f]]
            paths += [(m.group(1), m.start()) for m in INLINE.finditer(USE.sub(lambda u: ' ' * len(u.group(0)), code))]
            for p, pos in paths:
                segs = p.split('::')
                if segs[-1] == '*':
                    segs = segs[:-1]
                if segs[0] not in ('crate', '$crate', 'self', 'super'):
                    continue
                segs = self.unwind(f, segs, self.depth(f, pos))
                if self.through_root(f, segs):
                    self.via_root.append((f, p))
                r = self.resolve(f, segs)
                if r is None:
                    unresolved.append((f, p))
                elif r != 'extern' and r[1] != f:
                    deps.add(r[1])
            edges[f] = deps
        return edges, unresolved

    def through_root(self, f, segs):
        """Whether a path written in `f` reaches its item through a name the crate
        root imports (`crate::Name`, or `super::Name` up to the root, with `pub use
        module::Name` or `pub use other_crate::Name` there) rather than from the module
        that defines it: inside a crate, a file imports from the defining module."""
        # (`$crate::` paths are a macro's, which must name public paths: not counted.)
        head = segs[0] if segs else ''
        if head == 'crate':
            at, rest = self.root, segs[1:]
        elif head == 'super':
            at, rest = f, segs
            while rest and rest[0] == 'super':
                at, rest = self.parent(at), rest[1:]
                if at is None:
                    return False
        else:
            return False
        if at != self.root or not rest or f == self.root:
            return False
        name = rest[0]
        if self.child(self.root, name) or name in self.items[self.root] or name in self.exported_macros:
            return False
        return any(alias == name or (alias is None and path.endswith('*')) for path, alias, _ in self.uses[self.root])


def cycles_of(edges):
    """The strongly connected components of more than one file (Tarjan), each sorted."""
    index, low, on, stack, out, counter = {}, {}, set(), [], [], [0]
    sys.setrecursionlimit(100000)

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return out


def loop_in(comp, edges):
    """One closed walk through the component, from its first file, for the message."""
    comp_set = set(comp)
    start = comp[0]
    # Breadth-first from start back to start inside the component.
    prev, frontier, seen = {}, [start], {start}
    while frontier:
        nxt = []
        for v in frontier:
            for w in sorted(edges[v] & comp_set):
                if w == start:
                    walk = [v]
                    while walk[-1] != start:
                        walk.append(prev[walk[-1]])
                    return [start] + walk[::-1][1:] + [start] if len(walk) > 1 else [start, start]
                if w not in seen:
                    seen.add(w)
                    prev[w] = v
                    nxt.append(w)
        frontier = nxt
    return comp


def main(argv):
    verbose = '--verbose' in argv
    srcs = [a for a in argv if a != '--verbose']
    n_cycles = n_unresolved = n_paths = n_via_root = 0
    for src in srcs:
        crate = Crate(src)
        if crate.root is None:
            print(f'NO ROOT in {src}: neither lib.rs nor main.rs')
            n_unresolved += 1
            continue
        edges, unresolved = crate.graph()
        n_paths += sum(len(v) for v in edges.values())
        rel = lambda p: os.path.relpath(p, crate.src)  # noqa: E731
        for comp in cycles_of(edges):
            n_cycles += 1
            walk = loop_in(comp, edges)
            print(f'CYCLE in {src} ({len(comp)} files: {", ".join(rel(c) for c in comp)}): ' + ' -> '.join(rel(x) for x in walk))
        for f, p in unresolved:
            n_unresolved += 1
            print(f'UNRESOLVED in {src}: {rel(f)}: {p}')
        for f, p in crate.via_root:
            n_via_root += 1
            print(f'THROUGH THE ROOT in {src}: {rel(f)}: {p}')
        if verbose:
            for f in sorted(edges):
                for t in sorted(edges[f]):
                    print(f'  {rel(f)} -> {rel(t)}')
    print(f'import cycles between files: {n_cycles}; unresolved paths: {n_unresolved}; imports through a crate root: {n_via_root} ({n_paths} arrows between files read)')
    return 1 if n_cycles or n_unresolved or n_via_root else 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
