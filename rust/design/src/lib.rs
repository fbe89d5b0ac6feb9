//! Optimal experimental design: A-, D-, K-optimal plans with zones (Ch. 4).
