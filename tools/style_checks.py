#!/usr/bin/python3
"""Two of .clang-tidy's rules, checked in a second rather than in clang-tidy's minutes
(CTest `code_style` runs this beside clang-format):

  - no function in src/app, src/run, src/agents or src/session longer than 120 lines
    (readability-function-size: a newcomer reads a function whole);
  - every enumerator of an `enum class` in src/, tests/ and bench/ is kCamelCase
    (readability-identifier-naming).

It reads C++ as text: comments, strings and character literals are blanked first, then
braces are matched. A function is a brace block that opens at namespace or class scope
right after a parameter list. `run-clang-tidy -p build` applies the full .clang-tidy.

  tools/style_checks.py [ROOT]   exit 1 and one line per finding when there are any
"""
import os
import re
import sys

MAX_FUNCTION_LINES = 120
FUNCTION_DIRS = ("src/app", "src/run", "src/agents", "src/session")
ENUM_DIRS = ("src", "tests", "bench")
ENUMERATOR = re.compile(r"^k[A-Z][A-Za-z0-9]*$")

TOKEN = re.compile(
    r'//[^\n]*|/\*.*?\*/|R"(?P<d>[^(\s]*)\(.*?\)(?P=d)"|"(?:\\.|[^"\\\n])*"|(?<![0-9A-Za-z_])\'(?:\\.|[^\'\\\n])+\'',
    re.S,
)


def blank(text):
    """The text with comments, strings and character literals blanked (newlines kept)."""
    return TOKEN.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), text)


def statement_head(code, brace):
    """What stands before the brace at `brace`, back to the previous ; { or }."""
    start = max(code.rfind(";", 0, brace), code.rfind("{", 0, brace), code.rfind("}", 0, brace)) + 1
    return code[start:brace].strip()


def opens_function(head):
    if not head or re.match(r"^(if|for|while|switch|catch|do|else|try)\b", head):
        return False
    if re.search(r"\b(class|struct|union|enum|namespace)\b", head.split("(")[0]):
        return False
    if "=" in head.split("(")[0] or head.startswith("[") or re.search(r"\]\s*\(", head):
        return False  # an initialiser, a lambda
    head = re.sub(r"->\s*[\w:<>,\s&*]+$", "", head)  # a trailing return type
    head = re.sub(r"\b(const|override|final|noexcept|mutable|volatile)\b|&+", " ", head).strip()
    if head.endswith(")"):
        return True
    # a constructor with an initialiser list: `X(...) : a_(1), b_(2)`
    return re.search(r"\)\s*:\s*[\w:]+\s*[({]", head) is not None


def long_functions(path, code):
    findings = []
    stack = []  # (kind, start index) per open brace: "scope" or "function" or "block"
    for i, ch in enumerate(code):
        if ch == "{":
            in_function = any(kind == "function" for kind, _ in stack)
            kind = "block"
            if not in_function:
                head = statement_head(code, i)
                kind = "function" if opens_function(head) else "scope"
            stack.append((kind, i))
        elif ch == "}" and stack:
            kind, start = stack.pop()
            if kind != "function":
                continue
            lines = code.count("\n", start, i) - 1
            if lines > MAX_FUNCTION_LINES:
                line = code.count("\n", 0, start) + 1
                head = statement_head(code, start).split("(")[0].split()[-1]
                findings.append(f"{path}:{line}: function '{head}' is {lines} lines long (at most {MAX_FUNCTION_LINES})")
    return findings


def bad_enumerators(path, code):
    findings = []
    for m in re.finditer(r"\benum\s+class\s+(\w+)[^{;]*\{([^}]*)\}", code):
        for item in m.group(2).split(","):
            name = item.split("=")[0].strip()
            if name and not ENUMERATOR.match(name):
                line = code.count("\n", 0, m.start()) + 1
                findings.append(f"{path}:{line}: enumerator '{name}' of {m.group(1)} is not kCamelCase")
    return findings


def sources(root, dirs):
    for d in dirs:
        for folder, _, files in os.walk(os.path.join(root, d)):
            for f in sorted(files):
                if f.endswith((".cpp", ".hpp", ".h", ".cc")):
                    yield os.path.join(folder, f)


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), ".."))
    findings = []
    for path in sources(root, ENUM_DIRS):
        with open(path, encoding="utf-8") as f:
            code = blank(f.read())
        rel = os.path.relpath(path, root)
        findings += bad_enumerators(rel, code)
        if rel.startswith(FUNCTION_DIRS):
            findings += long_functions(rel, code)
    for line in findings:
        print(line)
    return 1 if findings else 0


if __name__ == "__main__":
    sys.exit(main())
