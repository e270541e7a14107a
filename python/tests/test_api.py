"""The type stub (regbench.pyi) and the module agree, and every public name is documented."""
import ast
import inspect
import pathlib

import regbench

STUB = pathlib.Path(__file__).resolve().parents[1] / "regbench.pyi"


def stub_api():
    """{public name: set of public member names (classes) or None (functions, constants)}."""
    api, classes = {}, {}
    for node in ast.parse(STUB.read_text()).body:
        if isinstance(node, ast.ClassDef):
            # A class's members are its own and those of its stub base classes (_DataTagged).
            members = {n.name for n in node.body if isinstance(n, ast.FunctionDef)
                       and (not n.name.startswith("_") or n.name in ("__len__", "__getitem__",
                                                                      "__iter__"))}
            for base in node.bases:
                if isinstance(base, ast.Name) and base.id in classes:
                    members |= classes[base.id]
            classes[node.name] = members
            if not node.name.startswith("_"):
                api[node.name] = members
        elif isinstance(node, ast.FunctionDef) and not node.name.startswith("_"):
            api[node.name] = None
        elif isinstance(node, ast.AnnAssign) and (node.target.id == "__version__"
                                                  or not node.target.id.startswith("_")):
            api[node.target.id] = None
    return api


def test_stub_matches_module():
    api = stub_api()
    public = {n for n in dir(regbench) if not n.startswith("_")} | {"__version__"}
    assert set(api) == public
    for name, members in api.items():
        if members is None:
            continue
        cls = getattr(regbench, name)
        actual = {n for n in dir(cls) if not n.startswith("_")}
        actual |= {n for n in ("__len__", "__getitem__", "__iter__") if n in vars(cls)}
        assert members == actual, name


def test_everything_public_has_a_docstring():
    assert regbench.__doc__
    for name in ("methods", "align", "metrics", "run", "read_results", "PairFile", "Pair",
                 "AlignResult"):
        assert inspect.getdoc(getattr(regbench, name)), name
    assert "fn(source, target, **params)" in regbench.run.__doc__
