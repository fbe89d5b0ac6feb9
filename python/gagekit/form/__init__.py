"""Form of lines, planes, circles, spheres and cylinders (Ch. 6)."""

# circles
from .circle import CIRCLE_CRITERIA, CircleFit, fit_circle

__all__: list[str] = [
    # circles
    "CircleFit",
    "fit_circle",
    "CIRCLE_CRITERIA",
]
