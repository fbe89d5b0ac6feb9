"""The package's layout rules (issue 11): the library never imports the CLI, plotting
(matplotlib) lives only in gagekit/report/, and the CLI registers its sub-apps explicitly."""

from __future__ import annotations

import ast
from pathlib import Path

import gagekit

PKG = Path(gagekit.__file__).parent


def _imports(path: Path) -> list[str]:
    """Absolute names of every module ``path`` imports (relative imports resolved)."""
    mod = path.relative_to(PKG.parent).with_suffix("").parts
    pkg = mod[:-1] if mod[-1] != "__init__" else mod[:-1]
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            out += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = list(pkg[: len(pkg) - node.level + 1]) if node.level else []
            name = ".".join(base + ([node.module] if node.module else []))
            out.append(name)
            out += [f"{name}.{a.name}" for a in node.names]
    return out


def _library_files():
    return [p for p in PKG.rglob("*.py") if "cli" not in p.relative_to(PKG).parts[:1] and p.name != "__main__.py"]


def test_library_never_imports_the_cli():
    bad = {str(p.relative_to(PKG)): n for p in _library_files() for n in _imports(p) if n.startswith("gagekit.cli")}
    assert not bad


def test_plotting_only_in_report():
    bad = [str(p.relative_to(PKG)) for p in PKG.rglob("*.py")
           if p.relative_to(PKG).parts[0] != "report" and any(n.split(".")[0] == "matplotlib" for n in _imports(p))]
    assert not bad


def test_cli_registers_its_sub_apps_in_one_place():
    # no CLI module imports another at its end for the side effect of registering commands:
    # every module-level import comes before the first definition
    for p in (PKG / "cli").glob("*.py"):
        body = ast.parse(p.read_text(encoding="utf-8")).body
        first_def = next((k for k, n in enumerate(body) if isinstance(n, (ast.FunctionDef, ast.ClassDef, ast.Assign))), len(body))
        late = [n.lineno for n in body[first_def:] if isinstance(n, (ast.Import, ast.ImportFrom))]
        assert not late, f"{p.name}: import at line {late}"
    from gagekit.cli import app
    from gagekit.cli.machine import app as machine_app

    names = {g.name for g in app.registered_groups} | {c.name for c in app.registered_commands}
    assert {"cloud", "form", "gage", "machine", "demo"} <= names
    assert {"design", "evaluate-plan", "track", "history", "simulate-cycles"} <= {c.name for c in machine_app.registered_commands}


def test_the_files_run_first_exist():
    # tests/conftest.py starts the longest files first; a renamed file would silently drop out.
    # Read from its source: under xdist, `import conftest` may find tests/qif/conftest.py.
    root = Path(__file__).resolve().parents[1]
    tree = ast.parse((root / "tests" / "conftest.py").read_text())
    (listed,) = [ast.literal_eval(node.value) for node in tree.body if isinstance(node, ast.Assign)
                 and any(isinstance(t, ast.Name) and t.id == "SLOW_FILES_FIRST" for t in node.targets)]
    assert listed and [f for f in listed if not (root / f).is_file()] == []
