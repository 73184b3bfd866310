"""Plain-text renderings of results, for a person at a terminal."""

from __future__ import annotations

from asp.game.metrics import PlanMetrics
from asp.numbers import cost_text


def _num(x: float) -> str:
    return cost_text(x, ".3f")


def metrics_text(m: PlanMetrics, title: str = "") -> str:
    """A two-column table of the metrics and the robust path."""
    rows = [
        ("nodes / edges", f"{m.nodes} / {m.edges}"),
        ("TCT (cooperative minimum)", _num(m.tct)),
        ("W* (minimax value)", _num(m.minimax)),
        ("WCPL (reference)", _num(m.wcpl)),
        ("certified WCPL", _num(m.certified_wcpl)),
        ("robust-optimal", "yes" if m.robust_optimal else "no"),
        ("avg random length (exact)", f"{m.avg_random:.3f}"),
        ("min / max random length (exact)", f"{_num(m.min_random)} / {_num(m.max_random)}"),
        ("RR vs reference WCPL (exact)", f"{100 * m.rr:.1f}%"),
        ("RR vs certified WCPL", f"{100 * m.rr_certified:.1f}%"),
        (
            f"simulated ({m.games} games, seed {m.seed})",
            f"avg {m.avg_random_sampled:.3f}, max {_num(m.max_random_sampled)}, "
            f"RR {100 * m.rr_sampled:.1f}%",
        ),
        ("adversarial tax (W*/TCT)", _tax(m.adversarial_tax)),
    ]
    width = max(len(k) for k, _ in rows)
    lines = [title] if title else []
    lines += [f"{k.ljust(width)}  {v}" for k, v in rows]
    lines.append("robust path (both play minimax): " + " -> ".join(str(x) for x in m.robust_path))
    return "\n".join(lines)


def _tax(tax: float | None) -> str:
    return "undefined (TCT 0, W* > 0)" if tax is None else f"{tax:.2f}"
