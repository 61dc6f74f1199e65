#!/usr/bin/env python3
"""Print the cycles of each crate's module graph (issue 13: "a module graph without cycles").

Usage: python3 tools/module_cycles.py [--edges] [--parents] [CRATE_DIR...]   (default: every crates/*)
       --edges also prints every edge with its first witness.
       --parents also prints every call-back: a module naming an item that its parent
       (or an ancestor) defines in its own file, test modules aside.
Exit status: 1 when some crate has a cycle (or, with --parents, a call-back), 0 otherwise.

Why a script: rustc accepts any module graph, so a cycle (module `a` uses an item of `b`
while `b` uses one of `a`) creeps in unnoticed, and then neither module can be read,
tested or moved alone. The data flow of the workspace is one way (description -> model
-> observation -> estimator -> report); this script shows where the code disagrees.

What counts as an edge `a -> b`: a path naming an item of module `b` in the code of
module `a`, written `crate::...`, `super::...`, `self::...` (or `$crate::...` in a
macro, or a bare child-module name in a `use`), in `use` trees (braces and nesting
included) and in code (`crate::inertia::sym3(...)`). Comments, doc comments (intra-doc
links are not dependencies) and string literals are ignored. A path through a
re-export (`crate::Transform` with `pub use model::*` in lib.rs, or
`crate::element::Friction` re-exported from `element/friction.rs`) is followed to the
module that defines the item, using each module's `pub use` lines and its top-level
item definitions. Inline modules (`mod tests { ... }`) count as part of their file's
module. What is not seen: method calls on a type whose `impl` blocks are spread over
several modules (no path is written), and macros' textual scope.

Levels: a module and its own submodules form one unit for cycles (a child naming an
item of its parent is not a cycle here; `--parents` lists those call-backs, which
dvrk-ident has none of: there a parent only declares its children and re-exports
theirs). So the graph is examined level by level: first the crate root's children,
each standing for its whole subtree; then, inside every module that has submodules, its
children, each standing for its subtree (the parent's own file is left out at that
level). A cycle is a strongly connected component of more than one node at some level;
each is printed with one witness reference (file:line and the path) per edge.
"""

import os
import re
import sys
from collections import defaultdict

ITEM_RE = re.compile(
    r"^(?:pub(?:\([^)]*\))?\s+)?(?:unsafe\s+|async\s+|const\s+|extern\s+\"[^\"]*\"\s+)*"
    r"(fn|struct|enum|trait|type|const|static|union|mod|macro_rules!)\s+([A-Za-z_][A-Za-z0-9_]*)",
    re.M,
)
MOD_DECL_RE = re.compile(r"^\s*(?:#\[[^\]]*\]\s*)*(?:pub(?:\([^)]*\))?\s+)?mod\s+([A-Za-z_][A-Za-z0-9_]*)\s*;", re.M)
USE_RE = re.compile(r"\b(pub(?:\([^)]*\))?\s+)?use\s+([^;]*);")
PATH_RE = re.compile(r"(?<![A-Za-z0-9_:])(\$?crate|super|self)((?:\s*::\s*[A-Za-z_][A-Za-z0-9_]*)+)")


