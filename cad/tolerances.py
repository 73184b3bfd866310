"""Default tolerances, in millimetres, and how they follow the part size.

- Contact tolerance: 0.01 mm. Two parts are in contact where their facing surfaces are
  at most this far apart (or overlap by at most the penetration tolerance).
- Penetration tolerance: ``max(0.05 mm, 0.001 x median part bounding-box diagonal)``,
  so 0.05 mm for parts up to 50 mm, 0.1 mm for 100 mm parts, 0.3 mm for 300 mm parts.
  This absorbs tessellation overlaps of exported CAD (a few hundredths of a millimetre)
  and the interference of press fits in larger parts. An overlap no deeper than it counts
  as touching; a deeper one in the assembled pose is an error.

Both are in millimetres whatever the source unit, because meshes are stored in mm; the same
parts therefore give the same tables in any unit.
"""

from __future__ import annotations

import numpy as np

DEFAULT_CONTACT_TOL_MM = 0.01
DEFAULT_PENETRATION_TOL_MM = 0.05
PENETRATION_TOL_PER_SIZE = 1e-3
CONTACT_NORMAL_MIN = 0.25
"""A surface faces direction ``d`` for contact if its normal's component along ``d`` is at
least this (normal within about 75.5 degrees of ``d``)."""


def default_penetration_tol(diagonals_mm: np.ndarray) -> float:
    """Penetration tolerance (mm) for parts with these bounding-box diagonals (mm)."""
    if len(diagonals_mm) == 0:
        return DEFAULT_PENETRATION_TOL_MM
    return max(
        DEFAULT_PENETRATION_TOL_MM, PENETRATION_TOL_PER_SIZE * float(np.median(diagonals_mm))
    )


def resolve_tolerances(
    diagonals_mm: np.ndarray, contact_tol: float | None, penetration_tol: float | None
) -> tuple[float, float]:
    """``(contact_tol, penetration_tol)`` in mm, defaults filled in and checked.

    Raises
    ------
    ValueError
        A negative contact tolerance or a non-positive penetration tolerance.
    """
    ctol = DEFAULT_CONTACT_TOL_MM if contact_tol is None else float(contact_tol)
    ptol = (
        default_penetration_tol(diagonals_mm) if penetration_tol is None else float(penetration_tol)
    )
    if not np.isfinite(ctol) or ctol < 0:
        raise ValueError(f"contact tolerance must be >= 0 mm, got {contact_tol}")
    if not np.isfinite(ptol) or ptol <= 0:
        raise ValueError(f"penetration tolerance must be > 0 mm, got {penetration_tol}")
    return ctol, ptol
