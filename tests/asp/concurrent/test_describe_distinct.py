"""The distinct rows the concurrent policy is named by (`describe._first_distinct`)."""

import numpy as np
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from asp.concurrent.describe import _first_distinct

values = st.one_of(st.integers(-3, 3), st.integers(-(2**40), 2**40))


@given(arrays(np.int64, st.tuples(st.integers(0, 60), st.integers(1, 5)), elements=values))
def test_first_distinct_numbers_rows_in_first_appearance_order(keys):
    rows = [tuple(r) for r in keys.tolist()]
    number: dict[tuple, int] = {}
    for r in rows:
        number.setdefault(r, len(number))
    first, inverse = _first_distinct(keys)
    assert inverse.tolist() == [number[r] for r in rows]
    assert first.tolist() == [rows.index(r) for r in number]
