"""`gagekit demo`: the whole product on bundled sample data."""

from __future__ import annotations


def demo() -> None:
    """Run the end-to-end demonstration on bundled sample data."""
    raise NotImplementedError
