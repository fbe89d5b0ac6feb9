//! Parallel, seeded particle swarm optimisation (Sec. 6.3).
