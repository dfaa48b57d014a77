#!/usr/bin/env python3
"""Checks the module layering of slam_mms (ctest `layering`; issue #19).

For every module declared with slam_mms_add_module(NAME DEPS ...) in the top CMakeLists.txt, the
modules its sources and headers include (include/slam_mms/NAME/*, src/NAME/*: both
`#include "slam_mms/<module>/..."` and the private `#include "<module>/..."`) must be exactly its
DEPS. Every DEPS entry must lie in a lower layer, the SDK modules (what slam_mms::slam_mms links)
may depend only on SDK modules, and an installed header (include/slam_mms) may not include a
private one (src/), which an installed tree does not have. The SDK is thin: where the umbrella
header include/slam_mms/slam_mms.hpp exists, every installed header of an SDK module must be
reachable from it through includes (anything else belongs in src/ or in a component).

Usage: check_layers.py [SOURCE_DIR]      check the tree (default: this script's project)
       check_layers.py --self-test       check that each rule catches its violation
Exit status 0 when clean, 1 with one line per violation (file:line where there is one).
"""

import pathlib
import re
import sys
import tempfile

# Layers, bottom up: a module may include only modules of a lower layer.
#   core <- io, ins, surfel <- registration, render_egl, rosbag <- backend <- pipeline
#   eval and sim beside pipeline; drive (offline runner, readers, outputs) and merge (multi-drive
#   adjustment) on top.
LAYER = {
    "core": 0,
    "io": 1, "ins": 1, "surfel": 1,
    "registration": 2, "render_egl": 2, "rosbag": 2,
    "backend": 3,
    "pipeline": 4, "eval": 4, "sim": 4,
    "drive": 5, "merge": 5,
}
SDK = {"core", "ins", "surfel", "render_egl", "registration", "backend", "pipeline"}

MODULE_RE = re.compile(r"slam_mms_add_module\(\s*(\w+)([^)]*)\)", re.S)
KEYWORDS = {"DEPS", "PUBLIC_LIBS", "PRIVATE_LIBS"}
INCLUDE_RE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')


def declared_modules(root):
    """{module: set of DEPS} from the top CMakeLists.txt."""
    text = (root / "CMakeLists.txt").read_text()
    text = re.sub(r"#[^\n]*", "", text)  # comments
    modules = {}
    for name, args in MODULE_RE.findall(text):
        deps, current = set(), None
        for tok in args.split():
            if tok in KEYWORDS:
                current = tok
            elif current == "DEPS":
                deps.add(tok)
        modules[name] = deps
    return modules


def includes_of(root, module, names):
    """[(file, line, included module, header text)] for module's own files."""
    out = []
    for base in (root / "include" / "slam_mms" / module, root / "src" / module):
        if not base.is_dir():
            continue
        for f in sorted(base.rglob("*")):
            if f.suffix not in (".hpp", ".cpp", ".h", ".cc", ".inl"):
                continue
            for n, line in enumerate(f.read_text(errors="replace").splitlines(), 1):
                m = INCLUDE_RE.match(line)
                if not m:
                    continue
                parts = m.group(1).split("/")
                if parts[0] == "slam_mms" and len(parts) >= 3:
                    out.append((f, n, parts[1], m.group(1), False))
                elif len(parts) >= 2 and parts[0] in names:
                    out.append((f, n, parts[0], m.group(1), True))  # private header
    return out


def check(root):
    root = pathlib.Path(root)
    modules = declared_modules(root)
    errors = []
    if not modules:
        return [f"{root / 'CMakeLists.txt'}: no slam_mms_add_module() found"]
    names = set(modules) | set(LAYER)
    for m, deps in sorted(modules.items()):
        if m not in LAYER:
            errors.append(f"module {m}: not in the layer table of scripts/check_layers.py")
            continue
        used = {}
        for f, n, inc, text, private in includes_of(root, m, names):
            rel = f.relative_to(root)
            if private and str(rel).startswith("include/"):
                errors.append(f"{rel}:{n}: installed header includes the private header "
                              f'"{text}" (src/ is not installed)')
            if inc == m:
                continue
            if inc not in names:
                errors.append(f"{rel}:{n}: includes unknown module {inc} (\"{text}\")")
                continue
            used.setdefault(inc, (rel, n, text))
            if inc not in deps:
                errors.append(f"{rel}:{n}: module {m} includes {inc} (\"{text}\"), which is not in "
                              f"its DEPS ({' '.join(sorted(deps)) or 'none'})")
        for d in sorted(deps):
            if d not in LAYER:
                errors.append(f"module {m}: DEPS names unknown module {d}")
                continue
            if LAYER[d] >= LAYER[m]:
                errors.append(f"module {m} (layer {LAYER[m]}) depends on {d} (layer {LAYER[d]}): "
                              "an arrow against the layers")
            if m in SDK and d not in SDK:
                errors.append(f"module {m} is in the SDK (slam_mms::slam_mms) but depends on {d}, "
                              "a component")
            if d not in used:
                errors.append(f"module {m}: DEPS lists {d}, which none of its files includes")
    errors += unreachable_sdk_headers(root)
    return errors


