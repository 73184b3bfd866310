"""State graphs whose keys take more than one 64-bit word (over 64 operations and tool bits)."""

from __future__ import annotations

import itertools
import math
import random
from functools import cache

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from asp.game.solve import solve
from asp.graph.game_dag import game_dag
from asp.graph.state_graph import build_state_graph
from asp.graph.state_keys import operation_model
from asp.spec import spec_from_dict
from tests.asp.helpers_assembly import precedence_spec, stack_relations, stack_spec


def diamond_chain(ks, first=0):
    """Precedence pairs of a chain of diamonds ``a -> (k middles) -> d``, one per ``k``.

    Returns the pairs and the number of tasks used (tasks ``first, first + 1, ...``).
    """
    pairs, pos, prev = [], first, None
    for k in ks:
        a, mids, d = pos, list(range(pos + 1, pos + 1 + k)), pos + 1 + k
        if prev is not None:
            pairs.append((prev, a))
        pairs += [(a, m) for m in mids] + [(m, d) for m in mids]
        if not mids:
            pairs.append((a, d))
        prev, pos = d, d + 1
    return pairs, pos - first


def diamond_formulas(ks):
    """States, transitions and sequences of one chain of diamonds, in closed form.

    A diamond with ``k`` middles has ``2**k + 1`` non-empty downsets once the diamonds before
    it are done, ``k * 2**(k - 1) + 2`` transitions among them and ``k!`` orders.
    """
    states = 1 + sum(2**k + 1 for k in ks)
    transitions = sum(k * 2 ** (k - 1) + 2 for k in ks) if ks else 0
    sequences = math.prod(math.factorial(k) for k in ks)
    return states, transitions, sequences


def relabel(n, pairs, seed):
    """The same precedence graph with the task numbers shuffled (ops spread over the words)."""
    perm = list(range(n))
    random.Random(seed).shuffle(perm)
    return [(perm[a], perm[b]) for a, b in pairs]


def test_hundred_task_diamond_chain_is_exact():
    ks = [1, 2, 3] * 8 + [2]  # 8 * 12 + 4 = 100 tasks
    pairs, n = diamond_chain(ks)
    assert n == 100
    graph = build_state_graph(precedence_spec(n, relabel(n, pairs, 1)))
    states, transitions, sequences = diamond_formulas(ks)
    assert graph.model.n_words == 2 and graph.keys.shape == (states, 2)
    assert (graph.n_states, graph.n_transitions) == (states, transitions)
    assert graph.count_sequences() == sequences == 2**9 * 6**8
    assert_layers_sorted(graph)
    assert len(graph.sequences(limit=5)) == 5
    assert solve(game_dag(graph)).tct == n


def test_two_interleaved_diamond_chains():
    # Two independent chains of 50 tasks: states multiply, sequences interleave.
    ks = [2] * 12 + [0]
    pairs_a, n_a = diamond_chain(ks)
    pairs_b, _ = diamond_chain(ks, first=n_a)
    n = 2 * n_a
    assert n == 100
    graph = build_state_graph(precedence_spec(n, relabel(n, pairs_a + pairs_b, 2)))
    s, t, q = diamond_formulas(ks)
    assert graph.n_states == s * s
    assert graph.n_transitions == 2 * t * s
    assert graph.count_sequences() == math.comb(n, n_a) * q * q
    # Every state is a downset: both orders of a pair of independent tasks meet again.
    done = graph.model.done_matrix(graph.keys)
    pairs = np.array(relabel(n, pairs_a + pairs_b, 2))
    assert not np.any(done[:, pairs[:, 1]] & ~done[:, pairs[:, 0]])
    assert np.array_equal(done.sum(axis=1), np.repeat(np.arange(n + 1), np.diff(graph.layer_ptr)))


def assert_layers_sorted(graph):
    """Within each layer the keys increase as integers (most significant word last)."""
    keys = graph.keys
    a, b = keys[:-1], keys[1:]
    greater = np.zeros(a.shape[0], dtype=bool)
    equal = np.ones(a.shape[0], dtype=bool)
    for w in range(keys.shape[1] - 1, -1, -1):
        greater |= equal & (b[:, w] > a[:, w])
        equal &= b[:, w] == a[:, w]
    inside = np.ones(a.shape[0], dtype=bool)
    inside[graph.layer_ptr[1:-1] - 1] = False  # pairs across a layer boundary
    assert greater[inside].all()


def random_poset(n, density, seed):
    """A random precedence graph on ``n`` tasks (pairs ``a -> b``, ``a`` earlier in a shuffled
    order) with each pair kept with probability ``density``."""
    rng = random.Random(seed)
    order = list(range(n))
    rng.shuffle(order)
    return [
        (order[i], order[j]) for i in range(n) for j in range(i + 1, n) if rng.random() < density
    ]


