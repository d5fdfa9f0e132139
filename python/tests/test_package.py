"""The package surface: exports, version, exception tree, and the stubs of the native
module checked against the module itself (names, members, signatures), so that they
cannot drift apart."""

from __future__ import annotations

import ast
import importlib.metadata
import inspect
import re
import types
from pathlib import Path
from typing import Any

import pytest

import coherent
from coherent import _coherent
from conftest import REPO

STUB = Path(coherent.__file__).with_name("_coherent.pyi")
TREE = ast.parse(STUB.read_text())
# Native functions that the package wraps rather than re-exports (`coherent.bench`,
# `coherent.results`, `coherent.report` return DataFrames built from them;
# `coherent.benchmark.tasks` is the project's benchmark).
# `coherent.view` wraps the pages of `coherent view`.
WRAPPED = {
    "run_bench", "read_results", "report_tables", "report_text", "price_lines", "benchmark_tasks", "view_page",
    "results_page", "framed_page", "export_sft",
}  # fmt: skip


def _public(name: str) -> bool:
    return not name.startswith("_") or name == "__version__"


def _stub_names() -> set[str]:
    """Public names the stub defines at top level."""
    names: set[str] = set()
    for node in TREE.body:
        if isinstance(node, (ast.ClassDef, ast.FunctionDef)):
            names.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
        elif isinstance(node, ast.Assign):
            names.update(t.id for t in node.targets if isinstance(t, ast.Name))
    return {n for n in names if _public(n)}


def _module_names() -> set[str]:
    return {n for n in dir(_coherent) if not n.startswith("_")} | {"__version__"}


def _stub_classes() -> dict[str, ast.ClassDef]:
    return {n.name: n for n in TREE.body if isinstance(n, ast.ClassDef) and _public(n.name)}


def _stub_functions() -> dict[str, ast.FunctionDef]:
    return {n.name: n for n in TREE.body if isinstance(n, ast.FunctionDef)}


def _parameters(node: ast.FunctionDef) -> list[tuple[str, str, Any]]:
    """(name, kind, default) of a stub function's parameters; `self` left out."""
    a = node.args
    positional = [*a.posonlyargs, *a.args]
    defaults: list[Any] = [inspect.Parameter.empty] * (len(positional) - len(a.defaults)) + [
        ast.literal_eval(d) for d in a.defaults
    ]
    params = [(p.arg, "positional", d) for p, d in zip(positional, defaults)]
    params += [
        (p.arg, "keyword", inspect.Parameter.empty if d is None else ast.literal_eval(d))
        for p, d in zip(a.kwonlyargs, a.kw_defaults)
    ]
    return [p for p in params if p[0] != "self"]


def _native_parameters(obj: Any) -> list[tuple[str, str, Any]]:
    kinds = {
        inspect.Parameter.POSITIONAL_ONLY: "positional",
        inspect.Parameter.POSITIONAL_OR_KEYWORD: "positional",
        inspect.Parameter.KEYWORD_ONLY: "keyword",
    }
    params = inspect.signature(obj).parameters.values()
    return [(p.name, kinds[p.kind], p.default) for p in params if p.name not in ("self", "$self")]


def _same_signature(stub: list[tuple[str, str, Any]], native: list[tuple[str, str, Any]], what: str) -> None:
    assert [(n, k) for n, k, _ in stub] == [(n, k) for n, k, _ in native], what
    for (name, _, want), (_, _, have) in zip(stub, native):
        # A default that is not a literal shows as `...` in the native signature.
        if have is not Ellipsis:
            assert want == have, f"{what}: default of {name}"


def test_stub_matches_the_module() -> None:
    assert STUB.is_file()
    stub, module = _stub_names(), _module_names()
    assert stub - module == set(), "in the stub but not in the module"
    assert module - stub == set(), "in the module but not in the stub"


def test_stub_members_match_the_classes() -> None:
    for name, node in _stub_classes().items():
        cls = getattr(_coherent, name)
        members = {item.name: item for item in node.body if isinstance(item, ast.FunctionDef)}
        if name.endswith("Error"):
            assert members == {}, name
            continue
        public = {n for n in dir(cls) if not n.startswith("_")}
        assert set(members) - {"__init__"} == public, name
        for member, item in members.items():
            is_property = any(isinstance(d, ast.Name) and d.id == "property" for d in item.decorator_list)
            if member == "__init__":
                _same_signature(_parameters(item), _native_parameters(cls), f"{name}()")
                continue
            native = inspect.getattr_static(cls, member)
            if is_property:
                assert isinstance(native, types.GetSetDescriptorType), f"{name}.{member} is not a property"
            else:
                assert callable(native), f"{name}.{member} is not a method"
                _same_signature(_parameters(item), _native_parameters(getattr(cls, member)), f"{name}.{member}")


def test_stub_signatures_match_the_functions() -> None:
    functions = _stub_functions()
    native = {n for n in _module_names() if inspect.isbuiltin(getattr(_coherent, n))}
    assert set(functions) == native
    for name, node in functions.items():
        _same_signature(_parameters(node), _native_parameters(getattr(_coherent, name)), name)


