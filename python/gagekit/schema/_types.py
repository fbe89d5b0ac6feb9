"""The value types the file schemas share (TOML has no vector type: a vector is an array)."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field

__all__ = ["Name", "Vec3", "NonNegative", "Positive"]

Name = Annotated[str, Field(min_length=1)]
Vec3 = Annotated[list[float], Field(min_length=3, max_length=3)]
NonNegative = Annotated[float, Field(ge=0.0)]
Positive = Annotated[float, Field(gt=0.0)]
