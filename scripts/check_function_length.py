#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Fails when a function of the library, apps/, examples/ or python/ is longer than 80 lines.

A function's length runs from the first line of its declarator (after any `template <…>`
line) to the line of its closing brace, both counted, so a multi-line signature counts. C++
sources (.h, .cc) are read without a compiler: comments, string and character literals and
preprocessor lines are blanked, then the braces are followed through namespaces and class
bodies. A brace opens a function body when the text before it (since the last `;`, `{` or
`}` of its scope) has a parenthesis outside any brace, no `=` outside parentheses (which
would make it an initializer), and names no class, struct, union or enum; a constructor's
member initializers (`: a_(x), b_{y} {`) are stepped over to the body. A lambda or a local
class inside a function counts as part of that function. Python sources (.py) are measured
with the ast module, a function from its `def` line to its last line.

Prints one line per function over the limit, `LINES FILE:LINE NAME`, longest first, and
exits 1; exits 0 when there is none. Exits 2 when a file's braces do not balance (the check
would otherwise miss what follows).

    scripts/check_function_length.py [ROOT] [--limit N] [--allow FILE:NAME]... [FOLDER...]

--allow FILE:NAME lets one function be long (NAME as printed, e.g. `Class::name`); it is for a
function that another branch is splitting, and is reported as a note while it stays long.
    scripts/check_function_length.py --self-test   # the check finds planted long functions
"""
import ast
import pathlib
import re
import sys
import tempfile

FOLDERS = ["io", "autodiff", "fields", "integrators", "solvers", "apps", "examples", "python"]
LIMIT = 80
CLASS_HEAD = re.compile(r"^(?:typedef\s+)?(class|struct|union|enum)\b")
NAMESPACE_HEAD = re.compile(r"^(?:inline\s+)?namespace\b|^extern\b")
ACCESS_LABEL = re.compile(r"(?:public|private|protected)\s*:(?!:)")


class Unbalanced(Exception):
    pass


def blank(text):
    """Comments, literals and preprocessor lines as spaces; newlines kept, so offsets keep their lines."""
    out = list(text)
    i, n = 0, len(text)
    line_start = True
    while i < n:
        c = text[i]
        if line_start and c == "#" or (line_start and c in " \t" and text[i:].lstrip(" \t").startswith("#")):
            j = i
            while j < n and text[j] != "\n":  # to the end of the line, through continuations
                if text[j] == "\\" and j + 1 < n and text[j + 1] == "\n":
                    j += 1
                j += 1
            for k in range(i, j):
                if out[k] != "\n":
                    out[k] = " "
            i = j
            continue
        line_start = c == "\n"
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
        elif text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'R"([^(]*)\(', text[i:])
            if not m:
                i += 1
                continue
            j = text.find(")" + m.group(1) + '"', i)
            j = n if j < 0 else j + len(m.group(1)) + 2
        elif c == '"' or (c == "'" and not (i > 0 and text[i - 1].isalnum())):  # not a digit separator
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j += 1
        else:
            i += 1
            continue
        for k in range(i, min(j, n)):
            if out[k] != "\n":
                out[k] = " "
        i = j
    return "".join(out)


def matching(code, i):
    """The offset of the brace or parenthesis that closes the one at code[i]."""
    pairs = {"{": "}", "(": ")", "[": "]"}
    stack = [pairs[code[i]]]
    for j in range(i + 1, len(code)):
        c = code[j]
        if c in pairs:
            stack.append(pairs[c])
        elif c in "})]":
            if c != stack.pop():
                raise Unbalanced(f"'{c}' does not close what is open")
            if not stack:
                return j
    raise Unbalanced("a bracket is never closed")


def head_start(code, start, brace):
    """Where the declarator before code[brace] begins: past blanks, access labels and `template <…>`."""
    while True:
        while start < brace and code[start].isspace():
            start += 1
        m = ACCESS_LABEL.match(code, start, brace)
        if m:
            start = m.end()
            continue
        m = re.compile(r"template\s*<").match(code, start, brace)
        if not m:
            return start
        depth, j = 0, m.end() - 1
        while j < brace:
            depth += {"<": 1, ">": -1}.get(code[j], 0)
            if depth == 0:
                break
            j += 1
        start = j + 1


def depth0(head):
    """The head with everything inside parentheses and brackets removed."""
    out, depth = [], 0
    for c in head:
        if c in "([":
            depth += 1
        elif c in ")]":
            depth -= 1
        elif depth == 0:
            out.append(c)
    return "".join(out)


def is_function_head(head):
    flat = depth0(head)
    if "(" not in head or CLASS_HEAD.match(head) or NAMESPACE_HEAD.match(head):
        return False
    # An `=` outside parentheses makes an initializer, unless it belongs to an operator's name.
    flat = re.sub(r"operator\s*(?:[=!<>+\-*/%&|^]=?|<<=?|>>=?|==|\(\s*\))", "operator", flat)
    return "=" not in flat.replace("==", "").replace("<=", "").replace(">=", "").replace("!=", "")


def has_initializers(head):
    """A constructor's `:` after its parameter list (not a `::`), outside parentheses."""
    close = head.rfind(")")
    flat = depth0(head[close:]) if close >= 0 else ""
    return re.search(r"(?<!:):(?!:)", flat) is not None


def function_body(code, i, head):
    """The offset of the brace that opens the body, from the first brace at i after `head`."""
    if not has_initializers(head):
        return i
    while True:  # a member's brace initializer follows its name (or a template's `>`)
        before = code[:i].rstrip()
        if not (before[-1:].isalnum() or before[-1:] in "_>"):
            return i
        i = matching(code, i) + 1
        while i < len(code) and code[i] not in "{;":
            i += 1
        if i >= len(code) or code[i] == ";":
            raise Unbalanced("a constructor's initializers end without a body")


