"""The installed package: abi3 extension, type stubs and py.typed, stubs in sync with
the module, docstrings."""

import ast
import inspect
from pathlib import Path

import pytest

import dvrk_ident as di

PACKAGE = Path(di.__file__).parent


def test_abi3_extension_and_typing_files():
    assert di.__version__.count(".") == 2
    native = [p.name for p in PACKAGE.iterdir() if p.suffix == ".so" or p.suffix == ".pyd"]
    assert native and all(".abi3." in n or n.endswith(".pyd") for n in native), native
    assert (PACKAGE / "py.typed").exists()
    assert (PACKAGE / "__init__.pyi").exists()


def stub_tree():
    return ast.parse((PACKAGE / "__init__.pyi").read_text())


def typed_dicts(tree):
    """The stub's ``TypedDict`` classes (typing only, not in the module): each one's
    fields ``{name: annotation}`` in order, its bases' first, and whether every field
    may be left out (``total=False``)."""
    found = {}
    for node in tree.body:
        if not isinstance(node, ast.ClassDef):
            continue
        bases = [b.id for b in node.bases if isinstance(b, ast.Name)]
        if not any(b == "TypedDict" or b in found for b in bases):
            continue
        fields = {}
        for b in bases:
            fields.update(found.get(b, ({}, True))[0])
        fields.update({n.target.id: n.annotation for n in node.body
                       if isinstance(n, ast.AnnAssign)})
        total = not any(k.arg == "total" and k.value.value is False for k in node.keywords)
        found[node.name] = (fields, total)
    return found


def unpacked(fn):
    """The ``TypedDict`` a stub's ``**options: Unpack[...]`` names, or None."""
    kwarg = fn.args.kwarg
    annotation = kwarg.annotation if kwarg else None
    if isinstance(annotation, ast.Subscript) and getattr(annotation.value, "id", None) == "Unpack":
        return annotation.slice.id
    return None


def stub_names():
    tree = stub_tree()
    typed = typed_dicts(tree)
    top, members = set(), {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef) and node.name not in typed:
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


def stub_parameters(fn, typed):
    """A stub's parameter names in order, ``*`` before keyword-only ones, a
    ``**options: Unpack[...]`` written out as its ``TypedDict``'s fields (``typed``)."""
    a = fn.args
    names = [p.arg for p in a.posonlyargs + a.args]
    if a.vararg:
        names.append("*" + a.vararg.arg)
    elif a.kwonlyargs:
        names.append("*")
    names += [p.arg for p in a.kwonlyargs]
    if unpacked(fn):
        names += [n for n in typed[unpacked(fn)][0] if n not in names]
    elif a.kwarg:
        names.append("**" + a.kwarg.arg)
    return [n for n in names if n not in ("self", "cls")]


def module_parameters(obj):
    """The same list from the compiled signature (pyo3's ``__text_signature__``), a
    function's ``**options`` (the fit options, ``dvrk_ident._options``, or the
    excitation options, ``dvrk_ident._excite_options``) written out."""
    names, star = [], False
    for p in inspect.signature(obj).parameters.values():
        if p.kind == p.VAR_KEYWORD and p.name == "options":
            table = di._options if obj.__name__ in di._options else di._excite_options
            names += [n for n in table[obj.__name__] if n not in names]
            continue
        if p.kind == p.VAR_POSITIONAL:
            names.append("*" + p.name)
            star = True
        elif p.kind == p.KEYWORD_ONLY:
            if not star:
                names.append("*")
                star = True
            names.append(p.name)
        elif p.kind == p.VAR_KEYWORD:
            names.append("**" + p.name)
        else:
            names.append(p.name)
    return [n for n in names if n not in ("self", "cls", "$self", "$cls")]


def test_stub_signatures_match_the_module():
    """Every function and method takes the stub's parameters, in its order, positional and
    keyword-only alike, so an editor's completion is the module's truth (properties and
    operators aside)."""
    checked = 0
    tree = stub_tree()
    typed = typed_dicts(tree)
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            pairs = [(node.name, node, getattr(di, node.name))]
        elif (isinstance(node, ast.ClassDef) and node.name not in typed
              and not issubclass(getattr(di, node.name), BaseException)):
            cls = getattr(di, node.name)
            pairs = [
                (f"{node.name}.{n.name}", n, cls if n.name == "__init__" else getattr(cls, n.name))
                for n in node.body
                if isinstance(n, ast.FunctionDef)
                and not any(getattr(d, "id", None) == "property" for d in n.decorator_list)
                and not (n.name.startswith("__") and n.name != "__init__")
            ]
        else:
            continue
        for name, stub, obj in pairs:
            assert module_parameters(obj) == stub_parameters(stub, typed), name
            checked += 1
    assert checked > 60, checked


