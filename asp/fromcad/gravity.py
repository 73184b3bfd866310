"""Which way is down in a CAD file: the gravity of a generated spec.

A CAD file rarely says which way is up. glTF does (``+y``, by its specification), STEP,
3MF, 3DXML and mesh folders do not, and CAD exporters differ: SolidWorks and Creo STEP
exports are often Y-up, most others Z-up. The wrong choice makes gravity sideways: a
bracket then "needs" the rod beside it to rest on, and the assembly is infeasible.

Rule (:func:`choose_gravity`), from the part relations and bounding boxes. For each of the
six axis directions ``g`` (gravity along ``g``; the base part the lowest of the large parts
along ``g``, :func:`base_index`):

- ``held``: the parts (the base aside) that nothing can keep from falling along ``g`` (an
  empty row of the support relation ``SP_g``); a generated spec marks each ``held``;
- ``held_large``: how many of them are large (a bounding box of at least
  :data:`LARGE_VOLUME` of the largest part's): plates and housings rest on something
  under true gravity, pins and shafts in through holes do not;
- ``feasible``: a complete insertion sequence exists, base first, with the held parts held
  (:func:`one_sequence`: depth-first over part sets, a set dropped as soon as a part left
  out is blocked along every direction, at most :data:`SEARCH_BUDGET` sets; ``None`` when
  it runs out). Subassemblies are not tried here, so ``False`` is a hint,
  not a proof, that the full planner fails;
- ``footprint``: the base part's bounding-box face across ``g`` as a share of its largest
  face; the base *lies flat* when it is at least :data:`FLAT_SHARE`, and *stands on edge*
  otherwise (a housing disc on its rim, a plate on its side). A product is fixtured on
  its base lying flat: a sideways gravity makes the walls of every hole "support" the
  pins in it, so along it fewer parts need holding, but the parts stand in any order and
  the states multiply (a Z-up cycloidal drive written as glTF: 87 M states on its rim,
  4.2 M lying flat).

Directions are ranked by, in order: fewer large parts held, not proven infeasible, the
base lying flat, proven feasible, fewer parts held, then the format's own down ``D``
(``-y`` for glTF/GLB, else ``-z``), then ``-z, -y, -x, +z, +y, +x``. The format's down is
kept unless the best direction ``b`` is better on the first three keys (fewer large parts
held, or feasible where ``D`` is proven infeasible, or its base lies flat where ``D``'s
stands on edge), or proven feasible where ``D`` is not and needs no more hands
(``held[b] <= held[D]``): fewer held parts alone never switch. When ``D`` fails even with
every part held (some part is blocked whatever the gravity: two meshing helical gears on
their shafts, each blocking the other along them), the switch still gives a plan, but the
reason says the product is planned lying on its side, not that the file is another axis
up. Measured on the public files of the survey: the Pro/E bolted brackets and ``as1``
(Y-up STEP) get ``-y``, the Z-up exports keep ``-z``, Y-up glTF keeps ``-y``, Z-up glTF
written without turning its axes (trimesh's export of ``cycloidal.3DXML`` or
``rod.3DXML``) gets ``-z``; the cost is milliseconds to a second beside the relations.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from asp.spec import DIRECTIONS

SEARCH_BUDGET = 2_000
"""Part sets the search for one sequence may visit per direction before giving up."""
LARGE_VOLUME = 0.25
"""A part whose bounding box has this share of the largest part's volume is large."""
FLAT_SHARE = 0.5
"""The base lies flat when its face across gravity is this share of its largest face."""
PREFERENCE = ("-z", "-y", "-x", "+z", "+y", "+x")
"""Tie order among directions after the format's own down."""
GLTF_SUFFIXES = (".glb", ".gltf")
"""Formats whose specification says ``+y`` is up (trimesh does not turn them)."""


