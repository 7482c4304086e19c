"""The package's shape: the module-level import graph of ``hugger`` has no cycle, and the core
modules import each other only at module level (no function-level imports among them).

Every module of python/hugger is parsed with ``ast`` (nothing is imported), so the test sees the
source as shipped. Imports under ``if TYPE_CHECKING:`` do not run and are left out; imports of
extras (matplotlib, mujoco, trimesh, ...) inside functions are the lazy loading the package wants.
"""
from __future__ import annotations

import ast
from pathlib import Path

import hugger

PACKAGE = Path(hugger.__file__).resolve().parent
#: The core of the package: the planner, its inputs and its result.
CORE = {"hugger.planner", "hugger.trajectory", "hugger.hand", "hugger.world", "hugger.batch", "hugger._types"}


def _modules() -> dict[str, Path]:
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


MODULES = _modules()


def _is_package(name: str) -> bool:
    return MODULES[name].name == "__init__.py"


def _resolve(module: str, node: ast.ImportFrom | ast.Import) -> list[str]:
    """The hugger modules an import statement in ``module`` loads (its own submodules and the
    modules its names come from); the implicit import of parent packages is left out."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names if a.name.split(".")[0] == "hugger" and a.name in MODULES]
    if node.level:
        base = module.split(".")
        if not _is_package(module):
            base = base[:-1]
        base = base[: len(base) - (node.level - 1)]
        origin = ".".join(base + ([node.module] if node.module else []))
    else:
        origin = node.module or ""
    if origin.split(".")[0] != "hugger":
        return []
    found = []
    for alias in node.names:
        sub = f"{origin}.{alias.name}"
        if sub in MODULES:  # `from . import hands`: the submodule itself
            found.append(sub)
        elif origin in MODULES and not (module + ".").startswith(origin + "."):
            found.append(origin)  # `from .hand import Hand`; a package's own ancestors load first anyway
            # (and `from . import _core`, the compiled module, has no source: left out)
    return sorted(set(found))


def _type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def _imports(module: str) -> tuple[list[tuple[str, int]], list[tuple[str, int]]]:
    """(module-level, function-level) hugger imports of ``module``, each as (target, line)."""
    tree = ast.parse(MODULES[module].read_text(encoding="utf-8"), filename=str(MODULES[module]))
    top: list[tuple[str, int]] = []
    inner: list[tuple[str, int]] = []

    def visit(node: ast.AST, in_function: bool) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and _type_checking(child):
                for sub in child.orelse:
                    visit(ast.Module(body=[sub], type_ignores=[]), in_function)
                continue
            if isinstance(child, (ast.Import, ast.ImportFrom)):
                (inner if in_function else top).extend((t, child.lineno) for t in _resolve(module, child))
            visit(child, in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)))

    visit(tree, False)
    return top, inner


def test_the_parser_sees_the_package():
    assert CORE <= set(MODULES), sorted(CORE - set(MODULES))
    top, _ = _imports("hugger.planner")
    assert {"hugger.hand", "hugger.trajectory", "hugger.world", "hugger._types"} <= {t for t, _ in top}
    top, _ = _imports("hugger")
    assert "hugger.skins" in {t for t, _ in top} and "hugger.batch" in {t for t, _ in top}


def test_module_level_imports_have_no_cycle():
    graph = {m: sorted({t for t, _ in _imports(m)[0]}) for m in MODULES}
    state: dict[str, int] = {}  # 1: on the current path, 2: finished
    path: list[str] = []

    def visit(m: str) -> list[str] | None:
        state[m] = 1
        path.append(m)
        for t in graph[m]:
            if state.get(t) == 1:
                return path[path.index(t):] + [t]
            if t not in state:
                cycle = visit(t)
                if cycle:
                    return cycle
        path.pop()
        state[m] = 2
        return None

    for m in graph:
        if m not in state:
            cycle = visit(m)
            assert cycle is None, "import cycle: " + " -> ".join(cycle)


def test_core_modules_import_each_other_at_module_level_only():
    late = [f"{MODULES[m].relative_to(PACKAGE.parent)}:{line} imports {t} inside a function"
            for m in sorted(CORE) for t, line in _imports(m)[1] if t in CORE]
    assert not late, late


def test_tip_states_keep_their_values():
    assert (int(hugger.FROZEN), int(hugger.CONTACT), int(hugger.DONE)) == (0, 1, 2)
    assert hugger.TipState(2) is hugger.DONE and hugger.FROZEN == 0
    assert hugger.planner.CONTACT is hugger.CONTACT and hugger.Configuration is hugger.planner.Configuration


def test_core_stub_matches_the_compiled_module():
    """python/hugger/_core.pyi names every class, method and property of ``hugger._core``, and nothing else."""
    from hugger import _core

    assert (PACKAGE / "py.typed").is_file()
    tree = ast.parse((PACKAGE / "_core.pyi").read_text(encoding="utf-8"))
    stub = {c.name: {f.name for f in c.body if isinstance(f, ast.FunctionDef)}
            for c in tree.body if isinstance(c, ast.ClassDef)}
    compiled = {name for name in dir(_core) if isinstance(getattr(_core, name), type)}
    assert set(stub) == compiled
    functions = {f.name for f in tree.body if isinstance(f, ast.FunctionDef)}
    constants = {a.target.id for a in tree.body
                 if isinstance(a, ast.AnnAssign) and isinstance(a.target, ast.Name) and not a.target.id.startswith("_")}
    assert functions | constants == {n for n in dir(_core) if not n.startswith("_") and n not in compiled}
    # the engine's limits, and the names of its rule sets and skins
    assert all(isinstance(getattr(_core, n), (int, float)) or
               (isinstance(getattr(_core, n), tuple) and all(isinstance(x, str) for x in getattr(_core, n)))
               for n in constants)
    for name, members in stub.items():
        cls = getattr(_core, name)
        own = {m for m in vars(cls) if not m.startswith("_") or m in ("__init__", "__repr__")}
        assert members == own, (name, sorted(members ^ own))


def test_mypy_strict_is_clean():
    """The package type-checks under mypy --strict with its stubs (_core.pyi, py.typed), and no
    code is unreachable to it (code after a check mypy thinks always fails is never checked)."""
    import pytest

    api = pytest.importorskip("mypy.api", reason="mypy is in the test extra")
    root = Path(__file__).resolve().parents[1]
    out, err, status = api.run(["--strict", "--warn-unreachable", "--no-incremental", "--config-file", str(root / "pyproject.toml"),
                                str(root / "python" / "hugger")])
    assert status == 0, out + err


def test_the_installed_version_is_the_package_s():
    """pyproject.toml reads the version from hugger._types.VERSION: one owner."""
    import importlib.metadata

    assert importlib.metadata.version("hugger") == hugger.__version__ == hugger._types.VERSION


def test_dir_lists_the_lazy_submodules_without_loading_them():
    import subprocess
    import sys

    # A fresh interpreter: other tests may have loaded the submodules already.
    code = ("import sys, hugger; names = dir(hugger); "
            "print(all(n in names for n in ('viz', 'physics', 'dataset', 'Dataset', 'Planner')), "
            "'annotations' in names, 'hugger.viz' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["True", "False", "False"]
