"""Plans as text: the robust plan's steps and the per-part relations summary."""

from __future__ import annotations

from asp.game.plan import PlanStep
from asp.numbers import cost_text


def plan_text(steps: list) -> str:
    """The step list as aligned text lines (:class:`~asp.game.plan.PlanStep` or the plan file's
    step dicts, ``robust_plan`` / ``worst_line``)."""
    lines = []
    for s in steps:
        s = s.to_dict() if isinstance(s, PlanStep) else s
        if not s["operation"]:
            what = "passes (nothing it may do)" if s["description"] == "pass" else "waits"
            if s["cost"]:
                what += f"  [{cost_text(s['cost'])}]"
        else:
            what = (
                f"{s['operation']:5s} {s['agent']:3s} {s['description']}  [{cost_text(s['cost'])}]"
            )
        line = f"{s['step']:3d}. {s['player']:5s} {what}"
        others = [o for o in s["human_options"] if not o.startswith(f"{s['operation']} ")]
        if s["player"] == "human" and others:
            line += f"   (human may instead: {', '.join(others)})"
        lines.append(line)
    return "\n".join(lines)


def relations_summary_text(summary: list[dict]) -> str:
    """The relations summary (:func:`asp.game.plan.relations_summary`) as aligned text lines."""
    width = max((len(r["part"]) for r in summary), default=4)
    lines = []
    for r in summary:
        touches = " ".join(f"{q}({','.join(ds)})" for q, ds in r["contacts"].items()) or "-"
        free = " ".join(r["free"]) or "none"
        lines.append(f"  {r['part'].ljust(width)}  touches {touches}; free: {free}")
    return "\n".join(lines)
