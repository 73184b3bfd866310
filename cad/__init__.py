"""CAD relations: part meshes in assembled pose -> contact (TC) and freedom (TT).

Public API::

    from cad import load_assembly, compute_relations, rtc, rtt, tt_set, truth_table

    assembly = load_assembly("examples/bracket/")      # folder of meshes or scene file
    rel = compute_relations(assembly)                  # rel.tc, rel.tt: (n, n, 6) bool
    rtt(rel, "screw", {"base", "plate"})

Directions are ``DIRECTIONS = ("+x", "-x", "+y", "-y", "+z", "-z")``; see
:mod:`cad.freedom` for the exact sweep method and :mod:`cad.tolerances` for defaults.
"""

_LOCATION = {
    "Assembly": "cad.assembly",
    "CONTACT_NORMAL_MIN": "cad.tolerances",
    "DEFAULT_CONTACT_TOL_MM": "cad.tolerances",
    "DEFAULT_PENETRATION_TOL_MM": "cad.tolerances",
    "DIRECTIONS": "cad.directions",
    "DIRECTION_VECTORS": "cad.directions",
    "Part": "cad.assembly",
    "PartRecord": "cad.bom",
    "Relations": "cad.relations",
    "TruthTable": "cad.truth_table",
    "check_interpenetration": "cad.freedom",
    "compute_relations": "cad.relations",
    "contact_relation": "cad.contact",
    "default_penetration_tol": "cad.tolerances",
    "direction_index": "cad.directions",
    "interlocked": "cad.frame",
    "parse_frame": "cad.frame",
    "rotated": "cad.frame",
    "load_assembly": "cad.loading",
    "load_parts": "cad.loading",
    "opposite": "cad.directions",
    "read_bom": "cad.bom",
    "rtc": "cad.relations",
    "rtt": "cad.relations",
    "translational_freedom": "cad.freedom",
    "truth_table": "cad.truth_table",
    "tt_set": "cad.relations",
    "unit_scale": "cad.units",
    "DecimalsAsText": "cad.yamlfile",
    "PlainNumbers": "cad.yamlfile",
    "STEP_CHORD_MM": "cad.readers",
    "checked_tolerance": "cad.tolerances",
    "coordinate_scale": "cad.scene",
    "frame_text": "cad.frame",
    "read_scene": "cad.scene",
    "replay_rules": "cad.relations",
    "size_hint": "cad.unit_hints",
    "why_blocked": "cad.explain",
}
"""Where each public name lives; modules load on first use (``import cad.bom`` stays light)."""

__all__ = [
    "CONTACT_NORMAL_MIN",
    "DEFAULT_CONTACT_TOL_MM",
    "DEFAULT_PENETRATION_TOL_MM",
    "DIRECTIONS",
    "DIRECTION_VECTORS",
    "STEP_CHORD_MM",
    "Assembly",
    "DecimalsAsText",
    "Part",
    "PartRecord",
    "PlainNumbers",
    "Relations",
    "TruthTable",
    "check_interpenetration",
    "checked_tolerance",
    "compute_relations",
    "contact_relation",
    "coordinate_scale",
    "default_penetration_tol",
    "direction_index",
    "frame_text",
    "interlocked",
    "load_assembly",
    "load_parts",
    "opposite",
    "parse_frame",
    "read_bom",
    "read_scene",
    "replay_rules",
    "rotated",
    "rtc",
    "rtt",
    "size_hint",
    "translational_freedom",
    "truth_table",
    "tt_set",
    "unit_scale",
    "why_blocked",
]


def __getattr__(name: str):
    if name in _LOCATION:
        import importlib

        value = getattr(importlib.import_module(_LOCATION[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'cad' has no attribute {name!r}")
