#!/usr/bin/env python3
"""Largest relative difference between the numbers of two JSON files of the same shape
(e.g. two identification.json). Usage: compare_json.py A.json B.json [IGNORED_KEY...]
Strings and shapes must match exactly; prints the worst path and the count of numbers."""
import json, sys

a, b = (json.load(open(p)) for p in sys.argv[1:3])
ignored = set(sys.argv[3:])
worst = [0.0, "", None, None]
count = [0]

def walk(x, y, path):
    if isinstance(x, dict):
        assert isinstance(y, dict) and x.keys() == y.keys(), path
        for k in x:
            if k not in ignored:
                walk(x[k], y[k], f"{path}.{k}")
    elif isinstance(x, list):
        assert isinstance(y, list) and len(x) == len(y), path
        for i, (u, v) in enumerate(zip(x, y)):
            walk(u, v, f"{path}[{i}]")
    elif isinstance(x, (int, float)) and not isinstance(x, bool):
        count[0] += 1
        d = abs(x - y) / max(abs(x), abs(y), 1e-300) if x != y else 0.0
        if d > worst[0]:
            worst[:] = [d, path, x, y]
    else:
        assert x == y, f"{path}: {x!r} != {y!r}"

walk(a, b, "")
print(f"{count[0]} numbers; max relative difference {worst[0]:.3e} at {worst[1]} ({worst[2]!r} vs {worst[3]!r})")
