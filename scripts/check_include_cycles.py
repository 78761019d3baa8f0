#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Fails when the library's files include each other in a cycle, or a layer includes from one above it.

Cycles. A file x.h and its x.cc are one node (what x.cc includes, x.h depends on as far as a
reader of the pair is concerned); an edge runs from a node to every node whose header one of
its files includes with a quoted "folder/name.h".

Layers. The top-level folders are layers in the order of FOLDERS, and solvers/ is split into
the layer folders of SOLVER_LAYERS: a file may include only from its own layer or one
before it in the list, and solvers/ holds no source file outside those folders.

Prints each cycle and each upward include found and exits 1; exits 0 when there are none.

    scripts/check_include_cycles.py [ROOT] [FOLDER...]
    scripts/check_include_cycles.py --self-test   # the check finds a planted cycle
"""
import pathlib
import re
import sys
import tempfile

FOLDERS = ["io", "autodiff", "fields", "integrators", "solvers"]
SOLVER_LAYERS = ["sampling", "geometry", "core", "training", "conditions", "problems", "output", "run"]
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


def layer(path):
    """(top-level index, solvers sub-layer index) of a path such as solvers/core/domain.h."""
    parts = pathlib.PurePosixPath(path).parts
    top = FOLDERS.index(parts[0]) if parts[0] in FOLDERS else None
    sub = None
    if parts[0] == "solvers" and len(parts) > 2:
        sub = SOLVER_LAYERS.index(parts[1]) if parts[1] in SOLVER_LAYERS else -1
    return top, sub


def layer_violations(root, folders):
    """Lines 'file: includes "x" from a later layer' for every upward include."""
    found = []
    for folder in folders:
        for path in sorted((root / folder).rglob("*")):
            if path.suffix not in (".h", ".cc"):
                continue
            name = str(path.relative_to(root).as_posix())
            top, sub = layer(name)
            if sub == -1 or (folder == "solvers" and sub is None):
                found.append(f"{name}: not in a layer folder of solvers/ ({', '.join(SOLVER_LAYERS)})")
                continue
            for included in INCLUDE.findall(path.read_text(encoding="utf-8")):
                their_top, their_sub = layer(included)
                if their_top is None:
                    continue
                if their_top > top or (top == their_top and sub is not None and their_sub is not None
                                       and their_sub > sub):
                    found.append(f'{name}: includes "{included}" from a later layer')
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
        found = layer_violations(root, FOLDERS)
        if found != ["solvers/a.cc: not in a layer folder of solvers/ (" + ", ".join(SOLVER_LAYERS) + ")",
                     "solvers/a.h: not in a layer folder of solvers/ (" + ", ".join(SOLVER_LAYERS) + ")",
                     "solvers/b.h: not in a layer folder of solvers/ (" + ", ".join(SOLVER_LAYERS) + ")",
                     "solvers/c.h: not in a layer folder of solvers/ (" + ", ".join(SOLVER_LAYERS) + ")"]:
            print(f"self-test: expected four files outside the layer folders; found {found}")
            return 1
    with tempfile.TemporaryDirectory() as folder:
        root = pathlib.Path(folder)
        for sub in ("solvers/core", "solvers/training", "fields"):
            (root / sub).mkdir(parents=True)
        files = {
            "solvers/core/problem.h": '#include "fields/field.h"\n',
            "solvers/training/trainer.h": '#include "solvers/core/problem.h"\n',
            "fields/field.h": "",
        }
        for name, text in files.items():
            (root / name).write_text(text, encoding="utf-8")
        if layer_violations(root, FOLDERS):
            print(f"self-test: expected no upward include; found {layer_violations(root, FOLDERS)}")
            return 1
        (root / "solvers/core/problem.h").write_text('#include "solvers/training/trainer.h"\n', encoding="utf-8")
        (root / "fields/field.h").write_text('#include "solvers/core/problem.h"\n', encoding="utf-8")
        found = layer_violations(root, FOLDERS)
        expected = ['fields/field.h: includes "solvers/core/problem.h" from a later layer',
                    'solvers/core/problem.h: includes "solvers/training/trainer.h" from a later layer']
        if found != expected:
            print(f"self-test: expected {expected}; found {found}")
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
    violations = layer_violations(root, folders)
    for line in violations:
        print(line)
    if not edges:
        print(f"no sources under {root} in {', '.join(folders)}")
        return 1
    return 1 if found or violations else 0


if __name__ == "__main__":
    sys.exit(main())
