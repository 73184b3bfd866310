"""The compiled enabled-operations test agrees with the numpy one (asp/graph/enabled_kernel.py)."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from asp.graph.feasibility import pack_words, unpack_words
from asp.graph.state_keys import operation_model
from asp.spec import with_subassemblies
from tests.asp.graph.test_symmetry_ring import _random_spec, _random_tables


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    data=st.data(),
    copies=st.integers(2, 3),
    singles=st.integers(0, 2),
    words=st.sampled_from([1, 2]),
    units=st.integers(0, 2),
)
def test_kernel_and_numpy_agree(data, copies, singles, words, units):
    rel = _random_tables(data.draw, copies, singles)
    held = data.draw(st.sets(st.sampled_from("psr")))
    spec = _random_spec(rel.parts, held)
    # units: pin k with its roller built in a workspace of their own, inserted as one body
    spec = with_subassemblies(spec, [(f"u{k}", (f"p{k}", f"r{k}")) for k in range(units)])
    compiled = operation_model(spec, rel, _min_words=words)
    plain = operation_model(spec, rel, _min_words=words)
    plain.__dict__["_kernel_args"] = None  # the numpy path
    assert compiled._kernel_args is not None
    n_ops, n = len(spec.operations), len(rel.parts)
    done = data.draw(st.lists(st.integers(0, (1 << n_ops) - 1), min_size=1, max_size=30))
    keys = compiled.pack(done)
    by_op = [spec.operations[i].parts for i in range(n_ops)]
    parts = pack_words(
        [
            sum(1 << rel.parts.index(p) for i in range(n_ops) if d >> i & 1 for p in by_op[i])
            | data.draw(st.sampled_from([0, 1]))  # the base part there or not
            for d in done
        ],
        compiled.oracle.n_words,
    )
    assert n + units == len(compiled.oracle.parts)
    np.testing.assert_array_equal(compiled.enabled(keys, parts), plain.enabled(keys, parts))
    dead = stuck(plain, keys, parts)
    np.testing.assert_array_equal(compiled.stuck(keys, parts), dead)
    # a state reached by one operation from a state that is not stuck: tested only for
    # what the new part changes, the same answer
    moves = [(r, i) for r in np.flatnonzero(~dead) for i in range(n_ops) if not done[r] >> i & 1]
    if moves:
        rows = np.array([r for r, _ in moves])
        child_keys = compiled.pack([done[r] | 1 << i for r, i in moves])
        child_parts = parts[rows] | compiled.op_parts[[i for _, i in moves]]
        np.testing.assert_array_equal(
            compiled.stuck(child_keys, child_parts, (keys[rows], parts[rows])),
            stuck(plain, child_keys, child_parts),
        )


def stuck(model, keys, parts):
    """The dead ends by the definition: an operation not done whose part (or unit) the set
    it is tested against blocks along every allowed direction."""
    oracle = model.oracle
    pending = model.pending_units(keys)
    out = []
    for row in range(keys.shape[0]):
        done = model.unpack(keys[row])
        dead = False
        for i, plist in enumerate(model.part_lists):
            if done >> i & 1 or not plist:
                continue
            rows = np.array([row])
            s, _ = model.assembled_for(i, parts[rows], pending, rows)
            s = unpack_words(s[0])
            p = plist[0]
            free = [
                not s & unpack_words(oracle.blocked[p, d]) for d in range(6) if oracle.directions[d]
            ]
            dead |= not any(free)
        out.append(dead)
    return np.array(out, dtype=bool)
