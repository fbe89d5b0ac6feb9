"""The exception hierarchy: kernel errors and panics arrive as gagekit exceptions."""

import numpy as np
import pytest

import gagekit
from gagekit import _core
from gagekit.errors import (
    ConfigError,
    DegenerateGeometryError,
    FileFormatError,
    GagekitError,
    InfeasibleError,
    InternalError,
    InvalidInputError,
    NumericalError,
)


def test_hierarchy():
    for cls in (InvalidInputError, FileFormatError, DegenerateGeometryError, InfeasibleError, ConfigError,
                NumericalError, InternalError):
        assert issubclass(cls, GagekitError)
    assert issubclass(FileFormatError, InvalidInputError)


def test_a_panic_is_an_internal_error_not_an_abort():
    with pytest.raises(InternalError, match="deliberate test panic"):
        _core._testing.panic_in_kernel()
    # the interpreter and the extension keep working afterwards
    assert len(gagekit.convex_hull_indices(np.eye(3))) == 3


def test_kernel_errors_map_to_their_classes():
    with pytest.raises(InvalidInputError, match="non-finite"):
        gagekit.convex_hull_indices([[0, 0, 0], [1, np.nan, 0]])
    with pytest.raises(InvalidInputError, match="shape"):
        _core.geometry.hull_indices(np.zeros((5, 2)))
