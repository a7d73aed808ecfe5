#!/usr/bin/python3
"""The shape of the code: how long its classes, functions and member lists are.

usage: tools/dev/code_shape.py [--max-function N] [--max-members N] DIR...

Prints, for the C++ files under each DIR:
  - every class's header + source lines (the .h and .cc named after it),
  - every function longer than --max-function lines (default 80),
  - every class or struct with more than --max-members data members
    (default 20; members are the declarations ending in `_;`, `_ = …;` or
    `_{…};` at the class's own indentation, the project's style).

A heuristic reader of this project's formatting (clang-format, Google style),
not a C++ parser: a function is a declaration ending in `{` whose text holds
`(`, starting at column 0 or two spaces in (a member defined in its class),
and ends at the line with the closing brace at the same indentation; its
length counts the signature's lines too.
"""
import argparse
import os
import re
import sys

MEMBER = re.compile(r"^\s+[\w:<>,\s\*&\[\]]+\s[\*&]?\w+_(\s*=.*|\{.*\})?;(\s*//.*)?$")
CLASS = re.compile(r"^(\s*)(class|struct)\s+(\w+)[^;]*\{\s*$")


def cpp_files(folder):
    for root, _, names in os.walk(folder):
        for name in sorted(names):
            if name.endswith((".h", ".cc")):
                yield os.path.join(root, name)


def signature_start(lines, i):
    """The first line of the declaration that ends at line i."""
    start = i
    while start > 0:
        previous = lines[start - 1].strip()
        if not previous or previous.endswith((";", "{", "}", ":")) or previous.startswith(("//", "#")):
            break
        start -= 1
    return start


def long_functions(path, lines, limit):
    out = []
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.rstrip().endswith("{") and not CLASS.match(line):
            start = signature_start(lines, i)
            head = " ".join(part.strip() for part in lines[start : i + 1])
            indent = re.match(r"^(\s*)", lines[start]).group(1)
            if (
                len(indent) <= 2
                and "(" in head
                and not head.startswith(("namespace", "extern \"C\" {", "if ", "for ", "while ", "switch "))
                and "=" not in head.split("(")[0]
            ):
                end = i + 1
                while end < len(lines) and not re.match("^" + indent + r"\}", lines[end]):
                    end += 1
                length = end - start + 1
                if length > limit:
                    out.append((length, path, start + 1, head[:90]))
                i = end + 1
                continue
        i += 1
    return out


def crowded_classes(path, lines, limit):
    out = []
    for i, line in enumerate(lines):
        match = CLASS.match(line)
        if not match:
            continue
        indent = match.group(1)
        members = 0
        j = i + 1
        while j < len(lines) and not re.match("^" + indent + r"\};", lines[j]):
            inner = lines[j]
            # Only the class's own level (not nested types or function bodies).
            if re.match("^" + indent + r"  \S", inner) and MEMBER.match(inner):
                members += 1
            j += 1
        if members > limit:
            out.append((members, path, i + 1, match.group(3)))
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("dirs", nargs="+")
    parser.add_argument("--max-function", type=int, default=80)
    parser.add_argument("--max-members", type=int, default=20)
    args = parser.parse_args()
    functions, classes = [], []
    for folder in args.dirs:
        print(f"== {folder}")
        sizes = {}
        for path in cpp_files(folder):
            with open(path, encoding="utf-8") as f:
                lines = f.read().split("\n")
            stem = os.path.splitext(path)[0]
            sizes[stem] = sizes.get(stem, 0) + len(lines) - 1
            functions += long_functions(path, lines, args.max_function)
            classes += crowded_classes(path, lines, args.max_members)
        for stem, count in sorted(sizes.items(), key=lambda item: -item[1]):
            if not stem.endswith("_test"):
                print(f"{count:6d}  {stem}.{{h,cc}}")
    print(f"== functions longer than {args.max_function} lines")
    for length, path, line, text in sorted(functions, reverse=True):
        print(f"{length:6d}  {path}:{line}  {text}")
    print(f"== classes with more than {args.max_members} data members")
    for members, path, line, name in sorted(classes, reverse=True):
        print(f"{members:6d}  {path}:{line}  {name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
