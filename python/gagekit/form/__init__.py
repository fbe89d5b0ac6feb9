"""Form of lines, planes, circles, spheres and cylinders (Ch. 6)."""

__all__: list[str] = []