def strip(text):
    """The source with comments, strings and char literals blanked (newlines kept, so
    line numbers still hold)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "r" and re.match(r'r#*"', text[i:i + 10]) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'r(#*)"', text[i:])
            end = '"' + m.group(1)
            j = text.find(end, i + len(m.group(0)))
            j = n if j < 0 else j + len(end)
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            j = min(n, j + 1)
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "'":
            m = re.match(r"'(\\(?:x[0-9a-fA-F]{2}|u\{[0-9a-fA-F]+\}|.)|[^\\'\n])'", text[i:])
            if m:
                out.append(" " * len(m.group(0)))
                i += len(m.group(0))
            else:
                out.append(c)
                i += 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def use_paths(tree):
    """Flatten a `use` tree without spaces (`crate::{a::{b,c},e::*}`) into segment lists."""
    tree = re.sub(r"\s+", "", tree)
    results = []

    def walk(prefix, s):
        # split s at top-level commas
        parts, depth, cur = [], 0, ""
        for ch in s:
            if ch == "{":
                depth += 1
            elif ch == "}":
                depth -= 1
            if ch == "," and depth == 0:
                parts.append(cur)
                cur = ""
            else:
                cur += ch
        if cur:
            parts.append(cur)
        for p in parts:
            if "{" in p:
                head, rest = p.split("{", 1)
                rest = rest[: rest.rfind("}")]
                head = [x for x in head.split("::") if x]
                walk(prefix + head, rest)
            else:
                segs = [x for x in p.split("::") if x]
                results.append(prefix + segs)

    walk([], tree)
    return results


def parse_use(tree):
    """(segments, alias) pairs of a `use` tree, aliases (`as x`) kept apart."""
    # mark aliases before removing spaces
    marked = re.sub(r"\s+as\s+([A-Za-z_][A-Za-z0-9_]*)", r"@\1", tree)
    out = []
    for segs in use_paths(marked):
        alias = None
        if segs and "@" in segs[-1]:
            segs[-1], alias = segs[-1].split("@", 1)
        out.append((segs, alias))
    return out


def inline_modules(text):
    """`(start, end, name)` of every `mod name { ... }` in stripped source text."""
    out = []
    for m in re.finditer(r"\bmod\s+([A-Za-z_][A-Za-z0-9_]*)\s*\{", text):
        depth, j = 1, m.end()
        while j < len(text) and depth:
            depth += {"{": 1, "}": -1}.get(text[j], 0)
            j += 1
        out.append((m.start(), j, m.group(1)))
    return out


class Crate:
    def __init__(self, root):
        self.root = root
        self.src = os.path.join(root, "src")
        self.files = {}  # module tuple -> path
        self.texts = {}  # module tuple -> stripped text
        self.children = defaultdict(set)
        self.items = defaultdict(set)  # module -> names defined at its top level
        self.reexports = defaultdict(list)  # module -> [(name|'*', target segments)]
        self.refs = []  # (from module, target segments absolute, file, line, text)
        self.test_modules = set()  # modules that exist for tests only
        for top in ("lib.rs", "main.rs"):
            p = os.path.join(self.src, top)
            if os.path.exists(p):
                self.load((), p)
                break

    def load(self, module, path):
        self.files[module] = path
        with open(path, encoding="utf-8") as f:
            text = strip(f.read())
        self.texts[module] = text
        base = os.path.dirname(path)
        name = os.path.basename(path)
        if module and name not in ("mod.rs",):
            base = os.path.join(base, name[:-3])
        for m in MOD_DECL_RE.finditer(text):
            child = m.group(1)
            # MOD_DECL_RE's match includes the declaration's attributes.
            if child == "tests" or "cfg(test)" in m.group(0):
                self.test_modules.add(module + (child,))
            for cand in (os.path.join(base, child + ".rs"), os.path.join(base, child, "mod.rs")):
                if os.path.exists(cand):
                    self.children[module].add(child)
                    self.load(module + (child,), cand)
                    break
        for m in ITEM_RE.finditer(text):
            self.items[module].add(m.group(2))

    def absolute(self, module, segs):
        """Absolute segments (from the crate root) of a path written in `module`, or None
        when it does not start inside this crate."""
        if not segs:
            return None
        head, rest = segs[0], segs[1:]
        if head in ("crate", "$crate"):
            return list(rest)
        if head == "self":
            return list(module) + list(rest)
        if head == "super":
            cur = list(module)
            while True:
                if not cur:
                    return None
                cur.pop()
                if rest and rest[0] == "super":
                    rest = rest[1:]
                    continue
                return cur + list(rest)
        if head in self.children[module]:
            return list(module) + list(segs)
        return None

    def collect(self):
        for module, text in self.texts.items():
            path = self.files[module]
            inline = inline_modules(text)

            def scope(pos):
                # `super::` in `mod tests { ... }` is the file's module, not its parent.
                return module + tuple(n for a, b, n in inline if a <= pos < b)

            for m in USE_RE.finditer(text):
                public = m.group(1) is not None and not scope(m.start())[len(module):]
                line = text.count("\n", 0, m.start()) + 1
                for segs, alias in parse_use(m.group(2)):
                    absolute = self.absolute(scope(m.start()), segs)
                    if absolute is None:
                        continue
                    if public:
                        name = alias or (segs[-1] if segs[-1] != "*" else "*")
                        self.reexports[module].append((name, absolute))
                    target = [s for s in absolute if s not in ("*", "self")]
                    self.refs.append((module, target, path, line, "::".join(segs)))
            code = USE_RE.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), text)
            for m in PATH_RE.finditer(code):
                segs = [m.group(1)] + [s for s in re.split(r"\s*::\s*", m.group(2)) if s]
                absolute = self.absolute(scope(m.start()), segs)
                if absolute is None:
                    continue
                line = code.count("\n", 0, m.start()) + 1
                self.refs.append((module, absolute, path, line, "::".join(segs)))

    def resolve(self, segs, depth=0):
        """The module defining the item named by absolute `segs` (following re-exports)."""
        module = ()
        i = 0
        while i < len(segs) and segs[i] in self.children[module]:
            module = module + (segs[i],)
            i += 1
        if i == len(segs) or depth > 20:
            return module
        name = segs[i]
        if name in self.items[module] and name not in self.children[module]:
            return module
        for alias, target in self.reexports[module]:
            if alias == name and target != list(module) + [name]:
                return self.resolve(target[:-1] + [target[-1]], depth + 1) if target[-1] == name else self.resolve(target, depth + 1)
        for alias, target in self.reexports[module]:
            if alias == "*":
                t = [s for s in target if s != "*"]
                found = self.resolve(t + [name], depth + 1)
                if found != tuple(t) or name in self.items[tuple(t)]:
                    return found
        return module

    def graph(self):
        """Edges between modules: {(from, to): first witness}."""
        self.collect()
        edges = {}
        for module, target, path, line, text in self.refs:
            to = self.resolve(target)
            if to == module:
                continue
            edges.setdefault((module, to), (os.path.relpath(path), line, text))
        return edges


def call_backs(crate):
    """[(module, ancestor, item, witness)]: a module naming an item its ancestor defines in
    its own file (issue 26: "no module calls back into its parent"; a parent is the facade
    that declares its children and re-exports theirs). A glob import of an ancestor counts:
    what it brings in cannot be told apart. Test modules (`tests`, or declared under
    `#[cfg(test)]`) are the parent's own and exempt."""
    if not crate.refs:
        crate.collect()
    found, seen = [], set()
    for module, target, path, line, text in crate.refs:
        if any(part in crate.test_modules for part in prefixes(module)):
            continue
        ancestor = crate.resolve([s for s in target if s != "*"])
        if not (len(ancestor) < len(module) and module[: len(ancestor)] == ancestor):
            continue
        rest = target[len(ancestor):]
        item = rest[0] if rest else "*"
        if item != "*" and (item not in crate.items[ancestor] or item in crate.children[ancestor]):
            continue
        if (module, ancestor, item) not in seen:
            seen.add((module, ancestor, item))
            found.append((module, ancestor, item, (os.path.relpath(path), line, text)))
    return found


