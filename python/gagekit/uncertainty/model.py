"""The measurement model: how an instrument's errors perturb a scan (JCGM 101:2008 Sec. 5,
the input quantities and their probability distributions).

A model is a few numbers, from a ``[measurement]`` table of a TOML file or from options:

``sigma`` (mm)
    Per-point random noise. Without ``origin``: isotropic, each coordinate N(0, sigma^2)
    (so the noise along any direction, e.g. a surface normal, has standard deviation
    sigma). With ``origin`` (the scanner's position, mm, in the scan's frame): along the line
    of sight only, N(0, s(r)^2) with s(r) = sigma + sigma_per_m * r / 1000, r the range (mm).
    ``"auto"``: estimated from the residuals of the fitted features (:func:`estimate_sigma`).
``probing`` (mm)
    The probing form error P_FTU of ISO 10360-5 (the range of a sphere's radial
    residuals): each point moves by a uniform amount in [-P_FTU/2, +P_FTU/2] along a
    uniformly random direction.
``scale_ppm`` (um/m)
    The length-dependent part of MPE_E (ISO 10360-2/-8: E = A + L/K gives L/K in um per m
    as 1000/K): one relative scale error per simulated measurement, uniform in
    [-scale_ppm, +scale_ppm] x 1e-6, applied about the instrument's origin (the scan's
    (0, 0, 0), or ``origin``).
``cte`` (1/K) and ``delta_t`` (K)
    Thermal expansion not compensated: a relative scale error cte x dT with dT uniform in
    [-delta_t, +delta_t] (the part's temperature deviation from 20 C, ISO 1), per simulated
    measurement, added to the one above.
``offset`` (mm)
    Standard uncertainty of a systematic offset, one draw N(0, offset^2) per simulated
    measurement: along the line of sight (a range offset, which changes sizes) with
    ``origin``, else a translation of the whole scan (every coordinate).

Every draw of one simulated measurement comes from its own generator keyed by
(seed, trial index) (:meth:`MeasurementModel.simulate`: the kernel's xoshiro256++ stream,
``gagekit_gdt::plan::perturb``), so a trial's perturbation never depends on the order or
the number of threads the trials run on.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Mapping, Optional, Union

import numpy as np

from ..errors import ConfigError, InvalidInputError

__all__ = ["MeasurementModel", "load_measurement_model", "measurement_model", "trial_rng", "estimate_sigma",
           "MODEL_KEYS"]

#: The keys of a ``[measurement]`` table and what they mean.
MODEL_KEYS = {
    "sigma": "per-point noise, mm (isotropic per coordinate; along the line of sight with origin), or \"auto\"",
    "origin": "the scanner's position [x, y, z] (mm): noise and offset along the line of sight",
    "sigma_per_m": "added noise per metre of range (mm/m), with origin",
    "probing": "probing form error P_FTU (ISO 10360-5), mm",
    "scale_ppm": "length-dependent part of MPE_E, um/m (uniform +-)",
    "cte": "coefficient of thermal expansion, 1/K",
    "delta_t": "half-width of the temperature deviation from 20 C, K (uniform +-)",
    "offset": "standard uncertainty of a systematic offset, mm",
}


@dataclass(frozen=True)
class MeasurementModel:
    """An instrument's error model (see the module docstring); lengths mm."""

    sigma: float = 0.0
    origin: Optional[tuple[float, float, float]] = None
    sigma_per_m: float = 0.0
    probing: float = 0.0
    scale_ppm: float = 0.0
    cte: float = 0.0
    delta_t: float = 0.0
    offset: float = 0.0
    #: ``sigma`` was estimated from the features' residuals (``--noise auto``)
    sigma_auto: bool = False
    #: how sigma was estimated (``sigma_auto``)
    sigma_note: str = ""

    def __post_init__(self) -> None:
        for name in ("sigma", "sigma_per_m", "probing", "scale_ppm", "cte", "delta_t", "offset"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                raise InvalidInputError(f"measurement model: {name} must be a finite number >= 0, got {v!r}")
        if self.origin is not None:
            o = tuple(self.origin)
            if len(o) != 3 or not all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in o):
                raise InvalidInputError(f"measurement model: origin must be three finite numbers [x, y, z], got {self.origin!r}")
            object.__setattr__(self, "origin", tuple(float(x) for x in o))
        if self.sigma_per_m > 0 and self.origin is None:
            raise ConfigError("measurement model: sigma_per_m (range-dependent noise) needs the scanner's origin")

    @property
    def relative_scale(self) -> float:
        """Half-width of the uniform relative scale error (MPE_E's length term + cte x dT)."""
        return self.scale_ppm * 1e-6 + self.cte * self.delta_t

    @property
    def is_null(self) -> bool:
        """No error at all: every simulated measurement equals the measured one."""
        return self.sigma == 0 and self.probing == 0 and self.relative_scale == 0 and self.offset == 0

    def with_sigma(self, sigma: float, note: str = "") -> "MeasurementModel":
        return replace(self, sigma=float(sigma), sigma_auto=bool(note), sigma_note=note)

    def kernel_args(self) -> tuple:
        """The model as the kernels take it: (sigma, origin, sigma_per_m, probing, relative
        scale, offset)."""
        return (float(self.sigma), self.origin, float(self.sigma_per_m), float(self.probing), float(self.relative_scale),
                float(self.offset))

    def simulate(self, points: np.ndarray, seed: int, trial: int) -> np.ndarray:
        """Simulated measurement ``trial`` of ``points`` ((n, 3), or (n, 2) for plane
        figures; mm), a new array: every draw from the generator of (seed, trial) alone
        (``gagekit_gdt::plan::perturb``, the one implementation the compiled inspection's
        trials use too), so it never depends on the order or the threads of the trials."""
        from .. import _core

        p = np.ascontiguousarray(np.asarray(points, dtype=float))
        if p.ndim != 2 or p.shape[1] not in (2, 3):
            raise InvalidInputError(f"measurement model: points must be (n, 3) or (n, 2), got shape {p.shape}")
        return _core.gdt.perturb(p, self.kernel_args(), int(seed), int(trial))

    def perturb(self, points: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """One simulated measurement of ``points`` drawn from ``rng`` (it draws the seed of
        :meth:`simulate`): a new array."""
        return self.simulate(points, int(rng.integers(0, 2**63)), 0)

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {"sigma": self.sigma}
        if self.sigma_auto:
            d["sigma_source"] = self.sigma_note
        d["noise"] = "isotropic (per coordinate)" if self.origin is None else "line of sight"
        if self.origin is not None:
            d["origin"] = list(self.origin)
            d["sigma_per_m"] = self.sigma_per_m
        d.update(probing=self.probing, scale_ppm=self.scale_ppm, cte=self.cte, delta_t=self.delta_t,
                 relative_scale=self.relative_scale, offset=self.offset)
        return d


def trial_rng(seed: int, trial: int) -> np.random.Generator:
    """The generator of one simulated measurement: seeded by (seed, trial), independent of
    the order and the threads the trials run on."""
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence([int(seed), int(trial)])))


