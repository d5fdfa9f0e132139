"""The package surface: exports, version, exception tree, and the stubs of the native module."""

from __future__ import annotations

import ast
import importlib.metadata
from pathlib import Path

import coherent
from coherent import _coherent

STUB = Path(coherent.__file__).with_name("_coherent.pyi")


def _stub_names() -> set[str]:
    """Public names the stub defines at top level."""
    names: set[str] = set()
    for node in ast.parse(STUB.read_text()).body:
        if isinstance(node, (ast.ClassDef, ast.FunctionDef)):
            names.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
        elif isinstance(node, ast.Assign):
            names.update(t.id for t in node.targets if isinstance(t, ast.Name))
    return {n for n in names if not n.startswith("_") or n == "__version__"}


def _module_names() -> set[str]:
    return {n for n in dir(_coherent) if not n.startswith("_")} | {"__version__"}


def test_stub_matches_the_module() -> None:
    assert STUB.is_file()
    stub, module = _stub_names(), _module_names()
    assert stub - module == set(), "in the stub but not in the module"
    assert module - stub == set(), "in the module but not in the stub"


def test_stub_members_match_the_classes() -> None:
    tree = ast.parse(STUB.read_text())
    for node in tree.body:
        if isinstance(node, ast.ClassDef) and not node.name.startswith("_") and not node.name.endswith("Error"):
            stub_members = {
                item.name
                for item in node.body
                if isinstance(item, ast.FunctionDef) and (not item.name.startswith("_") or item.name == "__init__")
            }
            cls = getattr(_coherent, node.name)
            public = {n for n in dir(cls) if not n.startswith("_")}
            assert stub_members - {"__init__"} == public, node.name


def test_py_typed_is_installed() -> None:
    assert Path(coherent.__file__).with_name("py.typed").is_file()


def test_all_is_the_public_api() -> None:
    assert sorted(coherent.__all__) == sorted(_module_names())
    for name in coherent.__all__:
        assert getattr(coherent, name) is getattr(_coherent, name)


def test_version() -> None:
    assert coherent.__version__ == importlib.metadata.version("coherent")


def test_exception_tree() -> None:
    assert issubclass(coherent.CoherentError, Exception)
    for exc in (coherent.TaskFormatError, coherent.UnknownRobotError, coherent.ActionParseError):
        assert issubclass(exc, coherent.CoherentError)
        assert exc.__module__ == "coherent._coherent"
    assert issubclass(coherent.TaskFormatError, ValueError)
    assert issubclass(coherent.ActionParseError, ValueError)
    assert not issubclass(coherent.UnknownRobotError, ValueError)


def test_classes_live_in_the_native_module() -> None:
    assert coherent.Task.__module__ == "coherent._coherent"
    assert coherent.Env.__module__ == "coherent._coherent"
