"""The installed package: abi3 extension, type stubs and py.typed, stubs in sync with
the module, docstrings."""

import ast
import inspect
from pathlib import Path

import dvrk_ident as di

PACKAGE = Path(di.__file__).parent


def test_abi3_extension_and_typing_files():
    assert di.__version__.count(".") == 2
    native = [p.name for p in PACKAGE.iterdir() if p.suffix == ".so" or p.suffix == ".pyd"]
    assert native and all(".abi3." in n or n.endswith(".pyd") for n in native), native
    assert (PACKAGE / "py.typed").exists()
    assert (PACKAGE / "__init__.pyi").exists()


def stub_names():
    tree = ast.parse((PACKAGE / "__init__.pyi").read_text())
    top, members = set(), {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            top.add(node.name)
            members[node.name] = {
                n.name for n in node.body if isinstance(n, (ast.FunctionDef, ast.AnnAssign))
                and not isinstance(n, ast.AnnAssign)
            }
        elif isinstance(node, ast.FunctionDef):
            top.add(node.name)
    return top, members


def test_stubs_match_the_module():
    top, members = stub_names()
    public = {n for n in dir(di) if not n.startswith("_") and n != "dvrk_ident"}
    assert public == top
    for cls, names in members.items():
        obj = getattr(di, cls)
        actual = {
            n for n in dir(obj)
            if not n.startswith("_") or n in ("__init__", "__len__", "__add__", "__bytes__")
        }
        if issubclass(obj, BaseException):
            continue
        names = {n for n in names if n != "__init__"}
        missing = names - actual
        assert not missing, f"{cls}: in the stubs, not in the module: {missing}"
        extra = {n for n in actual - names if not n.startswith("__")}
        assert not extra, f"{cls}: in the module, not in the stubs: {extra}"


def test_docstrings():
    for name in ("Robot", "Data", "Result", "BaseParameters", "Prepared", "fit", "read_log",
                 "prepare", "list_topics", "Trajectory", "Excitation", "excite",
                 "evaluate_trajectory"):
        assert inspect.getdoc(getattr(di, name)), name
    for name in ("regressor", "inverse_dynamics", "mass_matrix", "forward_kinematics", "base"):
        assert inspect.getdoc(getattr(di.Robot, name)), name
    assert "Example" in di.fit.__doc__ and "Example" in di.Robot.__doc__
    assert "Example" in di.excite.__doc__ and "Example" in di.Trajectory.__doc__
    assert "predict" in di.Result.__doc__ or di.Result.predict.__doc__
    assert "prepare(data).time" in di.Result.predict.__doc__