@dataclass(frozen=True)
class GravityChoice:
    """The gravity of a generated spec and why.

    Attributes
    ----------
    gravity : str
        The chosen direction (``"-z"``, ...).
    default : str
        The format's own down (``"-y"`` for glTF, else ``"-z"``).
    held : dict of str to int
        Per direction: parts nothing can keep from falling (held in a generated spec).
    held_large : dict of str to int
        Per direction: how many of those are large parts.
    feasible : dict of str to bool or None
        Per direction: a complete insertion sequence exists (None: the search ran out).
    footprint : dict of str to float
        Per direction: the base part's face across it as a share of its largest face (it
        lies flat at :data:`FLAT_SHARE` and more).
    base : dict of str to str
        Per direction: the base part's id.
    blocked_anyway : bool
        Along the default no order exists even with every part held: a part is blocked
        whatever the gravity (two helical gears on their shafts), so a switch says it builds
        the product lying on its side, not that the file is another axis up.
    given : str
        The gravity the user gave (``--gravity``; ``""``: none); it overrules the choice.
    """

    gravity: str
    default: str
    held: dict[str, int]
    held_large: dict[str, int]
    feasible: dict[str, bool | None]
    footprint: dict[str, float] = field(default_factory=dict)
    base: dict[str, str] = field(default_factory=dict)
    blocked_anyway: bool = False
    given: str = ""

    @property
    def reason(self) -> str:
        """Why this direction, in one line (stderr and ``asmplan init``'s comment)."""
        if self.given:
            return f"given (--gravity); from the geometry alone: {self.gravity}"
        g, d = self.gravity, self.default
        own = "glTF is +y up by its specification" if d == "-y" else "z up"
        if g == d:
            return f"the file format's own down ({own}); no other direction is clearly better"
        if self.feasible[g] and self.feasible[d] is False and self.blocked_anyway:
            return (
                f"not the default {d} ({own}): along {d} no part order can be inserted even "
                f"with every part held (some part is blocked whatever the gravity, as a "
                f"helical gear behind its mate): planned lying along {g}"
            )
        if self.held_large[g] < self.held_large[d]:
            why = f"along {d} {self.held_large[d]} large part(s) would need holding"
        elif self.feasible[g] is not False and self.feasible[d] is False:
            why = f"along {d} no part order can be inserted"
        elif self.lies_flat(g) and not self.lies_flat(d):
            why = (
                f"along {d} the base part {self.base[d]} stands on edge (its face across "
                f"{d} is {self.footprint[d]:.0%} of its largest), along {g} "
                f"{self.base[g]} lies flat"
            )
        else:
            why = f"along {d} no part order was found, along {g} one with no more parts held"
        return f"not the default {d} ({own}): {why}; the file is likely {_up_of(g)} up"

    def lies_flat(self, direction: str) -> bool:
        """Whether the base part along ``direction`` lies flat (True when not measured)."""
        return self.footprint.get(direction, 1.0) >= FLAT_SHARE

    def rank(self, direction: str) -> tuple:
        """The sort key of a direction (module docstring: the rule), the tie order aside."""
        feasible = self.feasible[direction]
        return (
            self.held_large[direction],
            feasible is False,
            not self.lies_flat(direction),
            feasible is not True,
            self.held[direction],
        )


def default_down(path: str | Path) -> str:
    """The down direction a file format declares: ``-y`` for glTF/GLB, else ``-z``."""
    return "-y" if Path(path).suffix.lower() in GLTF_SUFFIXES else "-z"


def base_index(bounds: np.ndarray, gravity: str = "-z") -> int:
    """The lowest of the large parts along ``gravity``.

    Of the parts whose footprint (bounding-box area across the gravity axis) is at least
    half the largest, the one whose bottom is lowest (the larger footprint on a tie);
    ``bounds`` shape (n, 2, 3).
    """
    axis = DIRECTIONS.index(gravity) // 2
    across = [a for a in range(3) if a != axis]
    extents = bounds[:, 1, :] - bounds[:, 0, :]
    footprint = extents[:, across[0]] * extents[:, across[1]]
    large = np.flatnonzero(footprint >= 0.5 * footprint.max())
    bottom = bounds[:, 0, axis] if gravity[0] == "-" else -bounds[:, 1, axis]
    order = sorted(large, key=lambda k: (bottom[k], -footprint[k], k))
    return int(order[0])


def choose_gravity(relations, bounds: np.ndarray, default: str = "-z") -> GravityChoice:
    """The gravity of a generated spec (module docstring: the rule).

    Parameters
    ----------
    relations : cad.relations.Relations
        ``tc``, ``tt``, ``sp``: ``(n, n, 6)`` bool.
    bounds : (n, 2, 3) float
        Each part's bounding box, in the order of ``relations.parts``.
    default : str
        The format's own down (:func:`default_down`).
    """
    volumes = np.prod(bounds[:, 1, :] - bounds[:, 0, :], axis=1)
    large = volumes >= LARGE_VOLUME * volumes.max()
    ids = [str(p) for p in relations.parts]
    held: dict[str, int] = {}
    held_large: dict[str, int] = {}
    feasible: dict[str, bool | None] = {}
    footprint: dict[str, float] = {}
    base: dict[str, str] = {}
    for g in DIRECTIONS:
        b = base_index(bounds, g)
        loose = _unsupportable(relations, g, b)
        held[g] = len(loose)
        held_large[g] = int(sum(large[k] for k in loose))
        feasible[g] = one_sequence(relations, g, b, loose)
        footprint[g] = footprint_share(bounds[b], g)
        base[g] = ids[b]
    anyway = feasible[default] is False and _blocked_anyway(relations, bounds, default)
    ranked = GravityChoice(default, default, held, held_large, feasible, footprint, base, anyway)
    order = [default, *(d for d in PREFERENCE if d != default)]
    best = min(order, key=lambda d: (ranked.rank(d), order.index(d)))
    mine, theirs = ranked.rank(best), ranked.rank(default)
    better = mine[:3] < theirs[:3] or (mine[:4] < theirs[:4] and held[best] <= held[default])
    return replace(ranked, gravity=best if better else default)