def _number(table: Mapping, key: str, source: str) -> float:
    v = table[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ConfigError(f"{source}: [measurement] {key} must be a number, got {v!r}")
    if not math.isfinite(v) or v < 0:
        raise InvalidInputError(f"{source}: [measurement] {key} must be a finite number >= 0, got {v!r}")
    return float(v)


def measurement_model(table: Optional[Mapping] = None, source: str = "measurement model", **overrides: Any) -> MeasurementModel:
    """A :class:`MeasurementModel` from a ``[measurement]`` table (a mapping) and keyword
    overrides (options on the command line win over the file; ``None`` keeps the file's).
    ``sigma = "auto"`` leaves sigma 0 and sets ``sigma_auto`` for :func:`estimate_sigma`."""
    t = dict(table or {})
    for k, v in overrides.items():
        if v is not None:
            t[k] = v
    unknown = sorted(set(t) - set(MODEL_KEYS))
    if unknown:
        raise ConfigError(f"{source}: [measurement] has unknown key(s) {', '.join(unknown)}; "
                          f"known: {', '.join(MODEL_KEYS)}")
    kw: dict[str, Any] = {}
    auto = False
    for key in MODEL_KEYS:
        if key not in t:
            continue
        if key == "origin":
            o = t[key]
            if not isinstance(o, (list, tuple)) or len(o) != 3:
                raise ConfigError(f"{source}: [measurement] origin must be [x, y, z], got {o!r}")
            kw["origin"] = tuple(o)  # checked (finite numbers) by MeasurementModel
        elif key == "sigma" and isinstance(t[key], str):
            if t[key].strip().lower() != "auto":
                raise ConfigError(f"{source}: [measurement] sigma must be a number (mm) or \"auto\", got {t[key]!r}")
            auto = True
        else:
            kw[key] = _number(t, key, source)
    model = MeasurementModel(**kw)
    return replace(model, sigma_auto=True) if auto else model


def load_measurement_model(path: Union[str, Path], **overrides: Any) -> MeasurementModel:
    """The ``[measurement]`` table of a TOML file (a file of its own, or a PART.toml /
    GAGES.toml that holds one) as a :class:`MeasurementModel`."""
    from .._util import load_toml

    doc = load_toml(path, "measurement model")
    table = doc.get("measurement")
    if not isinstance(table, Mapping):
        raise ConfigError(f"{path}: no [measurement] table (keys: {', '.join(MODEL_KEYS)})")
    return measurement_model(table, str(path), **overrides)


#: Parameters of each least-squares feature (for the degrees of freedom of its residuals).
FEATURE_PARAMETERS = {"plane": 3, "line": 4, "circle": 6, "sphere": 4, "cylinder": 5, "cone": 6, "slot": 4, "tab": 4}


#: ``--noise auto`` below this (mm, 0.1 nm) warns: no instrument is that quiet, so the points
#: were computed (a CAD sampling) or smoothed, and the residuals say nothing about noise.
SIGMA_AUTO_FLOOR = 1e-7


def estimate_sigma(residual_sets: list[tuple[np.ndarray, int]]) -> tuple[float, str]:
    """``--noise auto``: sigma = sqrt(sum r^2 / sum (n_i - p_i)), the pooled RMS of the
    least-squares residuals r (normal to each fitted feature) of every feature i with its
    n_i points and p_i fitted parameters (the degrees-of-freedom correction). The form
    deviations of the part count as noise, so the estimate errs on the large side.
    Returns (sigma, a sentence saying how)."""
    ss, dof, n = 0.0, 0, 0
    for r, p in residual_sets:
        r = np.asarray(r, dtype=float)
        ss += float(r @ r)
        dof += max(len(r) - int(p), 0)
        n += 1
    if dof <= 0:
        raise InvalidInputError("--noise auto: the fitted features have no degrees of freedom left to estimate the noise "
                                "(give sigma)")
    sigma = math.sqrt(ss / dof)
    if sigma < SIGMA_AUTO_FLOOR:
        warnings.warn(f"--noise auto: the residuals give sigma {sigma:.3g} mm, below any instrument's noise "
                      f"({SIGMA_AUTO_FLOOR:g} mm): the points look computed or smoothed, so the uncertainty counts no "
                      f"measurement noise; give --noise SIGMA or --measurement MODEL.toml", UserWarning, stacklevel=2)
    return sigma, (f"auto: pooled RMS of the least-squares residuals of {n} feature(s), "
                   f"sqrt(sum r^2 / (n - p)) with {dof} degrees of freedom")
