"""Feasible insertions and enabled operations, as a few integer operations per (state, op).

Geometry (``../shared/DESIGN.md``, "Directions and relations"): a part ``p`` placed into the
assembled set ``S`` (not empty) is feasible iff

- RTC: ``p`` touches some ``j`` in ``S`` (any direction), or comes to rest on it: a part that
  a short fall brings onto ``j`` (support, below, e.g. a shaft lying in a bore across its
  clearance) touches it once settled;
- RTT: some direction ``d`` is free, ``TT_d(p, j)`` for every ``j`` in ``S`` (``p`` is inserted
  along ``-d``);

and the enabled optimisation constraints hold (switches in the spec):

- topological: the base part is placed first (every other part needs it in ``S``), and
  the explicit ``after`` predecessors are done;
- stability (support): ``p`` cannot fall, ``SP_g(p, j)`` for some ``j`` in ``S`` with ``g`` the
  gravity direction (in a unit's workspace, the unit's build gravity ``spec.unit_gravity``,
  e.g. ``+z`` for a die set's upper half built upside down): a short move along ``g`` would
  drive it into ``j``, or it is threaded on ``j`` (:mod:`cad.support`; skipped for
  operations marked ``held``: an agent holds the part).
  Relations without a support table (built by hand) fall back to contact along gravity,
  ``TC_g(p, j)``;
- functional: the free direction must be one the gripper approaches from
  (``gripper_approach``).

Everything is precomputed as per-part bitmasks over the spec's parts (bit ``j`` = part ``j``):
``contact[p]`` (parts ``p`` touches), ``blocked[p, d]`` (parts that block ``p`` along ``d``),
``support[p]`` (parts that keep ``p`` from falling). With ``S`` a uint64 bitset the checks are
``S & contact != 0``, ``OR_d (S & blocked[d] == 0)`` and ``S & support != 0``.

An assembly state packs the done operations (bit ``i`` = operation ``i``) and the tool
values (a small field per tool above the operation bits) into a key of ``W = ceil(bits / 64)``
uint64 words (one word, the fast path, up to 64 bits; see
:class:`asp.graph.state_keys.OperationModel`, which compiles the spec over this oracle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from asp.errors import SpecError
from asp.spec import DIRECTIONS, AssemblySpec

WORD_BITS = 64
"""Bits per word of a state key (a state key is ``W`` uint64 words)."""
MAX_OPS = 32767
"""Operations that fit the int16 operation index of the transitions."""


@dataclass(frozen=True, eq=False)
class InsertionOracle:
    """Per-part bitmasks of the geometric insertion test.

    A set of parts is a row of ``PW = ceil(n / 64)`` uint64 words (bit ``j % 64`` of word
    ``j // 64`` is part ``j``); a batch of ``k`` sets is a ``(k, PW)`` array (``(k,)`` is
    accepted when ``PW == 1``). Any number of parts fits.

    Attributes
    ----------
    parts : tuple of str, length n
        Part ids (bit ``j`` is part ``parts[j]``).
    contact : (n, PW) uint64
        Parts each part touches in some direction (or comes to rest on, see support).
    blocked : (n, 6, PW) uint64
        Parts that block each part's motion along each direction.
    support : (n, PW) uint64
        Parts that keep each part from falling (support along gravity).
    directions : (6,) bool
        Directions a part may be inserted from (all six unless functional is on).
    base : int
        Index of the base part, or -1.
    geometric, topological, stability : bool
        Which checks apply (geometric: relations were given).
    """

    parts: tuple[str, ...]
    contact: np.ndarray
    blocked: np.ndarray
    support: np.ndarray
    directions: np.ndarray
    base: int
    geometric: bool
    topological: bool
    stability: bool

    @property
    def n_words(self) -> int:
        """``PW``: uint64 words per part set."""
        return int(self.contact.shape[1])

    def index(self, part: str) -> int:
        try:
            return self.parts.index(part)
        except ValueError:
            raise SpecError(f"unknown part {part!r}") from None

    def sets(self, assembled) -> np.ndarray:
        """(k, PW) uint64 part sets from ``(k, PW)``, ``(k,)`` (one word) or Python ints."""
        s = np.asarray(assembled)
        if s.dtype == object or (s.ndim == 1 and self.n_words > 1):
            return pack_words([int(x) for x in s.reshape(-1)], self.n_words)
        s = s.astype(np.uint64, copy=False)
        return s.reshape(-1, 1) if s.ndim == 1 else s

    def bit(self, p: int) -> np.ndarray:
        """(PW,) uint64: the set holding part ``p`` alone."""
        return pack_words([1 << int(p)], self.n_words)[0]

    def feasible(
        self, p: int, assembled, held: bool = False, workspace: bool = False
    ) -> np.ndarray:
        """Whether part ``p`` may be inserted into each set.

        Parameters
        ----------
        p : int
            Part index.
        assembled : (k, PW) or (k,) uint64
            Sets of assembled parts.
        held : bool
            Skip the stability check.
        workspace : bool
            The sets are a subassembly's own workspace (no base part there).

        Returns
        -------
        (k,) bool
        """
        s = self.sets(assembled)
        ok = np.ones(s.shape[0], dtype=bool)
        if self.topological and self.base >= 0 and p != self.base and not workspace:
            ok &= _meets(s, self.bit(self.base))
        if self.geometric:
            geo = _meets(s, self.contact[p])
            free = np.zeros(s.shape[0], dtype=bool)
            for d in np.flatnonzero(self.directions):
                free |= ~_meets(s, self.blocked[p, d])
            geo &= free
            if self.stability and not held:
                geo &= _meets(s, self.support[p])
            ok &= geo | ~s.any(axis=1)
        return ok

    def mask(self, row) -> int:
        """A (PW,) mask row as a Python int."""
        return unpack_words(row)

    def blockers(self, p: int, assembled: int) -> dict[str, list[str]]:
        """For each direction, the parts of ``assembled`` that block ``p`` moving along it."""
        s = int(assembled)
        out = {}
        for d, name in enumerate(DIRECTIONS):
            m = s & self.mask(self.blocked[p, d])
            out[name] = [self.parts[j] for j in range(len(self.parts)) if m >> j & 1]
        return out

    def reasons(
        self, p: int, assembled: int, held: bool = False, workspace: bool = False
    ) -> list[str]:
        """Why part ``p`` cannot be inserted into the set ``assembled`` (empty if it can)."""
        s = int(assembled)
        out = []
        base_missing = self.base >= 0 and p != self.base and not s >> self.base & 1
        if self.topological and base_missing and not workspace:
            out.append(f"the base part {self.parts[self.base]} is not placed yet")
        if not self.geometric or s == 0:
            return out
        if not s & self.mask(self.contact[p]):
            out.append("no contact with the assembled parts")
        by = self.blockers(p, s)
        free = [d for d in DIRECTIONS if not by[d]]
        allowed = [d for d in free if self.directions[DIRECTIONS.index(d)]]
        if not free:
            out.append("no free direction")
        elif not allowed:
            out.append(f"free only along {', '.join(free)}, which the gripper cannot approach")
        if self.stability and not held and not s & self.mask(self.support[p]):
            out.append("nothing to rest on below it")
        return out


def blocked_text(by: dict[str, list[str]], limit: int = 3) -> str:
    """``"along +x by a, b; along -x by c; ..."`` for the directions that are blocked."""
    parts = []
    for d, names in by.items():
        if names:
            more = f" and {len(names) - limit} more" if len(names) > limit else ""
            parts.append(f"along {d} by {', '.join(names[:limit])}{more}")
    return "; ".join(parts)


def _meets(sets: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(k,) bool: whether each (PW,) row of ``sets`` shares a bit with ``mask``."""
    if sets.shape[1] == 1:
        return (sets[:, 0] & mask[0]) != np.uint64(0)
    return ((sets & mask) != np.uint64(0)).any(axis=1)


