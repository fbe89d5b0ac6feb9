"""Report sections for form fits of cylinders (Sec. 6.3, Fig. 6.8, Tables 6.2-6.4)."""

from __future__ import annotations

from typing import Sequence

import numpy as np

from .html import Report


def radial_deviation(points: np.ndarray, fit) -> tuple[np.ndarray, np.ndarray]:
    """Angle about the fitted axis (deg) and distance to the axis (mm) of each point."""
    a = np.asarray(fit.direction, dtype=float)
    d = np.asarray(points, dtype=float) - np.asarray(fit.point, dtype=float)
    radial = d - np.outer(d @ a, a)
    e1 = np.cross(a, [1.0, 0, 0] if abs(a[0]) < 0.9 else [0, 1.0, 0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    ang = np.degrees(np.arctan2(radial @ e2, radial @ e1)) % 360.0
    return ang, np.linalg.norm(radial, axis=1)


def add_cylinder_fits(report: Report, label: str, points: np.ndarray, fits: Sequence) -> None:
    """One panel per criterion: each point's distance to the fitted axis against its angle,
    with the fitted radius (or the zone) and the control points marked (cf. Fig. 6.8)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(fits), figsize=(4.2 * len(fits), 3.6), squeeze=False)
    for ax, fit in zip(axes[0], fits):
        ang, r = radial_deviation(points, fit)
        ax.scatter(ang, 1e3 * (r - fit.radius), s=12, color="#2a5d9f", label="points")
        ctrl = list(fit.control_points)
        if ctrl:
            ax.scatter(ang[ctrl], 1e3 * (r[ctrl] - fit.radius), s=60, facecolors="none", edgecolors="#b3261e",
                       linewidths=1.5, label="control points")
        if fit.inner_radius is not None:
            for rr in (fit.inner_radius, fit.outer_radius):
                ax.axhline(1e3 * (rr - fit.radius), color="#b3261e", lw=1)
        else:
            ax.axhline(0.0, color="#b3261e", lw=1)
        ax.set_title(f"{fit.criterion}\nradius {fit.radius:.7f} mm, form {1e3 * fit.form_error:.4f} um", fontsize=9)
        ax.set_xlabel("angle about the axis (deg)")
        ax.set_ylabel("distance to axis - radius (um)")
        ax.set_xlim(0, 360)
        ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize=7, loc="best")
    fig.tight_layout()
    report.figure(fig, f"cylinders-{label}", f"{label}: radial deviations, fitted radius or zone, control points (cf. Fig. 6.8)")
