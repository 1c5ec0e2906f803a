"""The package's surface: every name of the extension module has a type stub, every public
name is exported, and the stubs and docstrings ship in the installed package."""

from __future__ import annotations

import ast
import inspect
from pathlib import Path

import pgt
from pgt import _pgt


def stub_names() -> set:
    stub = Path(pgt.__file__).with_name("_pgt.pyi")
    assert stub.is_file(), "the type stubs are installed beside the package"
    assert Path(pgt.__file__).with_name("py.typed").is_file()
    tree = ast.parse(stub.read_text())
    names = set()
    for node in tree.body:
        if isinstance(node, (ast.ClassDef, ast.FunctionDef)):
            names.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
        elif isinstance(node, ast.Assign):
            names.update(t.id for t in node.targets if isinstance(t, ast.Name))
    return names


def test_every_name_of_the_extension_has_a_stub():
    public = {n for n in dir(_pgt) if not n.startswith("_")}
    missing = public - stub_names()
    assert not missing, f"names of pgt._pgt without a stub in _pgt.pyi: {sorted(missing)}"


def test_every_public_name_is_exported_and_documented():
    for name in pgt.__all__:
        value = getattr(pgt, name)
        doc = inspect.getdoc(value)
        assert doc and len(doc) > 20, f"pgt.{name} has no docstring"
    classes = {n for n in dir(_pgt) if not n.startswith("_") and isinstance(getattr(_pgt, n), type)}
    assert classes <= set(pgt.__all__), sorted(classes - set(pgt.__all__))
    # help(pgt.render) names every argument, as `pgt render --help` names every flag.
    for function in (pgt.load_scene, pgt.render, pgt.approx, pgt.compare):
        doc = inspect.getdoc(function)
        for argument in inspect.signature(function).parameters:
            assert f"  {argument} " in doc, f"help(pgt.{function.__name__}) does not explain {argument}"
