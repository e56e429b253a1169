#!/usr/bin/env python3
"""Import cycles between the files of each crate (docs/architecture.md, "One concept
per module"): a file's `use` paths and its inline `crate::`, `super::` and `self::` paths
(tests and comments left out; a bare path, which names a child module or another crate,
is the module tree's own edge) make a graph per crate; any cycle is an error. Usage:
import_cycles.py SRC_DIR...
"""
import re, os, sys, glob
# module graph per crate: file -> set(files it imports from within the crate)
def modpath(crate_src, f):
    rel=os.path.relpath(f, crate_src)[:-3]
    parts=rel.split('/')
    if parts[-1] in ('lib','main','mod'): parts=parts[:-1]
    return parts
def resolve(crate_src, parts):
    # find file for module path prefix (longest)
    for k in range(len(parts),0,-1):
        p=os.path.join(crate_src,*parts[:k])
        if os.path.isfile(p+'.rs'): return p+'.rs'
        if os.path.isfile(os.path.join(p,'mod.rs')): return os.path.join(p,'mod.rs')
    return None
def uses(text):
    # collect paths from use statements (flatten braces roughly)
    out=[]
    for m in re.finditer(r'(?m)^\s*(?:pub(?:\([a-z]+\))?\s+)?use\s+([^;]+);', text):
        stmt=re.sub(r'\s+','',m.group(1))
        # expand a::{b,c::{d}} roughly: take prefix before { and first segments inside
        def expand(s, prefix=''):
            res=[]
            depth=0; i=0
            if '{' not in s: return [prefix+s]
            j=s.index('{'); pre=s[:j]; inner=s[j+1:s.rindex('}')]
            items=[]; cur=''; d=0
            for ch in inner:
                if ch=='{': d+=1
                if ch=='}': d-=1
                if ch==',' and d==0: items.append(cur); cur=''
                else: cur+=ch
            if cur: items.append(cur)
            for it in items: res+=expand(it, prefix+pre)
            return res
        out+=expand(stmt)
    # also inline paths: crate::a::b, super::a::b (any depth of super), self::a::b
    out+=['crate::'+p for p in re.findall(r'\bcrate::([a-z_0-9:]+)', text)]
    out+=re.findall(r'(?<![A-Za-z_0-9:])((?:super::)+[a-z_0-9:]+)', text)
    out+=re.findall(r'(?<![A-Za-z_0-9:])(self::[a-z_0-9:]+)', text)
    return out
bad=0
for crate_src in sys.argv[1:]:
    files=glob.glob(crate_src+'/**/*.rs', recursive=True)
    graph={}
    for f in files:
        text=open(f).read()
        # strip test modules: a declaration (`#[cfg(...test...)] mod tests;`, its file is
        # itself a test file and imports what it tests) anywhere, and an inline test
        # module (`mod tests {`) to the end of the file, where it conventionally stands
        text=re.sub(r'#\[cfg\([^\]]*\btest\b[^\]]*\)\]\s*(?:#\[[^\]]*\]\s*)*mod\s+\w+\s*;', '', text)
        text=re.split(r'#\[cfg\([^\]]*\btest\b[^\]]*\)\]\s*(?:#\[[^\]]*\]\s*)*mod\s+\w+\s*\{', text)[0]
        text='\n'.join(l for l in text.split('\n') if not l.lstrip().startswith('//'))
        me=modpath(crate_src,f)
        deps=set()
        for u in uses(text):
            was_crate=u.startswith('crate::')
            u=u.replace('crate::','',1) if u.startswith('crate::') else u
            segs=[x for x in u.split('::') if x]
            if not segs: continue
            if segs[0]=='self': segs=me+segs[1:]
            elif segs[0]=='super':
                base=me[:]
                while segs and segs[0]=='super': base=base[:-1]; segs=segs[1:]
                segs=base+segs
            elif not was_crate:
                # A bare path (Rust 2018) names a child module of this one (the module
                # tree's own edge: a parent re-exporting its children is their facade,
                # not an import) or another crate: neither is an import within the crate.
                continue
            t=resolve(crate_src, segs)
            if t and os.path.abspath(t)!=os.path.abspath(f): deps.add(os.path.abspath(t))
        graph[os.path.abspath(f)]=deps
    # find cycles (pairs and longer) via DFS
    import sys as _s
    _s.setrecursionlimit(10000)
    color={}; stack=[]
    cycles=[]
    def dfs(u):
        color[u]=1; stack.append(u)
        for v in graph.get(u,()):
            if color.get(v)==1:
                cyc=stack[stack.index(v):]+[v]; cycles.append(cyc)
            elif color.get(v) is None: dfs(v)
        stack.pop(); color[u]=2
    for u in graph:
        if color.get(u) is None: dfs(u)
    for c in cycles:
        bad+=1
        print('CYCLE in', crate_src, ' -> '.join(os.path.relpath(x, crate_src) for x in c))
print(f'import cycles between files: {bad}')
sys.exit(1 if bad else 0)