def closure(n, pairs):
    """Per task, the bitmasks of all its (transitive) predecessors and successors."""
    below = [0] * n
    succ = [[] for _ in range(n)]
    indeg = [0] * n
    for a, b in pairs:
        succ[a].append(b)
        indeg[b] += 1
    queue = [v for v in range(n) if indeg[v] == 0]
    for v in queue:  # Kahn: predecessors first
        for w in succ[v]:
            below[w] |= below[v] | (1 << v)
            indeg[w] -= 1
            if indeg[w] == 0:
                queue.append(w)
    above = [0] * n
    for w in range(n):
        for v in range(n):
            if below[w] >> v & 1:
                above[v] |= 1 << w
    return below, above


def count_downsets(n, pairs):
    """Downsets by the recursion N(P) = N(P - up(x)) + N(P - down(x)) (x in or out)."""
    below, above = closure(n, pairs)

    @cache
    def count(rest: int) -> int:
        if not rest:
            return 1
        x = (rest & -rest).bit_length() - 1
        without_x = rest & ~(above[x] | (1 << x))
        with_x = rest & ~(below[x] | (1 << x))
        return count(without_x) + count(with_x)

    return count((1 << n) - 1)


def count_linear_extensions(n, pairs):
    """Orders respecting the pairs, by a plain dict DP over downsets (Python ints)."""
    below, _ = closure(n, pairs)
    ways = {0: 1}
    for _ in range(n):
        nxt: dict[int, int] = {}
        for done, w in ways.items():
            for v in range(n):
                if not done >> v & 1 and below[v] & ~done == 0:
                    key = done | 1 << v
                    nxt[key] = nxt.get(key, 0) + w
        ways = nxt
    return ways[(1 << n) - 1]


@pytest.mark.parametrize(
    ("density", "states"), [(0.14, 68_638), (0.12, 435_772)], ids=["dense", "sparser"]
)
def test_seventy_task_random_graph_matches_independent_counts(density, states):
    n = 70
    pairs = random_poset(n, density, seed=7)
    assert len(pairs) > 250
    graph = build_state_graph(precedence_spec(n, pairs))
    assert graph.model.n_words == 2
    assert graph.n_states == count_downsets(n, pairs) == states
    if states < 100_000:  # the plain Python DP is slow beyond
        assert graph.count_sequences() == count_linear_extensions(n, pairs)
    # The states are exactly the downsets: none breaks a precedence.
    done = graph.model.done_matrix(graph.keys)
    p = np.array(pairs)
    assert not np.any(done[:, p[:, 1]] & ~done[:, p[:, 0]])
    assert np.unique(graph.keys, axis=0).shape[0] == graph.n_states
    assert_layers_sorted(graph)
    assert graph.key(graph.n_states - 1) == (1 << n) - 1


TOGGLE_OPS = [
    {"id": "a", "agents": {"R": 2}, "requires": {"R.bit": "hex"}},
    {"id": "x", "agents": {"H": 5}, "sets": {"R.bit": "cross"}},
    {"id": "b", "agents": {"R": 3}, "requires": {"R.bit": "cross"}},
    {"id": "y", "agents": {"H": 5}, "sets": {"R.bit": "hex"}},
    {"id": "g1", "agents": {"H": 1}, "sets": {"G.jaw": "closed"}},
    {"id": "g2", "agents": {"R": 4}, "requires": {"G.jaw": "closed"}, "sets": {"G.jaw": "half"}},
]
TOOLS = {"R.bit": {"initial": "hex", "change_time": 7}, "G.jaw": {"initial": "open"}}


def tool_spec(chain):
    """A chain of ``chain`` operations next to six operations that read and set two tools."""
    ops = [
        {"id": f"c{k}", "agents": {"H": 1}, "after": [f"c{k - 1}"] if k else []}
        for k in range(chain)
    ]
    data = {
        "agents": {"H": {"side": "human"}, "R": {"side": "robot"}},
        "tools": TOOLS,
        "operations": TOGGLE_OPS + ops,
    }
    return spec_from_dict(data, source="tools.yaml")


def brute_force_toggle_sequences():
    count = 0
    for perm in itertools.permutations(TOGGLE_OPS):
        tools = {"R.bit": "hex", "G.jaw": "open"}
        ok = True
        for op in perm:
            if any(tools[t] != v for t, v in op.get("requires", {}).items()):
                ok = False
                break
            tools.update(op.get("sets", {}))
        count += ok
    return count


