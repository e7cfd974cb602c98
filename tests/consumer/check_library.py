#!/usr/bin/env python3
"""What a consumer of the library relies on, checked on the source tree:
- the umbrella headers are complete: hawor/hawor.hpp includes every top-level header and every
  module's umbrella hawor/<module>/<module>.hpp, and each module umbrella includes every header of
  its folder (detail/ folders excepted); every header's first line of code is #pragma once;
- one version: hawor/version.hpp, CMakeLists.txt's project(VERSION) and package.json agree.
Usage: check_library.py SOURCE_DIR   (prints one line per problem; exit 1 if any)"""
import json
import re
import sys
from pathlib import Path

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def included(header: Path, folder: Path) -> set:
    """Headers `header` includes, as paths relative to the include root's hawor/ folder."""
    out = set()
    for name in INCLUDE.findall(header.read_text(encoding="utf-8")):
        # "hawor/<m>/x.hpp" (from the include root) or "x.hpp" / "<m>/x.hpp" (relative).
        out.add(name[len("hawor/"):] if name.startswith("hawor/") else str((folder / name).relative_to(root)))
    return out


source = Path(sys.argv[1]).resolve()
root = source / "include" / "hawor"
problems = []
for h in sorted(root.rglob("*.hpp")):
    code = [l for l in h.read_text(encoding="utf-8").splitlines() if l.strip() and not l.lstrip().startswith("//")]
    if not code or code[0].strip() != "#pragma once":
        problems.append(f"{h.relative_to(root)}: the first line of code is not #pragma once")

top = included(root / "hawor.hpp", root)
for h in sorted(root.glob("*.hpp")):
    if h.name != "hawor.hpp" and h.name not in top:
        problems.append(f"hawor.hpp does not include {h.name}")
modules = sorted(d for d in root.iterdir() if d.is_dir())
for m in modules:
    umbrella = m / f"{m.name}.hpp"
    if not umbrella.exists():
        problems.append(f"{m.name}/: no umbrella header {m.name}/{m.name}.hpp")
        continue
    if f"{m.name}/{m.name}.hpp" not in top:
        problems.append(f"hawor.hpp does not include {m.name}/{m.name}.hpp")
    inc = included(umbrella, m)
    for h in sorted(m.glob("*.hpp")):
        rel = f"{m.name}/{h.name}"
        if h != umbrella and rel not in inc:
            problems.append(f"{m.name}/{m.name}.hpp does not include {h.name}")

versions = {
    "include/hawor/version.hpp": re.search(r'#define HAWOR_VERSION_STRING "([^"]+)"', (root / "version.hpp").read_text()),
    "CMakeLists.txt": re.search(r"project\(hawor VERSION (\S+)", (source / "CMakeLists.txt").read_text()),
}
versions = {k: (m.group(1) if m else None) for k, m in versions.items()}
versions["package.json"] = json.loads((source / "package.json").read_text()).get("version")
if None in versions.values() or len(set(versions.values())) != 1:
    problems.append("the version differs: " + ", ".join(f"{k} {v}" for k, v in versions.items()))

for p in problems:
    print(p)
print(f"{len(modules)} modules, version {versions['CMakeLists.txt']}: {len(problems)} problems")
sys.exit(1 if problems else 0)
