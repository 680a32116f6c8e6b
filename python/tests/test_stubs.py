"""The stubs (python/rotavg/__init__.pyi) declare what the compiled module exports: every name,
every function's parameters with their defaults, every class's attributes; and every call of
typecheck_usage.py (which .ci/run type-checks with mypy --strict) runs.

.ci/run also runs `python -m mypy.stubtest rotavg`, which checks the same and more (types of
defaults, positional / keyword kinds); this test needs nothing but the package."""

import ast
import inspect

import rotavg
import typecheck_usage
from conftest import REPO

STUB = ast.parse((REPO / "python" / "rotavg" / "__init__.pyi").read_text())


def stub_functions():
    """name -> list of (parameter name, default as source or None) per overload."""
    out = {}
    for node in STUB.body:
        if isinstance(node, ast.FunctionDef):
            a = node.args
            params = a.args + a.kwonlyargs
            defaults = [None] * (len(a.args) - len(a.defaults)) + list(a.defaults)
            defaults += list(a.kw_defaults)
            out.setdefault(node.name, []).append(
                [(p.arg, None if d is None else ast.unparse(d)) for p, d in zip(params, defaults)]
            )
    return out


def stub_classes():
    """class name -> names declared in its body."""
    out = {}
    for node in STUB.body:
        if isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
            names = set()
            for item in node.body:
                if isinstance(item, ast.FunctionDef):
                    names.add(item.name)
                elif isinstance(item, ast.AnnAssign) and isinstance(item.target, ast.Name):
                    names.add(item.target.id)
            out[node.name] = names
    return out


def test_every_exported_name_is_declared():
    declared = set(stub_functions()) | set(stub_classes()) | {"__version__"}
    assert set(rotavg.__all__) == declared
    stub_all = next(
        n.value for n in STUB.body
        if isinstance(n, ast.Assign) and getattr(n.targets[0], "id", "") == "__all__"
    )
    assert sorted(ast.literal_eval(stub_all)) == sorted(rotavg.__all__)


def test_function_parameters_and_defaults_match():
    for name, overloads in stub_functions().items():
        runtime = inspect.signature(getattr(rotavg, name)).parameters
        declared = {p for overload in overloads for p, _ in overload}
        assert declared == set(runtime), name
        for overload in overloads:
            for p, default in overload:
                if default is None or default == "None" and runtime[p].default is None:
                    continue
                assert ast.literal_eval(default) == runtime[p].default, (name, p)


def test_class_attributes_match():
    for name, declared in stub_classes().items():
        cls = getattr(rotavg, name)
        if issubclass(cls, Exception):
            continue  # their attributes are set on each instance (test_errors.py)
        runtime = {a for a in vars(cls) if not a.startswith("_")}
        public = {a for a in declared if not a.startswith("_")}
        assert public == runtime, name


def test_typed_usage_runs():
    typecheck_usage.main()
