#!/usr/bin/python3
"""Fails on an #include that points up the layers (docs/architecture.md "Layers"):

    runtime/base        <- everything may use it; it uses nothing of ours
    kernels             <- base
    runtime/engine      <- base, kernels
    drivers             <- base (drivers/input and drivers/output never use each
                           other; both may use drivers/can, drivers/codec,
                           drivers/dds, drivers/module, drivers/watchdog)
    the application     <- all of the above: runtime/config, runtime/pose,
                           runtime/loop, runtime/cli

  tools/check_layers.py [ROOT]     prints each offending include; exit 1 if any
"""
import os
import re
import sys

ROOT = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
APP = "app"
# (folder prefix, layer), longest prefix first.
LAYERS = [
    ("runtime/base/", "base"),
    ("kernels/", "kernels"),
    ("runtime/engine/", "engine"),
    ("drivers/input/", "drivers/input"),
    ("drivers/output/", "drivers/output"),
    ("drivers/codec/", "drivers/shared"),
    ("drivers/can/", "drivers/shared"),
    ("drivers/dds/", "drivers/shared"),
    ("drivers/watchdog/", "drivers/shared"),
    ("drivers/module/", "drivers/shared"),
    ("runtime/config/", APP),
    ("runtime/pose/", APP),
    ("runtime/loop/", APP),
    ("runtime/cli/", APP),
]
ALLOWED = {
    "base": {"base"},
    "kernels": {"base", "kernels"},
    "engine": {"base", "kernels", "engine"},
    "drivers/shared": {"base", "drivers/shared"},
    "drivers/input": {"base", "drivers/shared", "drivers/input"},
    "drivers/output": {"base", "drivers/shared", "drivers/output"},
    APP: {"base", "kernels", "engine", "drivers/shared", "drivers/input", "drivers/output", APP},
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def layer_of(path):
    for prefix, layer in LAYERS:
        if path.startswith(prefix):
            return layer
    return None


def main():
    bad = []
    checked = 0
    for top in ("runtime", "kernels", "drivers"):
        for d, _, files in os.walk(os.path.join(ROOT, top)):
            for f in files:
                if not f.endswith((".h", ".cc", ".inl")):
                    continue
                path = os.path.relpath(os.path.join(d, f), ROOT)
                mine = layer_of(path)
                if mine is None:
                    bad.append(f"{path}: in no layer (add its folder to tools/check_layers.py)")
                    continue
                checked += 1
                with open(os.path.join(ROOT, path), encoding="utf-8") as fh:
                    text = fh.read()
                for m in INCLUDE.finditer(text):
                    target = layer_of(m.group(1))
                    if target is None or target in ALLOWED[mine]:
                        continue  # generated or third-party headers, or allowed
                    line = text.count("\n", 0, m.start()) + 1
                    bad.append(f"{path}:{line}: {mine} includes {m.group(1)} ({target})")
    if bad:
        print("layers: includes that point up (docs/architecture.md \"Layers\"):", file=sys.stderr)
        for b in bad:
            print("  " + b, file=sys.stderr)
        return 1
    print(f"layers: ok ({checked} files)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
