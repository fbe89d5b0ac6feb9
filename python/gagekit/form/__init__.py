"""Form of lines, planes, circles, spheres and cylinders (Ch. 6)."""

from .cylinder import *  # noqa: F401,F403
from .cylinder import __all__ as _cylinder_all
from .fits import *  # noqa: F401,F403
from .fits import __all__ as _fits_all

__all__: list[str] = [*_fits_all, *_cylinder_all]
