"""The type stubs and the module agree: every public name of a stub exists,
and the module has no public name the stubs leave out."""
from __future__ import annotations

import ast
import inspect

import numpy as np
import pytest

import rtcd
from conftest import IDENTITY, REPO

STUBS = REPO / "python" / "rtcd"
MODULES = {"__init__": rtcd, "gen": rtcd.gen, "oracle": rtcd.oracle}


def typing_class(node: ast.ClassDef) -> bool:
    """TypedDicts and Protocols describe values; they need not exist at run time."""
    return node.name.startswith("_") or any(
        isinstance(b, ast.Name) and b.id in ("TypedDict", "Protocol") for b in node.bases)


def stub_names(module: str) -> tuple[set[str], set[str]]:
    """(API names, typing-only names) a stub declares at its top level.

    API names: classes, functions, annotated variables and re-exported
    submodules (`from . import gen as gen`). Typing-only: aliases
    (`ArrayLike = npt.ArrayLike`), TypedDicts, Protocols and what the stub
    imports for its annotations; the module may have them or not.
    """
    tree = ast.parse((STUBS / f"{module}.pyi").read_text())
    api, typing_only = set(), set()
    for node in tree.body:
        if isinstance(node, ast.ClassDef) and typing_class(node):
            typing_only.add(node.name)
        elif isinstance(node, (ast.ClassDef, ast.FunctionDef)):
            api.add(node.name)
        elif isinstance(node, ast.AnnAssign):
            api.add(node.target.id)
        elif isinstance(node, ast.Assign):
            typing_only |= {t.id for t in node.targets}
        elif isinstance(node, ast.ImportFrom) and node.level == 1 and module == "__init__":
            api |= {a.asname or a.name for a in node.names}
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            typing_only |= {(a.asname or a.name).split(".")[0] for a in node.names}
    return api, typing_only


def class_members(module: str) -> dict[str, set[str]]:
    """Public methods, properties and attributes of each run-time class of a stub."""
    tree = ast.parse((STUBS / f"{module}.pyi").read_text())
    out = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef) and not typing_class(node):
            names = set()
            for item in node.body:
                if isinstance(item, ast.FunctionDef):
                    names.add(item.name)
                elif isinstance(item, ast.AnnAssign):
                    names.add(item.target.id)
            out[node.name] = {n for n in names if not n.startswith("_")}
    return out


@pytest.mark.parametrize("module", MODULES)
def test_stub_names_exist(module: str):
    api, _ = stub_names(module)
    assert api, "the stub declares something"
    missing = sorted(n for n in api if not hasattr(MODULES[module], n))
    assert not missing, f"in {module}.pyi but not in the module: {missing}"


@pytest.mark.parametrize("module", MODULES)
def test_module_names_are_in_the_stub(module: str):
    api, typing_only = stub_names(module)
    public = {n for n in dir(MODULES[module]) if not n.startswith("_")}
    extra = sorted(public - api - typing_only)
    assert not extra, f"in the module but not in {module}.pyi: {extra}"


def test_version():
    assert isinstance(rtcd.__version__, str)
    assert rtcd.__version__[0].isdigit() and "." in rtcd.__version__


# Rays, Pairs and the errors may have their members only on instances.
INSTANCE_ONLY = {"Rays", "Pairs", "Error", "MeshError", "ConfigError", "UsageError", "BackendError", "SimulationError"}


@pytest.mark.parametrize("module", MODULES)
def test_class_members_exist(module: str):
    missing = []
    for name, members in class_members(module).items():
        if name in INSTANCE_ONLY:
            continue
        cls = getattr(MODULES[module], name)
        missing += [f"{name}.{m}" for m in sorted(members) if not hasattr(cls, m)]
    assert not missing, missing


def test_rays_and_pairs_columns():
    r = rtcd.query(rtcd.gen.box([0.5, 0.5, 0.5]), rtcd.gen.box([0.6, 0.6, 0.6]), IDENTITY, [1, 0, 0, 1, 0, 0, 0],
                   backend="embree")
    members = class_members("__init__")
    for name, value in (("Rays", r.contacts), ("Pairs", r.pairs)):
        columns = members[name] - {"keys"}
        assert set(value.keys()) == columns, name
        for column in columns:
            array = getattr(value, column)
            assert len(array) == len(value), f"{name}.{column}"
            assert getattr(value, column) is array, f"{name}.{column}: built once, then cached"
            np.testing.assert_array_equal(value[column], array)


def test_mesh_error_members():
    with pytest.raises(rtcd.MeshError) as caught:
        rtcd.Mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 5]])
    e = caught.value
    assert e.kind == "index_out_of_range"
    assert e.triangle == 0 and e.vertex == 5


@pytest.mark.parametrize("module", MODULES)
def test_public_callables_have_docstrings(module: str):
    api, _ = stub_names(module)
    undocumented = []
    for name in sorted(api):
        thing = getattr(MODULES[module], name, None)
        if thing is None or inspect.ismodule(thing) or (inspect.isclass(thing) and issubclass(thing, BaseException)):
            continue
        if callable(thing) and not (thing.__doc__ or "").strip():
            undocumented.append(name)
    assert not undocumented, undocumented
