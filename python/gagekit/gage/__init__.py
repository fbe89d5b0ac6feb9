"""Virtual gages for scanned castings (Ch. 5)."""

__all__: list[str] = []
