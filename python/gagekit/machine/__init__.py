"""Machine-tool volumetric error models and their identification (Ch. 3)."""

__all__: list[str] = []