def test_stub_lists_every_option(psm, psm_excitation):
    """The fit options a function takes as keywords (``**options``, converted in one
    place from the library's list of options) are in the stub, as the fields of the
    ``TypedDict`` its ``**options: Unpack[...]`` names, in the library's order, each
    optional (``total=False``) and accepting None: an option the stub misses (a new
    one) fails here."""
    e = psm_excitation
    log = di.JointLog(e["t"], e["q"], e["noisy"])
    tree = stub_tree()
    stubs = {n.name: n for n in tree.body if isinstance(n, ast.FunctionDef)}
    typed = typed_dicts(tree)
    assert set(di._options) == {"fit", "observe", "prepare", "external_torque"}
    assert "filter_order" in di._options["prepare"] and "method" in di._options["fit"]
    for function, names in di._options.items():
        positional = [a.arg for a in stubs[function].args.args]
        fields, total = typed[unpacked(stubs[function])]
        assert list(fields) == [n for n in names if n not in positional], function
        assert not total, function
        for n, annotation in fields.items():
            assert ast.unparse(annotation).startswith("Optional["), (function, n)
    with pytest.raises(TypeError, match="unexpected keyword argument 'stribeck'"):
        di.prepare(psm, log, stribeck=0.3)
    # The option added through the list (tests/python/test_fit.py compares it with
    # --filter-order): refused without a filter, named as the keyword.
    with pytest.raises(di.InputError, match="filter_order: the order is the motion's low-pass"):
        di.fit(psm, log, method="ols", cutoff="none", filter_order=4)


def test_docstrings():
    for name in ("Model", "JointLog", "FitResult", "BaseParameters", "Prepared", "fit",
                 "read_log", "prepare", "list_topics", "FourierTrajectory", "Excitation", "excite",
                 "evaluate_trajectory"):
        assert inspect.getdoc(getattr(di, name)), name
    for name in ("regressor", "inverse_dynamics", "mass_matrix", "forward_kinematics", "base"):
        assert inspect.getdoc(getattr(di.Model, name)), name
    assert "Example" in di.fit.__doc__ and "Example" in di.Model.__doc__
    assert "Example" in di.excite.__doc__ and "Example" in di.FourierTrajectory.__doc__
    assert "predict" in di.FitResult.__doc__ or di.FitResult.predict.__doc__
    assert "prepare(data).time" in di.FitResult.predict.__doc__


@pytest.mark.parametrize("old,new", [("Robot", "Model"), ("Data", "JointLog"),
                                     ("Result", "FitResult"), ("Trajectory", "FourierTrajectory")])
def test_old_class_names_warn_and_are_the_new_classes(old, new):
    """The names of the development builds before 0.1.0 stay until 0.2.0, each with a DeprecationWarning
    that names its replacement; the stubs declare them as aliases."""
    with pytest.warns(DeprecationWarning, match=f"dvrk_ident.{old} is deprecated.*dvrk_ident.{new}"):
        cls = getattr(di, old)
    assert cls is getattr(di, new)
    assert f"{old} = {new}" in (PACKAGE / "__init__.pyi").read_text()
    assert old not in dir(di)
    with pytest.raises(AttributeError, match="has no attribute 'Robots'"):
        di.Robots


def test_wpi2019_names_warns(tmp_path):
    path = tmp_path / "coefficients.json"
    path.write_text('{"trajectories": {"b": {"dof": 1, "order": 1, "base_freq_hz": 0.18, '
                    '"coefficients": [0.1, 0.0, 0.0]}, "a": {"dof": 1, "order": 1, '
                    '"base_freq_hz": 0.18, "coefficients": [0.1, 0.0, 0.0]}}}')
    with pytest.warns(DeprecationWarning, match="FourierTrajectory.wpi_names"):
        old = di.FourierTrajectory.wpi2019_names(path)
    assert old == di.FourierTrajectory.wpi_names(path) == ["a", "b"]