def scan(code, begin, end, found, scope=""):
    """Functions in code[begin:end] (a namespace or class body): (first line offset, close offset, head)."""
    i, start = begin, begin
    while i < end:
        c = code[i]
        if c in ";}":
            start = i + 1
        elif c in "([":
            i = matching(code, i)
        elif c == "{":
            first = head_start(code, start, i)
            declarator = code[first:i].strip()
            close = matching(code, i)
            if NAMESPACE_HEAD.match(declarator):
                scan(code, i + 1, close, found, scope)
            elif CLASS_HEAD.match(declarator) and not declarator.startswith("enum"):
                words = re.findall(r"[A-Za-z_]\w*", declarator.split(":")[0])
                inner = words[-1] if len(words) > 1 and words[-1] != "final" else words[-2] if len(words) > 2 else ""
                scan(code, i + 1, close, found, scope + inner + "::")
            elif is_function_head(declarator):
                body = function_body(code, i, declarator)
                close = matching(code, body)
                found.append((first, close, scope + function_name(declarator)))
            i = close
            start = close + 1
        i += 1


def function_name(declarator):
    """`Class::name` of a declarator, template arguments left out."""
    name = declarator[:declarator.index("(")].split()[-1] if declarator.index("(") else declarator
    if name.endswith("operator") or not name:  # operator()(...)
        name = declarator.split()[0] if declarator.split() else "?"
    return re.sub(r"<[^<>]*>", "", name).lstrip("*&")


def cc_functions(text):
    code = blank(text)
    found = []
    scan(code, 0, len(code), found)
    line = lambda offset: code.count("\n", 0, offset) + 1
    return [(line(close) - line(first) + 1, line(first), name) for first, close, name in found]


def py_functions(text):
    out = []
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            out.append((node.end_lineno - node.lineno + 1, node.lineno, node.name))
    return out


def long_functions(root, folders, limit):
    """(lines, path, line, name) of every function over `limit`; raises Unbalanced naming the file."""
    long = []
    for folder in folders:
        for path in sorted((root / folder).rglob("*")):
            if path.suffix not in (".h", ".cc", ".py") or not path.is_file():
                continue
            text = path.read_text(encoding="utf-8")
            try:
                functions = py_functions(text) if path.suffix == ".py" else cc_functions(text)
            except Unbalanced as e:
                raise Unbalanced(f"{path.relative_to(root)}: {e}") from None
            for lines, line, name in functions:
                if lines > limit:
                    long.append((lines, str(path.relative_to(root)), line, name))
    return sorted(long, key=lambda f: (-f[0], f[1], f[2]))


SELF_TEST = {
    "solvers/a.cc": """
namespace x {
// a comment with a brace {
template <typename T>
std::vector<int> Foo<T>::long_one(int a,
                                  int b) const {
  const char* s = "}";
%s
}
Foo::Foo(int a) : a_(a), b_{a, 2}, c_(std::max(a, 1)) {
%s
}
struct Bar {
  int short_one() const { return 1; }
 private:
  void in_class(int n) {
%s
  }
  int x_ = 0;
};
const std::vector<int> kTable = {1, 2,
%s
};
void at_the_limit() {
%s}
}  // namespace x
""" % ("  f();\n" * 80, "  g();\n" * 79, "    h();\n" * 79, "  3,\n" * 90, "  k();\n" * 78),
    "apps/b.py": "def long_one():\n" + "    x = 1\n" * 80 + "\n\ndef short_one():\n    return 1\n",
}


def self_test():
    """Finds the planted long ones (multi-line signature, initializers, in a class, Python), not the
    table or the function of exactly the limit, and reports unbalanced braces."""
    with tempfile.TemporaryDirectory() as folder:
        root = pathlib.Path(folder)
        for name, text in SELF_TEST.items():
            (root / name).parent.mkdir(parents=True, exist_ok=True)
            (root / name).write_text(text, encoding="utf-8")
        found = [(lines, path, line) for lines, path, line, _ in long_functions(root, FOLDERS, LIMIT)]
        expected = [(85, "solvers/a.cc", 5), (82, "solvers/a.cc", 90), (82, "solvers/a.cc", 175),
                    (81, "apps/b.py", 1)]
        if found != expected:
            print(f"self-test: expected {expected}; found {found}")
            return 1
        (root / "solvers/a.cc").write_text("void f() {\n  {\n}\n", encoding="utf-8")
        try:
            long_functions(root, FOLDERS, LIMIT)
        except Unbalanced:
            return 0
        print("self-test: an unbalanced file went unreported")
        return 1


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    args, limit, allowed = argv[1:], LIMIT, set()
    while "--limit" in args or "--allow" in args:
        k = args.index("--limit") if "--limit" in args else args.index("--allow")
        if args[k] == "--limit":
            limit = int(args[k + 1])
        else:
            allowed.add(args[k + 1])
        del args[k:k + 2]
    root = pathlib.Path(args[0] if args else ".")
    try:
        long = long_functions(root, args[1:] or FOLDERS, limit)
    except Unbalanced as e:
        print(f"check_function_length: {e}")
        return 2
    failing = [f for f in long if f"{f[1]}:{f[3]}" not in allowed]
    for lines, path, line, name in long:
        note = " (allowed: --allow)" if (lines, path, line, name) not in failing else ""
        print(f"{lines} {path}:{line} {name}{note}")
    if failing:
        print(f"{len(failing)} function(s) over {limit} lines")
    return 1 if failing else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
