"""The type stubs of ``gagekit._core`` are generated from the bindings' Rust signatures and doc
comments (``cargo run -p gagekit-py --features stubs --bin stub_gen``; issue 23 item 4), one
``.pyi`` per domain submodule under ``python/gagekit/_core/``. These tests keep the checked-in
stubs current and complete."""

from __future__ import annotations

import ast
import filecmp
import importlib
import os
import shutil
import subprocess
from pathlib import Path

import pytest

import gagekit

REPO = Path(__file__).resolve().parents[1]
STUBS = REPO / "python" / "gagekit" / "_core"
DOMAINS = ("cloud", "design", "form", "gage", "gdt", "geometry", "kinematics", "mesh", "nc")


def _declared(stub: Path) -> set[str]:
    tree = ast.parse(stub.read_text())
    names: set[str] = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.Assign):
            names.update(t.id for t in node.targets if isinstance(t, ast.Name) and t.id != "__all__")
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
    return names


def test_the_extension_has_one_submodule_per_domain():
    from gagekit import _core

    assert {n for n in dir(_core) if not n.startswith("_")} == set(DOMAINS)
    for name in DOMAINS:
        # importable by its dotted name, and named by it
        assert importlib.import_module(f"gagekit._core.{name}").__name__ == f"gagekit._core.{name}"


@pytest.mark.parametrize("domain", DOMAINS)
def test_each_submodule_stub_declares_exactly_its_bindings(domain):
    mod = importlib.import_module(f"gagekit._core.{domain}")
    public = {n for n in dir(mod) if not n.startswith("__")}
    stub = STUBS / domain / "__init__.pyi"
    declared = _declared(stub)
    # the constants (CIRCLE_MIN_ARC_DEG, ...) are module attributes, not bindings the
    # generator sees: they are the only names allowed to be missing from a stub
    missing = {n for n in public - declared if not n.isupper()}
    assert missing == set(), f"{stub.name}: not declared {sorted(missing)}"
    assert declared - public == set(), f"{stub.name}: stale {sorted(declared - public)}"


def test_the_installed_package_ships_the_stubs():
    pkg = Path(gagekit.__file__).parent
    assert (pkg / "py.typed").is_file()
    assert (pkg / "_core" / "__init__.pyi").is_file()
    for name in DOMAINS:
        assert (pkg / "_core" / name / "__init__.pyi").is_file()


def test_the_checked_in_stubs_are_what_the_generator_writes(tmp_path):
    cargo = shutil.which("cargo")
    if cargo is None or not (REPO / "Cargo.toml").is_file():
        if os.environ.get("CI"):
            pytest.fail("cargo and the Rust sources are needed to check the stubs")
        pytest.skip("no cargo or no Rust sources here")
    proc = subprocess.run(
        [cargo, "run", "--quiet", "--release", "-p", "gagekit-py", "--features", "stubs",
         "--bin", "stub_gen", "--", str(tmp_path)],
        cwd=REPO, capture_output=True, text=True, timeout=1800,
    )
    assert proc.returncode == 0, proc.stderr[-4000:]
    fresh = tmp_path / "gagekit" / "_core"

    def differing(cmp: filecmp.dircmp) -> list[str]:
        out = [str(Path(cmp.left) / f) for f in cmp.diff_files + cmp.left_only + cmp.right_only]
        for sub in cmp.subdirs.values():
            out += differing(sub)
        return out

    stale = differing(filecmp.dircmp(fresh, STUBS, ignore=["__pycache__"]))
    assert stale == [], (
        f"stubs out of date: {stale}; run `cargo run -p gagekit-py --features stubs --bin stub_gen`"
    )