def unreachable_sdk_headers(root):
    """Installed headers of SDK modules that the umbrella header does not reach."""
    inc = root / "include"
    umbrella = inc / "slam_mms" / "slam_mms.hpp"
    if not umbrella.is_file():
        return []
    seen, stack = set(), ["slam_mms/slam_mms.hpp"]
    while stack:
        h = stack.pop()
        if h in seen or not (inc / h).is_file():
            continue
        seen.add(h)
        for line in (inc / h).read_text(errors="replace").splitlines():
            m = INCLUDE_RE.match(line)
            if m and m.group(1).startswith("slam_mms/"):
                stack.append(m.group(1))
    errors = []
    for f in sorted((inc / "slam_mms").rglob("*.hpp")):
        rel = f.relative_to(inc)
        if len(rel.parts) == 3 and rel.parts[1] in SDK and str(rel) not in seen:
            errors.append(f"include/{rel}: installed SDK header that slam_mms/slam_mms.hpp does not "
                          "reach: move it to src/ (internal) or include it from the SDK")
    return errors


def self_test():
    """Each rule must catch its violation in a small synthetic tree; a clean tree must pass."""
    def tree(d, cmake, files):
        d.mkdir(parents=True)
        (d / "CMakeLists.txt").write_text(cmake)
        for path, text in files.items():
            p = d / path
            p.parent.mkdir(parents=True, exist_ok=True)
            p.write_text(text)

    clean_cmake = ("slam_mms_add_module(core PUBLIC_LIBS Eigen3::Eigen)\n"
                   "slam_mms_add_module(surfel DEPS core)\n"
                   "slam_mms_add_module(eval DEPS core PRIVATE_LIBS x)\n")
    clean_files = {
        "include/slam_mms/core/a.hpp": "#pragma once\n",
        "src/core/a.cpp": '#include "slam_mms/core/a.hpp"\n#include "core/p.hpp"\n',
        "src/core/p.hpp": "#pragma once\n",
        "include/slam_mms/surfel/s.hpp": '#include "slam_mms/core/a.hpp"\n',
        "src/eval/e.cpp": '#include "slam_mms/core/a.hpp"\n#include "slam_mms/version.hpp"\n',
    }
    cases = {
        "upward": (clean_cmake.replace("(surfel DEPS core)", "(surfel DEPS core eval)"),
                   {"src/surfel/x.cpp": '#include "slam_mms/eval/e.hpp"\n'},
                   "an arrow against the layers"),
        "undeclared": (clean_cmake, {"src/eval/y.cpp": '#include "slam_mms/surfel/s.hpp"\n'},
                       "not in its DEPS"),
        "unused dep": (clean_cmake.replace("(eval DEPS core", "(eval DEPS core surfel"), {},
                       "none of its files includes"),
        "public includes private": (clean_cmake,
                                    {"include/slam_mms/core/b.hpp": '#include "core/p.hpp"\n'},
                                    "includes the private header"),
        "unreachable sdk header": (clean_cmake,
                                   {"include/slam_mms/slam_mms.hpp":
                                        '#include "slam_mms/surfel/s.hpp"\n',
                                    "include/slam_mms/core/internal.hpp": "#pragma once\n"},
                                   "does not reach"),
        "sdk on component": (clean_cmake.replace("(surfel DEPS core)", "(surfel DEPS core io)")
                             + "slam_mms_add_module(io DEPS core)\n",
                             {"src/surfel/z.cpp": '#include "slam_mms/io/r.hpp"\n',
                              "src/io/r.cpp": '#include "slam_mms/core/a.hpp"\n'},
                             "a component"),
    }
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        d = pathlib.Path(tmp) / "clean"
        tree(d, clean_cmake, clean_files)
        if check(d):
            failures.append(f"clean tree reported: {check(d)}")
        for name, (cmake, extra, expect) in cases.items():
            d = pathlib.Path(tmp) / name.replace(" ", "_")
            tree(d, cmake, {**clean_files, **extra})
            errs = check(d)
            if not any(expect in e for e in errs):
                failures.append(f"case '{name}': expected a line with '{expect}', got {errs}")
    for f in failures:
        print("self-test FAILED:", f)
    print(f"check_layers self-test: {len(cases) + 1 - len(failures)}/{len(cases) + 1} cases pass")
    return 1 if failures else 0


def main(argv):
    if len(argv) > 1 and argv[1] == "--self-test":
        return self_test()
    root = pathlib.Path(argv[1]) if len(argv) > 1 else pathlib.Path(__file__).resolve().parent.parent
    errors = check(root)
    for e in errors:
        print(e)
    modules = declared_modules(root)
    print(f"check_layers: {len(modules)} modules, {len(errors)} violation(s)")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
