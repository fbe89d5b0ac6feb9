"""The bundled bracket and its analytic expectations (python/gagekit/data/make_bracket.py)."""

import importlib.util

import pytest

from gagekit.samples import data_path


def load_generator():
    spec = importlib.util.spec_from_file_location("make_bracket", data_path("make_bracket.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="session")
def bracket():
    from gagekit import load_part_spec, read_points

    return read_points(data_path("bracket.ply")), load_part_spec(data_path("bracket.toml")), load_generator()


def key(t) -> str:
    """The EXPECTED (EXPECTED_SIZES: the callout's name) key of a callout."""
    if t.name:
        return t.name
    base = f"{t.characteristic} of {t.feature}"
    if t.feature == "C":
        base += " to " + "|".join(t.datums)
    return base
