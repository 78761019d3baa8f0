#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Fails when the library's files include each other in a cycle.

A file x.h and its x.cc are one node (what x.cc includes, x.h depends on as far as a
reader of the pair is concerned); an edge runs from a node to every node whose header one of
its files includes with a quoted "folder/name.h". Prints each cycle found and exits 1;
exits 0 when the graph has none.

    scripts/check_include_cycles.py [ROOT] [FOLDER...]
    scripts/check_include_cycles.py --self-test   # the check finds a planted cycle
"""
import pathlib
import re
import sys
import tempfile

FOLDERS = ["io", "autodiff", "fields", "integrators", "solvers"]
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.MULTILINE)


def graph(root, folders):
    edges = {}
    for folder in folders:
        for path in sorted((root / folder).rglob("*")):
            if path.suffix not in (".h", ".cc"):
                continue
            node = str(path.relative_to(root).with_suffix(""))
            targets = edges.setdefault(node, set())
            for included in INCLUDE.findall(path.read_text(encoding="utf-8")):
                target = str(pathlib.PurePosixPath(included).with_suffix(""))
                if target != node and target.split("/")[0] in folders:
                    targets.add(target)
    return edges


def cycles(edges):
    """The strongly connected components of more than one node (Tarjan)."""
    index, low, on_stack, stack, found = {}, {}, set(), [], []

    def visit(node):
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for target in sorted(edges.get(node, ())):
            if target not in index:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in on_stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    sys.setrecursionlimit(10000)
    for node in sorted(edges):
        if node not in index:
            visit(node)
    return found


def self_test():
    """A pair x.h/x.cc is one node: a.cc -> b.h and b.h -> a.h is a cycle; a.cc -> c.h is not."""
    with tempfile.TemporaryDirectory() as folder:
        root = pathlib.Path(folder)
        (root / "solvers").mkdir()
        files = {
            "solvers/a.h": "",
            "solvers/a.cc": '#include "solvers/a.h"\n#include "solvers/b.h"\n#include "solvers/c.h"\n',
            "solvers/b.h": '#include <vector>\n#include "solvers/a.h"\n',
            "solvers/c.h": '#include "io/config.h"\n',
        }
        for name, text in files.items():
            (root / name).write_text(text, encoding="utf-8")
        found = cycles(graph(root, FOLDERS))
        if found != [["solvers/a", "solvers/b"]]:
            print(f"self-test: expected the cycle solvers/a, solvers/b; found {found}")
            return 1
        (root / "solvers/b.h").write_text("", encoding="utf-8")
        found = cycles(graph(root, FOLDERS))
        if found:
            print(f"self-test: expected no cycle; found {found}")
            return 1
    return 0


def main():
    if sys.argv[1:] == ["--self-test"]:
        return self_test()
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    folders = sys.argv[2:] or FOLDERS
    edges = graph(root, folders)
    found = cycles(edges)
    for component in found:
        members = set(component)
        links = [f"{a} -> {b}" for a in component for b in sorted(edges[a]) if b in members]
        print("include cycle among " + ", ".join(component) + ":\n  " + "\n  ".join(links))
    if not edges:
        print(f"no sources under {root} in {', '.join(folders)}")
        return 1
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
