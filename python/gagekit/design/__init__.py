"""Optimal experimental design: A-, D-, K-, E-, I-optimal plans with zones (Ch. 4)."""

from .optimal import CRITERIA, DesignResult, optimal_design

__all__: list[str] = ["optimal_design", "DesignResult"]
