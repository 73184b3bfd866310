"""Which way the product is fixtured: the build frame of a generated spec.

The six directions are axes of the build frame (:mod:`cad.frame`). A CAD file's own frame
is kept whenever it can work; only when some pair of parts can never be assembled in it
(:func:`cad.frame.interlocked`: each blocks the other along all six directions, or the
base part blocks a part along all six: whichever goes in second has no way in, whatever
the order, the subassemblies, gravity or hands) are other frames tried, so every assembly
that plans in its file's frame plans exactly as before.

Rule (:func:`choose_frame`): the candidates of :func:`cad.frame.candidate_frames` (at most
:data:`cad.frame.MAX_CANDIDATES`: a rotation turning an axis several parts share onto the
nearest coordinate axis, the most shared first, of the axes that a part of an interlocked
pair has) are tried in order; in each the relations
are computed afresh and the generated spec's decisions taken again (gravity, base part,
``held``). The first in which no pair is interlocked and the derived precedences do not
refute every sequence (:func:`asp.graph.precedences.infeasibility`) is taken; else the first in
which no pair is interlocked; else the file's frame stays (nothing helps; the state graph
then says which part can never be inserted). Each candidate costs one computation of the
relations. A candidate whose relations cannot be computed (a pair overlaps there that is a
fit in the file's frame: the toy truck's pins turned 20 degrees off their holes' axes are
no longer recognised as pins in holes) does not help, and is passed over.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from cad.errors import GeometryError
from cad.frame import Rotation, candidate_frames, frame_text, interlocked


@dataclass(frozen=True)
class FrameChoice:
    """The build frame of a generated spec, when the file's own could not do.

    Attributes
    ----------
    rotation : Rotation or None
        ``x_build = R @ x_file``; None: the file's frame kept (no candidate helped).
    stuck : tuple of (str, str)
        The pairs interlocked in the file's frame.
    reason : str
        Why this frame (the shared axis it turns onto a coordinate axis).
    tried : int
        Candidate frames tried.
    failed : int
        Candidates passed over because their relations could not be computed.
    """

    rotation: Rotation | None
    stuck: tuple[tuple[str, str], ...]
    reason: str
    tried: int
    failed: int = 0

    @property
    def text(self) -> str:
        """One line for a person (stderr, ``asmplan init``'s comment)."""
        shown = ", ".join(f"{a}-{b}" for a, b in self.stuck[:4])
        more = f" and {len(self.stuck) - 4} more" if len(self.stuck) > 4 else ""
        why = (
            f"in the file's frame {len(self.stuck)} pair(s) of parts block each other along "
            f"every axis direction ({shown}{more})"
        )
        if self.rotation is None:
            failed = (
                f" ({self.failed} of them: parts overlap there that fit in the file's frame)"
                if self.failed
                else ""
            )
            return (
                f"the file's frame kept, though {why}: none of {self.tried} frame(s) from "
                f"the parts' own axes helped{failed}"
            )
        return f"{frame_text(self.rotation)}: {why}; {self.reason}, now coordinate axes"


def choose_frame(decided, geometry, in_frame: Callable) -> tuple[FrameChoice | None, object]:
    """The build frame of a generated spec (module docstring: the rule).

    Parameters
    ----------
    decided : asp.fromcad.generate.Decisions
        The decisions in the file's frame (``spec``, ``relations``).
    geometry : cad.Assembly
        The parts in the file's frame.
    in_frame : callable
        ``in_frame(rotation)`` -> the decisions in that build frame.

    Returns
    -------
    (FrameChoice or None, Decisions or None)
        None, None when the file's frame is kept without a try (a user's spec, no
        relations, or no interlocked pair); else the choice and the decisions in the frame
        taken (None when the file's frame stays).
    """
    from asp.graph.precedences import infeasibility

    spec, relations = decided.spec, decided.relations
    if not spec.generated or relations is None or spec.frame is not None:
        return None, None
    stuck = tuple(interlocked(relations, spec.base_part))
    if not stuck:
        return None, None
    fallback, failed = None, 0
    candidates = candidate_frames(geometry, parts={p for pair in stuck for p in pair})
    for candidate in candidates:
        try:
            framed = in_frame(candidate.rotation)
        except GeometryError:  # overlaps there that the file's frame has as fits
            failed += 1
            continue
        if interlocked(framed.relations, framed.spec.base_part):
            continue
        choice = FrameChoice(candidate.rotation, stuck, candidate.reason, len(candidates))
        if not infeasibility(framed.spec, framed.relations):
            return choice, framed
        fallback = fallback or (choice, framed)
    return fallback or (FrameChoice(None, stuck, "", len(candidates), failed), None)


__all__ = ["FrameChoice", "choose_frame"]
