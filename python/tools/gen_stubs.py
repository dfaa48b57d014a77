#!/usr/bin/env python3
"""Writes python/slam_mms/_slam_mms.pyi from the built extension (pybind11 signatures and
docstrings), so editors and type checkers see the API:

    PYTHONPATH=build/python:python /usr/bin/python3 python/tools/gen_stubs.py

tests/test_stubs.py checks that the committed stub names every public attribute of the module.
"""

from __future__ import annotations

import inspect
import pathlib
import re
import sys

import slam_mms._slam_mms as C  # noqa: E402  (the package puts the module there)

OUT = pathlib.Path(__file__).resolve().parents[1] / "slam_mms" / "_slam_mms.pyi"

_TYPE_FIXES = [
    (r"numpy\.ndarray\[[^\]]*\]", "numpy.ndarray"),
    (r"numpy\.ndarray\[numpy\.float\d+\[[^\]]*\]\]", "numpy.ndarray"),
    (r"\bos\.PathLike\b", "os.PathLike[str]"),
    (r"_slam_mms\.", ""),
    (r"slam_mms::[A-Za-z_:<>]+", "typing.Any"),
    (r"std::[A-Za-z_:<>]+", "typing.Any"),
    (r"\bpathlib\.Path\b", "pathlib.Path"),
]


def _strip_array_params(sig: str) -> str:
    """numpy.ndarray[numpy.float64[3, 1], ...] -> numpy.ndarray (bracket-matched)."""
    key = "numpy.ndarray["
    while key in sig:
        i = sig.index(key)
        depth, j = 0, i + len(key) - 1
        while j < len(sig):
            depth += {"[": 1, "]": -1}.get(sig[j], 0)
            if depth == 0:
                break
            j += 1
        sig = sig[:i] + "numpy.ndarray" + sig[j + 1:]
    return sig


def _fix(sig: str) -> str:
    sig = _strip_array_params(sig)
    for pat, rep in _TYPE_FIXES:
        sig = re.sub(pat, rep, sig)
    # numpy arrays nested: strip leftover brackets like numpy.ndarray[...]] once more
    sig = re.sub(r"numpy\.ndarray\[[^()]*?\](?=[,)\]])", "numpy.ndarray", sig)
    # default values pybind renders as <...> objects
    sig = re.sub(r"= <[^>]*>", "= ...", sig)
    sig = re.sub(r"=\s*[A-Za-z_][\w.]*\.(?:[A-Z_]+)\b", "= ...", sig)
    return sig


def _doc_lines(doc: str, indent: str) -> list:
    doc = doc.strip().replace('"""', "'''")
    if not doc:
        return []
    return [f'{indent}"""{doc}"""']


def _signatures(obj, name: str):
    doc = obj.__doc__ or ""
    sigs, rest = [], []
    for line in doc.splitlines():
        m = re.match(rf"^(?:\d+\. )?{re.escape(name)}(\(.*\)\s*->\s*.+)$", line.strip())
        if m:
            sigs.append(_fix(m.group(1)))
        elif not line.startswith("Overloaded function."):
            rest.append(line)
    text = "\n".join(rest).strip()
    return sigs, text


def _function(name: str, obj, indent: str, method: bool) -> list:
    sigs, text = _signatures(obj, name)
    if not sigs:
        sigs = ["(*args, **kwargs) -> typing.Any"]
    out = []
    for sig in sigs:
        if len(sigs) > 1:
            out.append(f"{indent}@typing.overload")
        out.append(f"{indent}def {name}{sig}:")
        body = _doc_lines(text, indent + "    ") if len(sigs) == 1 else []
        out.extend(body or [f"{indent}    ..."])
    return out


def _class(name: str, cls) -> list:
    bases = [b.__name__ for b in cls.__bases__ if b.__module__ == C.__name__]
    out = [f"class {name}({', '.join(bases)}):" if bases else f"class {name}:"]
    if cls.__doc__ and not cls.__doc__.startswith(name + "("):
        out.extend(_doc_lines(cls.__doc__, "    "))
    members = cls.__dict__
    if "__members__" in members:  # a pybind11 enum
        for value in cls.__members__:
            out.append(f"    {value}: typing.ClassVar[{name}]")
        out.append("    def __init__(self, value: int) -> None: ...")
        out.append("    def __int__(self) -> int: ...")
        out.append("    @property\n    def name(self) -> str: ...")
        out.append("    @property\n    def value(self) -> int: ...")
        return out
    if "_fields" in members:
        out.append("    _fields: typing.ClassVar[tuple]")
        out.append("    def to_dict(self) -> dict: ...")
    for attr, obj in members.items():
        if attr.startswith("_") and attr not in ("__init__", "__len__", "__getitem__",
                                                 "__iter__", "__next__", "__eq__", "__copy__"):
            continue
        if isinstance(obj, property):
            sig = _fix((obj.fget.__doc__ or "").splitlines()[0]) if obj.fget else ""
            m = re.search(r"->\s*(.+)$", sig)
            rtype = m.group(1) if m else "typing.Any"
            doc = obj.__doc__ or ""
            doc = "\n".join(l for l in doc.splitlines() if "->" not in l).strip()
            out.append("    @property")
            out.append(f"    def {attr}(self) -> {rtype}:")
            out.extend(_doc_lines(doc, "        ") or ["        ..."])
            if obj.fset is not None:
                out.append(f"    @{attr}.setter")
                out.append(f"    def {attr}(self, value: {rtype}) -> None: ...")
        elif inspect.isroutine(obj) or type(obj).__name__ in ("instancemethod", "builtin_function_or_method"):
            static = isinstance(obj, staticmethod) or type(obj).__name__ == "staticmethod"
            fn = obj.__func__ if static else obj
            if static:
                out.append("    @staticmethod")
            out.extend(_function(attr, fn, "    ", not static))
    return out


def main() -> int:
    lines = [
        '"""Type stubs of slam_mms._slam_mms (generated by python/tools/gen_stubs.py)."""',
        "",
        "import os",
        "import pathlib",
        "import typing",
        "from typing import Any, Callable, Dict, Iterator, List, Optional, Tuple, Union",
        "",
        "import numpy",
        "",
        "__version__: str",
        "HAVE_OPEN_DRIVE: bool",
        "HAVE_FOLDER_READER: bool",
        "HAVE_ROSBAG_READER: bool",
        "",
        "class Error(RuntimeError):",
        '    """A slam_mms Status other than InvalidArgument/NotFound/OutOfRange."""',
        "    code: str",
        "",
    ]
    names = sorted(n for n in dir(C) if not n.startswith("__"))
    aliases = []
    for n in names:
        obj = getattr(C, n)
        if n in ("Error",) or isinstance(obj, bool) or isinstance(obj, str):
            continue
        if inspect.isclass(obj):
            if obj.__name__ != n:
                aliases.append(f"{n} = {obj.__name__}")
                continue
            lines.extend(_class(n, obj))
            lines.append("")
        elif callable(obj):
            lines.extend(_function(n, obj, "", False))
            lines.append("")
    lines.extend(aliases)
    OUT.write_text("\n".join(lines) + "\n")
    print(f"wrote {OUT} ({len(lines)} lines)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
