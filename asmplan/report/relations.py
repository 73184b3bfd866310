"""Render :class:`cad.relations.Relations` as text, Markdown, CSV or JSON."""

from __future__ import annotations

import csv
import io
import json

from cad.relations import Relations


def _dirs(relations: Relations, row) -> str:
    return " ".join(d for d, v in zip(relations.directions, row, strict=True) if v) or "-"


def _header(relations: Relations) -> str:
    return (
        f"{len(relations.parts)} parts, source units {relations.units}, tolerances in mm: "
        f"contact {relations.contact_tol:.3g}, penetration up to {relations.penetration_tol:.3g} "
        "per pair"
    )


def _rows(relations: Relations) -> tuple[list[tuple[str, str, str, str]], int]:
    """``(i, j, contact directions, free directions)`` for pairs worth listing."""
    rows, quiet = [], 0
    for a, pa in enumerate(relations.parts):
        for b, pb in enumerate(relations.parts):
            if a == b:
                continue
            tc, tt = relations.tc[a, b], relations.tt[a, b]
            if not tc.any() and tt.all():
                quiet += 1
                continue
            rows.append((pa, pb, _dirs(relations, tc), _dirs(relations, tt)))
    return rows, quiet


def relations_text(relations: Relations) -> str:
    """Aligned listing: per ordered pair, contact directions and free directions."""
    rows, quiet = _rows(relations)
    head = ("i", "j", "TC: j touches i on side", "TT: i free past j along")
    widths = [max(len(r[c]) for r in [head, *rows]) for c in range(4)]
    lines = [_header(relations), ""]
    for row in [head, tuple("-" * w for w in widths), *rows]:
        lines.append("  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)).rstrip())
    if quiet:
        lines.append(f"({quiet} other ordered pairs: no contact, free in every direction)")
    return "\n".join(lines) + "\n"


def relations_markdown(relations: Relations) -> str:
    """Markdown table of the same listing as :func:`relations_text`."""
    rows, quiet = _rows(relations)
    lines = [
        _header(relations),
        "",
        "| i | j | TC: j touches i on side | TT: i free past j along |",
        "|---|---|---|---|",
    ]
    lines += [f"| {a} | {b} | {c} | {t} |" for a, b, c, t in rows]
    if quiet:
        lines += ["", f"{quiet} other ordered pairs: no contact, free in every direction."]
    return "\n".join(lines) + "\n"


def relations_csv(relations: Relations) -> str:
    """CSV, one row per ordered pair and relation: ``i,j,relation,+x,-x,+y,-y,+z,-z``."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["i", "j", "relation", *relations.directions])
    for a, pa in enumerate(relations.parts):
        for b, pb in enumerate(relations.parts):
            if a == b:
                continue
            for name, table in (("tc", relations.tc), ("tt", relations.tt)):
                writer.writerow([pa, pb, name, *(int(v) for v in table[a, b])])
    return out.getvalue()


def relations_json(relations: Relations) -> str:
    """One JSON object: ``parts``, ``directions``, ``units``, ``tc``, ``tt`` and tolerances."""
    return json.dumps(relations.to_dict())


def why_text(relations: Relations, part: str) -> str:
    """Why ``part`` cannot move along each direction: blockers and depth, one line each."""
    from cad.explain import why_blocked

    lines = [f"{part}: what blocks it along each direction (depth: layers of parts to take out"]
    lines[0] += " first along that direction)"
    for b in why_blocked(relations, part):
        if not b.blockers:
            lines.append(f"  {b.direction}  free (depth 0)")
            continue
        depth = "never free: parts lock each other" if b.depth is None else f"depth {b.depth}"
        lines.append(f"  {b.direction}  blocked by {', '.join(b.blockers)} ({depth})")
    free = [b.direction for b in why_blocked(relations, part) if not b.blockers]
    lines.append(
        f"  free now along {' '.join(free)}: it can be inserted along the opposite"
        if free
        else "  free along no direction: it can only go in before some of its blockers"
    )
    return "\n".join(lines) + "\n"


def why_json(relations: Relations, part: str) -> str:
    """:func:`why_text` as JSON: ``{part, directions: [{direction, blockers, depth}]}``."""
    from cad.explain import why_blocked

    rows = [
        {"direction": b.direction, "blockers": list(b.blockers), "depth": b.depth}
        for b in why_blocked(relations, part)
    ]
    return json.dumps({"part": part, "directions": rows}) + "\n"
