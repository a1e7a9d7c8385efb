#!/usr/bin/env python3
"""The code-shape rules of ARCHITECTURE.md, checked: no source file under crates/*/src longer than 800
lines, no function there longer than 80 lines of code (comment and blank lines aside, so a `// SAFETY:`
line costs nothing; tests modules aside), no shader file under glsl/ longer than 400 lines, and no
barrier recorded outside the device crate's sync module (the graph plans every other one). Prints each
violation; exits 1 if there is any. Run by scripts/test.sh."""
import pathlib
import re
import sys

root = pathlib.Path(__file__).resolve().parent.parent
MAX_FILE, MAX_FN, MAX_SHADER = 800, 80, 400
problems = []
fn_re = re.compile(r"^\s*(pub(\([a-z]+\))?\s+)?(const\s+)?(unsafe\s+)?(extern\s+\"[^\"]+\"\s+)?fn\s+(\w+)")

for path in sorted(root.glob("crates/*/src/**/*.rs")):
    rel = path.relative_to(root)
    lines = path.read_text().split("\n")
    if len(lines) > MAX_FILE:
        problems.append(f"{rel}: {len(lines)} lines (at most {MAX_FILE})")
    in_tests = False
    k = 0
    while k < len(lines):
        line = lines[k]
        if re.match(r"^\s*#\[cfg\(test\)\]", line):
            in_tests = True  # test modules come last in a file
        m = fn_re.match(line)
        if m and not in_tests:
            # The body runs from the first `{` at the signature's end to its matching `}`.
            depth, start, end = 0, k, None
            for j in range(k, len(lines)):
                code = re.sub(r'"(\\.|[^"\\])*"|//.*$|\'.\'', "", lines[j])
                if depth == 0 and ";" in code and "{" not in code and j > k and code.strip().endswith(";"):
                    break  # a declaration without a body (trait method)
                depth += code.count("{") - code.count("}")
                if depth == 0 and "{" in "".join(lines[k : j + 1]):
                    end = j
                    break
            if end is not None:
                n = sum(1 for t in lines[start : end + 1] if t.strip() and not t.strip().startswith("//"))
                if n > MAX_FN:
                    problems.append(f"{rel}:{start + 1}: fn {m.group(6)} is {n} lines (at most {MAX_FN})")
                k = end
        if "cmd_pipeline_barrier" in line and not str(rel).endswith("device/src/sync.rs"):
            problems.append(f"{rel}:{k + 1}: a barrier recorded outside bounce_device::sync")
        k += 1

for path in sorted(root.glob("glsl/**/*")):
    if path.suffix in (".comp", ".glsl", ".vert", ".frag", ".geom"):
        n = len(path.read_text().split("\n"))
        if n > MAX_SHADER:
            problems.append(f"{path.relative_to(root)}: {n} lines (at most {MAX_SHADER})")

for p in problems:
    print(p)
if problems:
    sys.exit(1)
print("structure: every file ≤ 800 lines, every function ≤ 80 lines of code, every shader ≤ 400 lines, every barrier from the sync module")