def projected(graph, toggle_ids):
    """(done toggle ops, tools) of each state and the toggle transitions between them."""
    model = graph.model
    state = [
        (
            frozenset(set(model.done_ops(graph.keys[s])) & toggle_ids),
            str(model.tool_state(graph.keys[s])),
        )
        for s in range(graph.n_states)
    ]
    ids = graph.spec.op_ids
    changes = model.tool_changes(graph.keys[graph.src], graph.op)
    edges = {
        (state[s], ids[o], state[d], tuple(c))
        for s, o, d, c in zip(graph.src, graph.op, graph.dst, changes.tolist(), strict=True)
        if ids[o] in toggle_ids
    }
    return set(state), edges


def test_tool_bits_push_the_key_over_64_bits():
    # 62 operations: R.bit takes bit 62, G.jaw's two bits would straddle bit 64 and move to
    # the second word.
    wide = build_state_graph(tool_spec(56))
    small = build_state_graph(tool_spec(0))
    model = wide.model
    assert model.n_ops == 62 and model.n_words == 2
    assert model.tool_shift == (62, 64) and model.n_bits == 66
    assert wide.n_states == 57 * small.n_states
    toggles = brute_force_toggle_sequences()
    assert small.count_sequences() == toggles
    assert wide.count_sequences() == math.comb(62, 6) * toggles
    ids = frozenset(op["id"] for op in TOGGLE_OPS)
    assert projected(wide, ids) == projected(small, ids)
    labels = set(game_dag(wide, labels=True).node_labels)
    assert "start R.bit=hex G.jaw=open" in labels
    # Time costs read the tool fields of both words: the same optimum as without the chain.
    assert solve(game_dag(wide, cost="time")).tct == pytest.approx(
        solve(game_dag(small, cost="time")).tct + 56
    )


def same_graph(one, many):
    w = many.model.n_words
    assert one.model.n_words == 1 and w > 1
    assert np.array_equal(one.keys[:, 0], many.keys[:, 0])
    assert not many.keys[:, 1:].any()
    for name in ("parts", "layer_ptr", "src", "dst", "op"):
        assert np.array_equal(getattr(one, name), getattr(many, name)), name
    assert one.count_sequences() == many.count_sequences()
    assert one.sequences(limit=20) == many.sequences(limit=20)
    assert [one.label(s) for s in range(one.n_states)] == [
        many.label(s) for s in range(many.n_states)
    ]
    a, b = game_dag(one, cost="time"), game_dag(many, cost="time")
    assert np.array_equal(a.costs, b.costs) and a.operations == b.operations


@settings(max_examples=25, deadline=None)
@given(
    n=st.integers(1, 9),
    seed=st.integers(0, 10**6),
    density=st.floats(0.0, 0.5),
    words=st.integers(2, 3),
)
def test_single_and_multi_word_paths_agree(n, seed, density, words):
    spec = precedence_spec(n, random_poset(n, density, seed))
    one = build_state_graph(spec)
    many = build_state_graph(spec, model=operation_model(spec, _min_words=words))
    same_graph(one, many)


@pytest.mark.parametrize(
    ("spec", "relations"),
    [(tool_spec(3), None), (stack_spec(), stack_relations()), (stack_spec(), None)],
    ids=["tools", "geometry", "no-geometry"],
)
def test_single_and_multi_word_paths_agree_with_tools_and_parts(spec, relations):
    one = build_state_graph(spec, relations)
    many = build_state_graph(spec, relations, model=operation_model(spec, relations, _min_words=2))
    same_graph(one, many)


def test_wide_state_limit_is_one_line_and_early():
    with pytest.raises(ValueError, match="exceeds the limit of 1,000 states") as info:
        build_state_graph(precedence_spec(100, []), max_states=1000)
    message = str(info.value)
    assert "after layer 2 of 100" in message and "\n" not in message
    assert "raise max_states" in message


def test_keys_pack_and_unpack():
    model = operation_model(precedence_spec(130, []))
    assert model.n_words == 3
    values = [0, 1, 1 << 63, 1 << 64, (1 << 130) - 1, 12345 << 70]
    keys = model.pack(values)
    assert keys.shape == (6, 3)
    assert [model.unpack(k) for k in keys] == values
    done = model.done_matrix(keys)
    assert [sum(1 << int(i) for i in np.flatnonzero(r)) for r in done] == values
    assert model.is_complete(keys).tolist() == [False] * 4 + [True, False]
    assert model.has_op(keys, 64).tolist() == [False, False, False, True, True, False]


def test_progress_names_words_and_layers(capsys):
    build_state_graph(precedence_spec(70, [(k, k + 1) for k in range(69)]), progress=True)
    err = capsys.readouterr().err
    assert "70 operations, 70 key bits in 2 word(s)" in err
    assert "layer 70/70: 1 states, 1 transitions (71 states so far" in err