def test_stub_exceptions_match_the_tree() -> None:
    for name, node in _stub_classes().items():
        if name.endswith("Error"):
            bases = [b.id for b in node.bases if isinstance(b, ast.Name)]
            native_bases = [b.__name__ for b in getattr(_coherent, name).__bases__]
            assert bases == native_bases, name


def test_py_typed_is_installed() -> None:
    assert Path(coherent.__file__).with_name("py.typed").is_file()


# The names `coherent` defines in Python (the rest of `__all__` is the native module's).
PYTHON_API = {"Page", "RayExecutor", "Report", "bench", "report", "results", "view"}
SUBMODULES = {"analysis", "benchmark", "executors", "gym", "marl", "plot", "training"}
DOCS = REPO / "docs" / "python.md"


def test_all_is_the_stub_less_what_is_wrapped_plus_the_python_api() -> None:
    assert set(coherent.__all__) == (_stub_names() - WRAPPED) | PYTHON_API
    assert len(coherent.__all__) == len(set(coherent.__all__)), "a name twice in __all__"
    for name in _stub_names() - WRAPPED:
        assert getattr(coherent, name) is getattr(_coherent, name)
    for name in PYTHON_API - {"Page", "RayExecutor", "view"}:
        assert getattr(coherent, name) is getattr(coherent.analysis, name)
    assert coherent.view is coherent._view.view and coherent.Page is coherent._view.Page
    assert coherent.RayExecutor is coherent.executors.RayExecutor


def test_the_namespace_holds_the_api_and_the_submodules_and_nothing_else() -> None:
    for name in SUBMODULES:
        importlib.import_module(f"coherent.{name}")
    assert dir(coherent) == sorted([*coherent.__all__, *SUBMODULES])
    # The module's own dict, not only what `dir` shows: no helper of the package's own
    # (`importlib`, `Any`, the `annotations` of a __future__ import) under a public name.
    public = {n for n in vars(coherent) if not n.startswith("_")}
    assert public == (set(coherent.__all__) | SUBMODULES) - {"__version__"}


def _documented_names() -> set[str]:
    """The names in the first column of docs/python.md's table "The package's names"."""
    section = DOCS.read_text().split("## The package's names", 1)[1].split("\n## ", 1)[0]
    rows = [line for line in section.splitlines() if line.startswith("| `")]
    return {name for row in rows for name in re.findall(r"`([A-Za-z_][A-Za-z_0-9]*)`", row.split(" | ")[0])}


def test_the_docs_table_of_names_is_all_and_the_submodules() -> None:
    documented = _documented_names()
    assert documented - set(coherent.__all__) - SUBMODULES == set(), "in docs/python.md but not in the package"
    assert (set(coherent.__all__) | SUBMODULES) - documented == set(), "in the package but not in docs/python.md"


def test_submodules_load_on_first_use() -> None:
    import coherent.gym
    import coherent.plot

    assert coherent.plot.__name__ == "coherent.plot"
    assert coherent.gym.__name__ == "coherent.gym"
    with pytest.raises(AttributeError, match="no_such_thing"):
        _ = coherent.no_such_thing  # type: ignore[attr-defined]


def test_version_is_the_installed_distributions() -> None:
    assert coherent.__version__ == importlib.metadata.version("coherent-robots")


def test_methods_are_the_cli_methods() -> None:
    assert coherent.METHODS == [
        "pefa",
        "pefa-no-history",
        "cmrs",
        "dmrs-1d",
        "dmrs-2d",
        "mcts",
        "llm-mcts",
        "optimal",
        "random",
        "llm-pddl",
    ]


def test_exception_tree() -> None:
    assert issubclass(coherent.CoherentError, Exception)
    errors = (
        coherent.TaskFormatError,
        coherent.UnknownRobotError,
        coherent.ActionParseError,
        coherent.PhysicsError,
        coherent.BackendError,
        coherent.ReplayMismatchError,
        coherent.PromptError,
        coherent.MethodError,
        coherent.RobotError,
        coherent.DataFileError,
    )
    for exc in errors:
        assert issubclass(exc, coherent.CoherentError)
        assert exc.__module__ == "coherent._coherent"
    assert issubclass(coherent.TaskFormatError, ValueError)
    assert issubclass(coherent.ActionParseError, ValueError)
    assert issubclass(coherent.PromptError, ValueError)
    assert issubclass(coherent.DataFileError, ValueError)
    assert not issubclass(coherent.UnknownRobotError, ValueError)
    assert not issubclass(coherent.RobotError, ValueError)


def test_classes_live_in_the_native_module() -> None:
    for cls in (
        coherent.Task,
        coherent.Env,
        coherent.LLM,
        coherent.Episode,
        coherent.View,
        coherent.Decision,
        coherent.Reply,
    ):
        assert cls.__module__ == "coherent._coherent"


def test_wheel_is_abi3() -> None:
    # One wheel for every CPython from 3.11: the extension is built for the stable ABI.
    assert Path(_coherent.__file__).name in ("_coherent.abi3.so", "_coherent.pyd")