def prefixes(module):
    return [module[: i + 1] for i in range(len(module))]


def scc(nodes, adjacency):
    """Tarjan's strongly connected components."""
    index, low, on, stack, out = {}, {}, set(), [], []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(adjacency.get(v, ())):
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
            out.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in sorted(nodes):
        if v not in index:
            visit(v)
    return out


def name(module):
    return "::".join(module) if module else "crate"


def cycles(crate):
    """Cycles level by level (see the module docstring): [(parent, [component], witnesses)]."""
    edges = crate.graph()
    found = []
    for parent in sorted(crate.files):
        kids = sorted(crate.children[parent])
        if len(kids) < 2:
            continue
        depth = len(parent)
        adjacency, witness = defaultdict(set), {}
        for (a, b), w in edges.items():
            if len(a) <= depth or len(b) <= depth or a[:depth] != parent or b[:depth] != parent:
                continue
            ca, cb = a[depth], b[depth]
            if ca != cb:
                adjacency[ca].add(cb)
                witness.setdefault((ca, cb), (a, b, w))
        for comp in scc(kids, adjacency):
            if len(comp) > 1:
                ws = [witness[(x, y)] for x in comp for y in comp if (x, y) in witness]
                found.append((parent, comp, ws))
    return found, edges


def main(argv):
    show_edges = "--edges" in argv
    parents = "--parents" in argv
    argv = [a for a in argv if a not in ("--edges", "--parents")]
    here = os.path.dirname(os.path.abspath(__file__))
    crates = argv or sorted(
        os.path.join(here, "..", "crates", d) for d in os.listdir(os.path.join(here, "..", "crates"))
    )
    failed = False
    for root in crates:
        crate = Crate(root)
        if not crate.files:
            continue
        found, edges = cycles(crate)
        label = os.path.basename(os.path.normpath(root))
        print(f"{label}: {len(crate.files)} modules, {len(edges)} edges, "
              f"{len(found)} cycle{'s' if len(found) != 1 else ''}")
        if show_edges:
            for (a, b), (path, line, text) in sorted(edges.items()):
                print(f"  edge {name(a)} -> {name(b)}: {path}:{line} {text}")
        for parent, comp, ws in found:
            failed = True
            inside = "" if not parent else f" (inside {name(parent)})"
            print(f"  cycle{inside}: {' <-> '.join(comp)}")
            for a, b, (path, line, text) in ws:
                print(f"    {name(a)} -> {name(b)}: {path}:{line} {text}")
        if parents:
            backs = call_backs(crate)
            print(f"{label}: {len(backs)} call-back{'s' if len(backs) != 1 else ''} into a parent")
            for module, ancestor, item, (path, line, text) in backs:
                failed = True
                print(f"  {name(module)} -> {name(ancestor)}::{item}: {path}:{line} {text}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
