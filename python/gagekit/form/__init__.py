"""Form of lines, planes, circles, spheres, cylinders (Ch. 6) and cones (Sec. 7.2 item 6)."""

# circles
from .circle import CIRCLE_CRITERIA, CircleFit, fit_circle

# 3-D fits
from .cylinder import *  # noqa: F401,F403
from .cylinder import __all__ as _cylinder_all
from .cone import *  # noqa: F401,F403
from .cone import __all__ as _cone_all
from .fits import *  # noqa: F401,F403
from .fits import __all__ as _fits_all

# filtered form parameters (ISO 16610-21, ISO 12181, ISO 12780, ISO 12781)
from .parameters import *  # noqa: F401,F403
from .parameters import __all__ as _parameters_all

__all__: list[str] = [
    # circles
    "CircleFit",
    "fit_circle",
    "CIRCLE_CRITERIA",
    # 3-D fits
    *_fits_all,
    *_cylinder_all,
    *_cone_all,
    *_parameters_all,
]