def pack_words(values: list[int], n_words: int) -> np.ndarray:
    """(k, n_words) uint64 rows of the Python ints ``values`` (least significant word first)."""
    rows = [split_words(int(v), n_words) for v in values]
    return np.array(rows, dtype=np.uint64).reshape(len(values), n_words)


def bool_words(table: np.ndarray, n_words: int) -> np.ndarray:
    """(k, n_words) uint64 rows of the (k, m) bool table (column ``j`` is bit ``j``)."""
    k, m = table.shape
    padded = np.zeros((k, n_words * WORD_BITS), dtype=bool)
    padded[:, :m] = table
    packed = np.packbits(padded, axis=1, bitorder="little")
    return packed.view("<u8").astype(np.uint64).reshape(k, n_words)


def unpack_words(row) -> int:
    """The Python int of a row of uint64 words (or of an int)."""
    if isinstance(row, int | np.integer):
        return int(row)
    return sum(int(w) << (WORD_BITS * k) for k, w in enumerate(np.asarray(row).reshape(-1)))


def insertion_oracle(spec: AssemblySpec, relations=None) -> InsertionOracle:
    """Precompute the per-part masks of ``spec`` from cad relations (or none: topology only).

    Parameters
    ----------
    relations : cad Relations, optional
        ``.parts`` (ids), ``.tc`` and ``.tt`` bool arrays ``(n, n, 6)``, and ``.sp``
        (support, same shape; contact along gravity when absent). Its parts must include
        every part an operation places and the base part.
    """
    real = spec.part_ids or tuple(dict.fromkeys(spec.placed_parts))
    parts = real + tuple(u for u, _ in spec.subassemblies)
    n = len(parts)
    n_words = max(1, math.ceil(n / WORD_BITS))
    contact = np.zeros((n, n), dtype=bool)
    blocked = np.zeros((n, 6, n), dtype=bool)
    support = np.zeros((n, n), dtype=bool)
    directions = np.ones(6, dtype=bool)
    c = spec.constraints
    if c.functional:
        directions[:] = [d in spec.gripper_approach for d in DIRECTIONS]
    geometric = relations is not None
    if geometric:
        rel_ids = tuple(str(x) for x in relations.parts)
        tc = np.asarray(relations.tc, dtype=bool)
        tt = np.asarray(relations.tt, dtype=bool)
        sp = getattr(relations, "sp", None)
        sp = tc if sp is None else np.asarray(sp, dtype=bool)
        m = len(rel_ids)
        if tc.shape != (m, m, 6) or tt.shape != (m, m, 6) or sp.shape != (m, m, 6):
            raise SpecError(
                f"relations: expected tc, tt and sp of shape ({m}, {m}, 6), got {tc.shape}, "
                f"{tt.shape} and {sp.shape}"
            )
        needed = set(spec.placed_parts) | ({spec.base_part} if spec.base_part else set())
        missing = sorted(needed - set(rel_ids))
        if missing:
            raise SpecError(
                f"{spec.source}: parts: no geometry (relations) for part {missing[0]!r}"
            )
        g = DIRECTIONS.index(spec.gravity)
        where = {pid: k for k, pid in enumerate(rel_ids)}
        known = np.array([k for k, pid in enumerate(parts) if pid in where], dtype=np.int64)
        r = np.array([where[parts[k]] for k in known], dtype=np.int64)
        ix = np.ix_(known, known)
        support[ix] = sp[np.ix_(r, r)][:, :, g]
        contact[ix] = tc[np.ix_(r, r)].any(axis=2) | support[ix]
        blocked[np.ix_(known, range(6), known)] = ~tt[np.ix_(r, r)].transpose(0, 2, 1)
        diagonal = np.arange(n)
        for table in (contact, support):
            table[diagonal, diagonal] = False
        blocked[diagonal, :, diagonal] = False
    for k, (_, members) in enumerate(spec.subassemblies):
        # a unit is one rigid body: the pairwise relations ORed over its members
        u, idx = len(real) + k, [parts.index(m) for m in members]
        for table in (contact, support, blocked):
            table[u] = table[idx].any(axis=0)
            table[u, ..., idx] = False
    if geometric and spec.unit_gravity:
        # a unit built in another orientation: its members rest along its own gravity
        # (their rows serve its workspace only; the unit's row above keeps the product's)
        for uid, down in spec.unit_gravity:
            idx = [parts.index(m) for m in dict(spec.subassemblies)[uid] if m in where]
            rows = np.array([where[parts[k]] for k in idx], dtype=np.int64)
            turned = sp[np.ix_(rows, r)][:, :, DIRECTIONS.index(down)]
            support[np.ix_(idx, known)] = turned
            contact[np.ix_(idx, known)] = tc[np.ix_(rows, r)].any(axis=2) | turned
            support[idx, idx] = contact[idx, idx] = False
    base = parts.index(spec.base_part) if spec.base_part in parts else -1
    return InsertionOracle(
        parts=parts,
        contact=bool_words(contact, n_words),
        blocked=bool_words(blocked.reshape(6 * n, n), n_words).reshape(n, 6, n_words),
        support=bool_words(support, n_words),
        directions=directions,
        base=base,
        geometric=geometric,
        topological=c.topological,
        stability=c.stability,
    )


