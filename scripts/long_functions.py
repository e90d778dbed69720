#!/usr/bin/python3
"""Lists the functions of the C++ sources longer than a limit (default 150 lines), longest first.

A function is a definition whose body opens with '{' at the end of a line that holds a ')'
closing its parameter list (or a constructor's initialiser list), outside any other function;
its length is the lines from that line to the matching '}'. Lambdas and nested bodies are counted
inside their function. Usage: scripts/long_functions.py [LIMIT] [DIR ...] (default models sim workloads).
"""
import pathlib
import re
import sys

CONTROL = re.compile(r'^\s*(if|for|while|switch|catch|do|else|try)\b|\bnamespace\b|^\s*(struct|class|enum|union)\b|=\s*\{$|^\s*\{$')


def strip(line):
    line = re.sub(r'"(\\.|[^"\\])*"', '""', line)
    line = re.sub(r"'(\\.|[^'\\])*'", "''", line)
    return line.split('//')[0]


def functions(path):
    lines = path.read_text(errors='replace').splitlines()
    depth = 0
    scope = []  # stack of (kind, start line, name)
    out = []
    pending_sig = []
    for i, raw in enumerate(lines, 1):
        line = strip(raw)
        opens = line.count('{')
        closes = line.count('}')
        in_function = any(k == 'f' for k, _, _ in scope)
        if opens > closes and not in_function and line.rstrip().endswith('{') and not CONTROL.search(line):
            sig = ' '.join(pending_sig[-3:] + [line])
            m = re.search(r'([\w:~<>]+)\s*\([^;]*\)\s*(const)?\s*(noexcept)?\s*(override)?\s*(->\s*[\w:<>]+)?\s*(:.*)?\{\s*$', sig)
            if m and ')' in sig:
                scope.append(('f', i, m.group(1)))
                depth += opens - closes
                pending_sig = []
                continue
        for _ in range(opens):
            scope.append(('b', i, ''))
        for _ in range(closes):
            if not scope:
                break
            kind, start, name = scope.pop()
            if kind == 'f':
                out.append((i - start + 1, name, start))
        depth += opens - closes
        pending_sig = (pending_sig + [line.strip()])[-3:] if line.strip() else pending_sig
    return out


def main():
    args = sys.argv[1:]
    limit = int(args.pop(0)) if args and args[0].isdigit() else 150
    dirs = args or ['models', 'sim', 'workloads']
    rows = []
    for d in dirs:
        for p in sorted(pathlib.Path(d).rglob('*.cpp')) + sorted(pathlib.Path(d).rglob('*.hpp')):
            for n, name, start in functions(p):
                if n > limit:
                    rows.append((n, f'{p}:{start}', name))
    for n, where, name in sorted(rows, reverse=True):
        print(f'{n:5d}  {where}  {name}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
