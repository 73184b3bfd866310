"""CAD relations: part meshes in assembled pose -> contact (TC) and freedom (TT).

Public API::

    from cad import load_assembly, compute_relations, rtc, rtt, tt_set, truth_table

    assembly = load_assembly("examples/bracket/")      # folder, scene or assembly.yaml
    rel = compute_relations(assembly)                  # rel.tc, rel.tt: (n, n, 6) bool
    rtt(rel, "screw", {"base", "plate"})

Directions are ``DIRECTIONS = ("+x", "-x", "+y", "-y", "+z", "-z")``; see
:mod:`cad.freedom` for the exact sweep method and :mod:`cad.tolerances` for defaults.
"""

from cad.assembly import Assembly, Part, unit_scale
from cad.contact import contact_relation
from cad.directions import DIRECTION_VECTORS, DIRECTIONS, direction_index, opposite
from cad.freedom import check_interpenetration, translational_freedom
from cad.loading import load_assembly, read_bom
from cad.relations import Relations, compute_relations, rtc, rtt, tt_set
from cad.tolerances import (
    CONTACT_NORMAL_MIN,
    DEFAULT_CONTACT_TOL_MM,
    DEFAULT_PENETRATION_TOL_MM,
    default_penetration_tol,
)
from cad.truth_table import TruthTable, truth_table

__all__ = [
    "CONTACT_NORMAL_MIN",
    "DEFAULT_CONTACT_TOL_MM",
    "DEFAULT_PENETRATION_TOL_MM",
    "DIRECTIONS",
    "DIRECTION_VECTORS",
    "Assembly",
    "Part",
    "Relations",
    "TruthTable",
    "check_interpenetration",
    "compute_relations",
    "contact_relation",
    "default_penetration_tol",
    "direction_index",
    "load_assembly",
    "opposite",
    "read_bom",
    "rtc",
    "rtt",
    "translational_freedom",
    "truth_table",
    "tt_set",
    "unit_scale",
]