def footprint_share(box: np.ndarray, gravity: str) -> float:
    """A part's bounding-box face across ``gravity`` as a share of its largest face
    (``box`` shape (2, 3); 1.0: it lies on its largest face)."""
    e = np.maximum(np.asarray(box[1], dtype=float) - np.asarray(box[0], dtype=float), 0.0)
    faces = np.array([e[1] * e[2], e[0] * e[2], e[0] * e[1]])
    top = float(faces.max())
    return float(faces[DIRECTIONS.index(gravity) // 2]) / top if top > 0 else 1.0


def one_sequence(relations, gravity: str, base: int, held: set[int]) -> bool | None:
    """Whether the parts can all be inserted one by one, base first (None: search ran out).

    The insertion test of ``asp.graph.feasibility`` with every direction open to the gripper:
    a part goes in when it touches (or rests on) the parts there, some direction is free
    of all of them, and something stops it falling along ``gravity`` unless it is held.
    """
    n = len(relations.parts)
    g = DIRECTIONS.index(gravity)
    tc = np.asarray(relations.tc, dtype=bool)
    tt = np.asarray(relations.tt, dtype=bool)
    sp = np.asarray(relations.sp if relations.sp is not None else relations.tc, dtype=bool)

    def masks(table: np.ndarray) -> list[int]:
        # Python ints (not numpy's int64): the masks of 64 parts and more must not overflow.
        rows = [np.flatnonzero(row).tolist() for row in table]
        return [sum(1 << j for j in js if j != i) for i, js in enumerate(rows)]

    support = masks(sp[:, :, g])
    contact = [c | s for c, s in zip(masks(tc.any(axis=2)), support, strict=True)]
    blocked = [masks(~tt[:, :, d]) for d in range(6)]
    full = (1 << n) - 1
    dead: set[int] = set()

    def fits(p: int, s: int) -> bool:
        if not s & contact[p]:
            return False
        if p not in held and not s & support[p]:
            return False
        return any(not s & blocked[d][p] for d in range(6))

    def stuck(s: int) -> bool:
        """Some part left out is blocked along every direction: blocking only grows."""
        return any(not s >> p & 1 and all(s & blocked[d][p] for d in range(6)) for p in range(n))

    stack = [1 << int(base)]
    while stack:
        s = stack.pop()
        if s == full:
            return True
        if s in dead:
            continue
        dead.add(s)
        if len(dead) > SEARCH_BUDGET:
            return None
        if not stuck(s):
            stack += [s | 1 << p for p in reversed(range(n)) if not s >> p & 1 and fits(p, s)]
    return False


def _blocked_anyway(relations, bounds: np.ndarray, gravity: str) -> bool:
    """Whether no order exists along ``gravity`` even with every part held (support is not
    what fails: the translational freedom does not depend on gravity)."""
    everyone = set(range(len(relations.parts)))
    return one_sequence(relations, gravity, base_index(bounds, gravity), everyone) is False


def _unsupportable(relations, gravity: str, base: int) -> set[int]:
    """Indices of the parts (the base aside) whose support row along ``gravity`` is empty."""
    if getattr(relations, "sp", None) is None:
        return set()
    rows = np.asarray(relations.sp, dtype=bool)[:, :, DIRECTIONS.index(gravity)].any(axis=1)
    return {int(k) for k in np.flatnonzero(~rows) if k != base}


def _why_default(down: str) -> str:
    return "glTF is +y up by its specification" if down == "-y" else "z up"


def _up_of(gravity: str) -> str:
    """The up of a gravity direction, as a file's axis is named (``-y`` -> ``Y``)."""
    return gravity[1].upper() if gravity[0] == "-" else "-" + gravity[1].upper()
