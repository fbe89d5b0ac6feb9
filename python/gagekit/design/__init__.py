"""Optimal experimental design: A-, D-, K-, E-, I-optimal plans with zones (Ch. 4)."""

__all__: list[str] = []