def split_words(value: int, n_words: int) -> list[int]:
    """The ``n_words`` 64-bit words of ``value``, least significant first."""
    mask = (1 << WORD_BITS) - 1
    return [(value >> (WORD_BITS * k)) & mask for k in range(n_words)]


def load_relations(spec: AssemblySpec, *, progress: bool = False):
    """Read the meshes of ``spec``'s parts (in its build frame) and compute their cad
    relations (:func:`spec_relations`; ``None`` when the spec has no geometry)."""
    if not spec.has_geometry:
        return None
    from cad.loading import load_parts

    geometry = load_parts(spec.parts, spec.folder, spec.units, frame=spec.frame)
    return spec_relations(spec, geometry, progress=progress)


def spec_relations(spec: AssemblySpec, geometry, *, progress: bool = False):
    """The cad relations of ``geometry``, the meshes of ``spec``'s parts already read.

    With the spec's ``contact_tol`` and ``penetration_tol`` (None: the per-part rule), its
    ``overlap_ok`` pairs and its ``flex`` parts (:func:`asp.cad_keys.with_flex`); a contact
    graph in pieces has them joined by its nearest parts (:func:`cad.relations.with_nearest`).
    """
    import cad
    from asp.cad_keys import with_flex
    from cad.relations import with_nearest

    relations = cad.compute_relations(
        geometry,
        contact_tol=spec.contact_tol,
        penetration_tol=spec.penetration_tol,
        progress=progress,
        overlap_ok=spec.overlap_ok,
    )
    relations = with_nearest(relations)
    return with_flex(relations, spec.flex)
