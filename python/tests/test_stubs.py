"""The committed type stub (_slam_mms.pyi) parses and names every public attribute of the built
module (regenerate with python/tools/gen_stubs.py after changing a binding)."""

from __future__ import annotations

import ast
import pathlib

import slam_mms

STUB = pathlib.Path(slam_mms.__file__).with_name("_slam_mms.pyi")


def test_stub_covers_the_module():
    if not STUB.exists():  # the build-tree layout imports the package from python/
        STUB_SRC = pathlib.Path(__file__).resolve().parents[1] / "slam_mms" / "_slam_mms.pyi"
        tree = ast.parse(STUB_SRC.read_text())
    else:
        tree = ast.parse(STUB.read_text())
    names = set()
    for node in tree.body:
        if isinstance(node, (ast.ClassDef, ast.FunctionDef)):
            names.add(node.name)
        elif isinstance(node, ast.Assign):
            names.update(t.id for t in node.targets if isinstance(t, ast.Name))
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
    public = {n for n in dir(slam_mms._C) if not n.startswith("__")}
    missing = sorted(public - names)
    assert not missing, f"not in {STUB.name}: {missing} (run python/tools/gen_stubs.py)"
    assert (pathlib.Path(slam_mms.__file__).with_name("py.typed")).exists()
