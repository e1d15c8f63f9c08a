"""Cycles between the crate's top-level modules (issue 13).

Reads every `.rs` file under `src/<module>` (or `src/<module>.rs`), drops
each file's `#[cfg(test)] mod tests` block, and takes an edge A -> B for
every `crate::B` path in A (in `use` lines and inline paths, `use crate::{..}`
groups included). Prints the module count, the edge count and the strongly
connected components with more than one module (the cycles); exits 1 when
there is one. The CLI (`src/cli`, `src/main.rs`) sits above the library and
is left out.

    python3 tools/module_cycles.py [src]
"""

import os
import re
import sys


def module_files(src, module):
    path = os.path.join(src, module)
    if os.path.isdir(path):
        for root, _, files in os.walk(path):
            for f in files:
                if f.endswith(".rs"):
                    yield os.path.join(root, f)
    else:
        yield path + ".rs"


def graph(src):
    skip = {"lib.rs", "main.rs", "cli"}
    modules = sorted(
        m[:-3] if m.endswith(".rs") else m for m in os.listdir(src) if m not in skip
    )
    edges = {m: set() for m in modules}
    for m in modules:
        for path in module_files(src, m):
            text = open(path, encoding="utf-8").read()
            cut = text.find("#[cfg(test)]\nmod tests")
            if cut >= 0:
                text = text[:cut]
            names = re.findall(r"crate::(\w+)", text)
            for group in re.findall(r"use crate::\{([^}]*)\}", text):
                names += re.findall(r"\b(\w+)\b", group)
            edges[m] |= {n for n in names if n in edges and n != m}
    return edges


def cycles(edges):
    """Tarjan's strongly connected components of more than one module."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(edges[v]):
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


def main():
    src = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "src")
    edges = graph(src)
    found = cycles(edges)
    print(f"{len(edges)} modules, {sum(len(e) for e in edges.values())} edges, cycles: {found or 'none'}")
    sys.exit(1 if found else 0)


if __name__ == "__main__":
    main()
