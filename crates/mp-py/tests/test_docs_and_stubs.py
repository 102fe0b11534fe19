"""The package's stubs and PYTHON.md describe what the package has: every public name, every
keyword each function takes, and every method and property of each class."""

import ast
import inspect
import pathlib
import re

import motion_programs as mp

ROOT = pathlib.Path(__file__).resolve().parents[3]
STUBS = ROOT / "crates/mp-py/python/motion_programs/__init__.pyi"
GUIDE = ROOT / "docs/PYTHON.md"


def stub_tree():
    return ast.parse(STUBS.read_text())


def stub_functions():
    """Module-level functions of the stubs: name → set of parameter names (over overloads)."""
    out = {}
    for node in stub_tree().body:
        if isinstance(node, ast.FunctionDef):
            a = node.args
            names = {x.arg for x in a.args + a.kwonlyargs}
            out.setdefault(node.name, set()).update(names)
    return out


def stub_classes():
    """Classes of the stubs: name → set of member names."""
    out = {}
    for node in stub_tree().body:
        if isinstance(node, ast.ClassDef):
            out[node.name] = {
                n.name for n in node.body if isinstance(n, (ast.FunctionDef, ast.AnnAssign))
            } | {n.target.id for n in node.body if isinstance(n, ast.AnnAssign)}
    return out


def test_every_public_name_is_in_the_stubs_and_the_guide():
    funcs, classes = stub_functions(), stub_classes()
    guide = GUIDE.read_text()
    for name in mp.__all__:
        assert name in funcs or name in classes, f"{name} is not in __init__.pyi"
        if not name.endswith("Error"):
            assert re.search(rf"\b{name}\b", guide), f"{name} is not in docs/PYTHON.md"


def test_every_keyword_a_function_takes_is_in_its_stub():
    funcs = stub_functions()
    for name in mp.__all__:
        obj = getattr(mp, name)
        if inspect.isclass(obj) or not callable(obj):
            continue
        sig = inspect.signature(obj)
        missing = set(sig.parameters) - funcs[name]
        assert not missing, f"{name}: {sorted(missing)} missing from __init__.pyi"


def test_every_method_and_property_of_a_class_is_in_its_stub():
    classes = stub_classes()
    for name in mp.__all__:
        obj = getattr(mp, name)
        if not inspect.isclass(obj) or issubclass(obj, BaseException):
            continue
        public = {m for m in dir(obj) if not m.startswith("_")}
        missing = public - classes.get(name, set())
        assert not missing, f"{name}: {sorted(missing)} missing from __init__.pyi"
