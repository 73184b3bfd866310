"""Assignment of participants to the study's robot conditions and plans.

A participant plays a list of *blocks*, one session each: ``(plan, condition)``.

- ``design: within``: every participant meets every condition, on every plan (plans in
  the outer loop, conditions in the inner); ``between``: each participant meets one
  condition, on every plan.
- ``order: counterbalanced``: the ``n``-th participant enrolled (0, 1, ...) takes row
  ``n mod rows`` of a balanced Latin square of the conditions (within: each condition in
  each position equally often, and for an even count each condition following each other
  once: Williams' design; an odd count takes the square and its mirror, 2 x count rows);
  between: condition ``n mod count``. ``random``: a permutation (within) or a condition
  (between) drawn from a generator seeded with the study's ``seed`` and the participant's
  id, so the same participant always gets the same.
- ``plans: fixed`` (the study's order), ``counterbalanced`` (a Latin square of the plans
  by enrolment) or ``random`` (seeded likewise).
"""

from __future__ import annotations

import random

DESIGNS = ("within", "between")
ORDERS = ("counterbalanced", "random")
PLAN_ORDERS = ("fixed", "counterbalanced", "random")


def latin_square(n: int) -> list[list[int]]:
    """A balanced Latin square of ``n`` items: rows of ``range(n)`` (Williams' design).

    For even ``n`` each item is in each position once and follows every other item once;
    for odd ``n`` the square's rows are followed by their mirrors (``2 n`` rows)."""
    if n < 1:
        raise ValueError(f"latin square: expected at least one item, got {n}")
    first, lo, hi = [0], 1, n - 1
    while len(first) < n:
        first.append(lo)
        lo += 1
        if len(first) < n:
            first.append(hi)
            hi -= 1
    rows = [[(x + r) % n for x in first] for r in range(n)]
    if n % 2:
        rows += [row[::-1] for row in rows]
    return rows


def _order(count: int, how: str, number: int, rng: random.Random) -> list[int]:
    if how == "fixed":
        return list(range(count))
    if how == "counterbalanced":
        rows = latin_square(count)
        return rows[number % len(rows)]
    order = list(range(count))
    rng.shuffle(order)
    return order


def blocks(
    plans: list[str],
    conditions: list[str],
    *,
    design: str,
    order: str,
    plan_order: str,
    seed: int,
    number: int,
    participant: str,
) -> list[dict]:
    """The blocks of the ``number``-th participant enrolled, ``participant`` by id:
    ``[{"block", "plan", "condition"}]`` in the order played."""
    if design not in DESIGNS or order not in ORDERS or plan_order not in PLAN_ORDERS:
        raise ValueError(
            f"assignment: bad design {design!r}, order {order!r} or plans {plan_order!r}"
        )
    rng = random.Random(f"{seed}/{participant}")
    plan_seq = [plans[i] for i in _order(len(plans), plan_order, number, rng)]
    if design == "within":
        conds = [conditions[i] for i in _order(len(conditions), order, number, rng)]
    elif order == "counterbalanced":
        conds = [conditions[number % len(conditions)]]
    else:
        conds = [rng.choice(conditions)]
    out = []
    for plan in plan_seq:
        for cond in conds:
            out.append({"block": len(out), "plan": plan, "condition": cond})
    return out
