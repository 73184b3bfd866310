"""A first assembly spec from a CAD file alone, and the choices it makes from the geometry.

:mod:`~asp.fromcad.generate` (the generated spec and ``asmplan init``'s commented file),
:mod:`~asp.fromcad.gravity` (which way is down), :mod:`~asp.fromcad.framing` (the build
frame) and :mod:`~asp.fromcad.orientation` (which way up a unit is built).
"""

from asp.lazy import lazy_exports

__all__, __getattr__ = lazy_exports(
    __name__,
    {
        "generate": (
            "Source",
            "decide_generated",
            "load_any",
            "read_source",
            "spec_geometry",
            "spec_text",
        ),
    },
)
