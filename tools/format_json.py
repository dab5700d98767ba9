#!/usr/bin/env python3
"""Formats scene/graph JSON files the way the examples are written: 2-space indentation, and any
value whose one-line form fits in the line width kept on one line. Usage: tools/format_json.py FILE..."""
import json
import sys

WIDTH = 110


def fmt(v, indent=0, prefix=0):
    """indent: indentation of the value's closing bracket; prefix: columns used before the value."""
    one = json.dumps(v)
    if not isinstance(v, (dict, list)) or len(one) + indent + prefix <= WIDTH:
        return one
    pad = " " * indent
    inner = " " * (indent + 2)
    if isinstance(v, list):
        return "[\n" + ",\n".join(inner + fmt(x, indent + 2) for x in v) + "\n" + pad + "]"
    return "{\n" + ",\n".join(inner + json.dumps(k) + ": " + fmt(x, indent + 2, len(json.dumps(k)) + 2)
                              for k, x in v.items()) + "\n" + pad + "}"


if __name__ == "__main__":
    for path in sys.argv[1:]:
        with open(path) as f:
            data = json.load(f)
        with open(path, "w") as f:
            f.write(fmt(data) + "\n")
