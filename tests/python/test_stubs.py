"""The type stubs (python/nimble_rig/_rig.pyi) against the compiled module: every function and class
of the module is in them, nothing else is, and each function has the module's parameter names in
its order (pybind11 writes the signature as the first line of each docstring)."""
import ast
import inspect
import pathlib
import re

import nimble_rig
from nimble_rig import _rig


def stub_tree():
    path = pathlib.Path(nimble_rig.__file__).with_name("_rig.pyi")
    return ast.parse(path.read_text())


def module_parameters(function):
    """Parameter names from pybind11's signature line: 'name(a: T, b: T = ..., *, c: T) -> R'."""
    first = function.__doc__.splitlines()[0]
    inside = re.match(r"\w+\((.*)\) ->", first).group(1)
    names, depth, part = [], 0, ""
    for ch in inside + ",":
        if ch in "([{":
            depth += 1
        elif ch in ")]}":
            depth -= 1
        if ch == "," and depth == 0:
            name = part.strip().split(":")[0].strip()
            if name and name != "*":
                names.append(name)
            part = ""
        else:
            part += ch
    return names


def test_every_function_and_class_of_the_module_is_in_the_stubs_with_its_parameters():
    tree = stub_tree()
    stub_functions = {n.name: n for n in tree.body if isinstance(n, ast.FunctionDef)}
    stub_classes = {n.name for n in tree.body if isinstance(n, ast.ClassDef)}
    public = {name: obj for name, obj in vars(_rig).items() if not name.startswith("_")}
    functions = {name for name, obj in public.items() if callable(obj) and not inspect.isclass(obj)}
    classes = {name for name, obj in public.items() if inspect.isclass(obj)}
    assert functions == set(stub_functions)
    assert classes == stub_classes
    for name in functions:
        args = stub_functions[name].args
        stub = [a.arg for a in args.posonlyargs + args.args + args.kwonlyargs]
        assert stub == module_parameters(public[name]), name
        assert len(public[name].__doc__.splitlines()) > 1, name + " has no docstring"
