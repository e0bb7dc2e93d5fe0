# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""The typing stub (python/sss/__init__.pyi) against the module: every public
name of the module is in the stub and every name of the stub is in the
module; the same for the public members of its classes; functions and
methods take the same parameters (names, kinds, which have defaults); and
py.typed sits next to the stub (docs/python.md, Typing)."""

import ast
import inspect
import os

import pytest

import sss

STUB = os.path.join(os.path.dirname(sss.__file__), "__init__.pyi")


def stub_tree():
    with open(STUB) as f:
        return ast.parse(f.read(), STUB)


def public(names):
    return {n for n in names if not n.startswith("_")}


def stub_top_level():
    """name -> its node, for the stub's public definitions."""
    out = {}
    for node in stub_tree().body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            out[node.name] = node
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            out[node.target.id] = node
        elif isinstance(node, ast.Assign):
            for target in node.targets:
                if isinstance(target, ast.Name):
                    out[target.id] = node
    return {name: node for name, node in out.items() if not name.startswith("_")}


def stub_members(cls_node):
    """name -> [nodes] of a stub class's public members (overloads repeat)."""
    out = {}
    for node in cls_node.body:
        if isinstance(node, ast.FunctionDef):
            name = node.name
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            name = node.target.id
        else:
            continue
        if not name.startswith("_") or name == "__init__":
            out.setdefault(name, []).append(node)
    return out


def stub_parameters(node):
    """[(name, kind, has_default)] of a stub function, as inspect names them."""
    a = node.args
    params = []
    positional = a.posonlyargs + a.args
    defaults = [None] * (len(positional) - len(a.defaults)) + list(a.defaults)
    for arg, default in zip(positional, defaults):
        kind = "POSITIONAL_ONLY" if arg in a.posonlyargs else "POSITIONAL_OR_KEYWORD"
        params.append((arg.arg, kind, default is not None))
    if a.vararg:
        params.append((a.vararg.arg, "VAR_POSITIONAL", False))
    for arg, default in zip(a.kwonlyargs, a.kw_defaults):
        params.append((arg.arg, "KEYWORD_ONLY", default is not None))
    if a.kwarg:
        params.append((a.kwarg.arg, "VAR_KEYWORD", False))
    return params


def module_parameters(f):
    return [(p.name, p.kind.name, p.default is not inspect.Parameter.empty)
            for p in inspect.signature(f).parameters.values()]


def test_stub_and_marker_are_installed_with_the_package():
    assert os.path.isfile(STUB)
    assert os.path.isfile(os.path.join(os.path.dirname(STUB), "py.typed"))


def test_every_public_name_is_in_the_stub_and_back():
    module_names = public(dir(sss))
    stub_names = set(stub_top_level())
    assert module_names - stub_names == set(), "in the module, missing from the stub"
    assert stub_names - module_names == set(), "in the stub, not in the module"


def test_all_is_the_public_api():
    assert set(sss.__all__) <= set(dir(sss))
    for name in sss.__all__:
        assert hasattr(sss, name), name
    # The two that would hide builtins under `from sss import *` are left out.
    assert public(dir(sss)) - set(sss.__all__) == {"FileNotFoundError", "ValueError"}


def test_functions_take_the_stubs_parameters():
    stub = stub_top_level()
    functions = [n for n, v in vars(sss).items()
                 if n in public(dir(sss)) and inspect.isfunction(v)]
    assert functions, "no functions found"
    for name in functions:
        node = stub[name]
        assert isinstance(node, ast.FunctionDef), f"{name} is not a function in the stub"
        assert module_parameters(getattr(sss, name)) == stub_parameters(node), name


@pytest.mark.parametrize("name", sorted(
    n for n in public(dir(sss)) if inspect.isclass(getattr(sss, n))))
def test_classes_have_the_stubs_members(name):
    cls = getattr(sss, name)
    node = stub_top_level()[name]
    assert isinstance(node, ast.ClassDef), f"{name} is not a class in the stub"
    stub_bases = {ast.unparse(b).split(".")[-1].split("[")[0].lower() for b in node.bases}
    module_bases = {b.__name__.lower() for b in cls.__bases__} - {"object"}
    assert stub_bases == module_bases, name
    members = stub_members(node)
    own = {n for n, v in vars(cls).items()
           if not n.startswith("_") or (n == "__init__" and inspect.isfunction(v))}
    # Data attributes set in __init__ are declared in the stub (annotations).
    declared = {n for n, nodes in members.items()
                if all(isinstance(x, ast.AnnAssign) for x in nodes)}
    assert own - set(members) == set(), f"{name}: missing from the stub"
    assert set(members) - own - declared == set(), f"{name}: not in the module"
    for member, nodes in members.items():
        value = vars(cls).get(member)
        if inspect.isfunction(value):
            if len(nodes) == 1:
                assert module_parameters(value) == stub_parameters(nodes[0]), \
                    f"{name}.{member}"
            else:
                # Overloads (by return_found) may differ in defaults, not in
                # names and kinds.
                names = [p[:2] for p in module_parameters(value)]
                for x in nodes:
                    assert [p[:2] for p in stub_parameters(x)] == names, f"{name}.{member}"
        elif isinstance(value, property):
            assert any(isinstance(d, ast.Name) and d.id == "property"
                       for x in nodes for d in x.decorator_list), f"{name}.{member}"


def test_declared_attributes_exist_on_instances(sphere, tmp_path):
    cloud = sss.read_cloud(sphere)
    for member, nodes in stub_members(stub_top_level()["Cloud"]).items():
        if isinstance(nodes[0], ast.AnnAssign) and member != "report":
            assert hasattr(cloud, member), member
    sss.make_brickmap(sphere, tmp_path / "s.bkm")
    assert isinstance(sss.BrickMap(tmp_path / "s.bkm").path, str)
    assert sss.PointCloudLookup(sphere).path == sphere
    assert sss.PointCloudLookup(cloud).path is None
