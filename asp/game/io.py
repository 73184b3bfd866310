"""Reading and writing game DAGs: JSON (``asmplan-dag/1``) and GraphML, chosen by extension.

``asmplan-dag/1`` is one JSON object::

    {
      "format": "asmplan-dag/1",
      "start": 0, "end": 9,                  # node ids
      "cost_model": "steps",                 # or "time"
      "turn_model": "alternate",
      "nodes": [{"id": 0, "label": "..."}],  # label optional
      "edges": [{"source": 0, "target": 1, "cost": 1,
                 "side": "any", "operation": "1.2", "agent": "H"}],
      "metadata": {...}                      # free-form provenance
    }

Edge keys other than ``source`` and ``target`` are optional (cost 1, side ``any``).
A GraphML file written by plain networkx works: start is the one node without in-edges,
end the one without out-edges, edge attribute ``cost`` (default 1). Parallel edges (a
multigraph) are kept, each a move of its own, exactly as two JSON edges between the same
nodes are: the cooperative TCT takes the cheapest, a maximising human the dearest. A DAG
with parallel edges is written as a multigraph, so GraphML round-trips every move.
"""

from __future__ import annotations

import io
import json
import os
from pathlib import Path

import networkx as nx

from asp.atomic import write_bytes, write_text
from asp.errors import FormatError, GraphError
from asp.game.dag import MAX_COST, SIDE_NAMES, GameDAG, from_edges, from_networkx, side_from_name
from asp.game.turns import ALTERNATE
from asp.numbers import json_number, plain
from cad.numbers import plain_number
from cad.texts import bounded

FORMAT = "asmplan-dag/1"
JSON_SUFFIXES = (".json",)
GRAPHML_SUFFIXES = (".graphml", ".xml")
READABLE_EDGES = 10_000
"""Graphs up to this many edges are written as indented JSON."""


def dag_to_dict(dag: GameDAG) -> dict:
    """The ``asmplan-dag/1`` object of ``dag``."""
    nodes = []
    for i, nid in enumerate(dag.node_ids):
        node = {"id": plain(nid)}
        if dag.node_labels is not None:
            node["label"] = dag.node_labels[i]
        nodes.append(node)
    src = dag.sources
    edges = []
    for e in range(dag.n_edges):
        edge = {
            "source": plain(dag.node_ids[src[e]]),
            "target": plain(dag.node_ids[int(dag.targets[e])]),
            "cost": json_number(dag.costs[e]),
            "side": SIDE_NAMES[int(dag.sides[e])],
        }
        if dag.operations is not None:
            edge["operation"] = dag.operations[e]
        if dag.agents is not None:
            edge["agent"] = dag.agents[e]
        edges.append(edge)
    return {
        "format": FORMAT,
        "start": plain(dag.node_ids[dag.start]),
        "end": plain(dag.node_ids[dag.end]),
        "cost_model": dag.cost_model,
        "turn_model": dag.turn_model,
        "nodes": nodes,
        "edges": edges,
        "metadata": dag.metadata,
    }


def dag_from_dict(data: dict, source: str = "<dict>") -> GameDAG:
    """Build a :class:`GameDAG` from an ``asmplan-dag/1`` object; ``source`` names it in errors."""
    if not isinstance(data, dict):
        raise FormatError(f"{source}: expected a JSON object, got {type(data).__name__}")
    fmt = data.get("format", FORMAT)
    if fmt != FORMAT:
        raise FormatError(f"{source}: expected format {FORMAT!r}, got {fmt!r}")
    for key in ("nodes", "edges"):
        if not isinstance(data.get(key), list):
            raise FormatError(f"{source}: key {key!r} must be a list")
    if data.get("turn_model", ALTERNATE.name) != ALTERNATE.name:
        raise GraphError(f"{source}: turn_model must be 'alternate', got {data['turn_model']!r}")
    try:
        ids = [n["id"] if isinstance(n, dict) else n for n in data["nodes"]]
        labels = [n.get("label") if isinstance(n, dict) else None for n in data["nodes"]]
        edges = data["edges"]
        pairs = [(e["source"], e["target"]) for e in edges]
        _check_ids(source, "node id", ids)
        _check_ids(source, "edge end", [x for pair in pairs for x in pair])
        _check_ids(
            source, "start/end", [data[k] for k in ("start", "end") if data.get(k) is not None]
        )
        _check_texts(source, "node label", labels)
        _check_texts(source, "edge operation", [e.get("operation") for e in edges])
        _check_texts(source, "edge agent", [e.get("agent") for e in edges])
        costs = [_cost(source, k, e.get("cost", 1)) for k, e in enumerate(edges)]
        sides = [side_from_name(e.get("side", "any")) for e in edges]
        has_ops = any("operation" in e for e in edges)
        has_agents = any("agent" in e for e in edges)
        return from_edges(
            ids,
            pairs,
            start=data.get("start"),
            end=data.get("end"),
            costs=costs,
            sides=sides,
            operations=[str(e.get("operation", "")) for e in edges] if has_ops else None,
            agents=[str(e.get("agent", "")) for e in edges] if has_agents else None,
            node_labels=labels if all(x is not None for x in labels) else None,
            cost_model=data.get("cost_model", "steps"),
            metadata=data.get("metadata") or {},
        )
    except (KeyError, TypeError, AttributeError) as exc:
        raise FormatError(f"{source}: malformed graph ({type(exc).__name__}: {exc})") from None
    except FormatError:
        raise  # it names the file already
    except OverflowError:
        raise GraphError(f"{source}: a cost is too large (the limit is {MAX_COST:g})") from None
    except ValueError as exc:
        raise GraphError(f"{source}: {exc}") from None


def _check_ids(source: str, what: str, values: list) -> None:
    """Node ids are strings or integers, as written: a float, bool or null id would match
    another id silently (``1.0`` is ``1``, ``true`` is ``1``) and is refused."""
    for value in values:
        if isinstance(value, bool) or not isinstance(value, int | str):
            raise FormatError(
                f"{source}: {what} {json.dumps(value)}: expected a string or an integer"
            )
    _check_texts(source, what, values)


def _cost(source: str, k: int, value) -> float:
    """Edge ``k``'s cost as written: a number (never a bool), else refused naming the edge."""
    x = plain_number(value)
    if x is None:
        raise FormatError(
            f"{source}: edge {k + 1} cost {json.dumps(value)[:40]}: expected a number"
        )
    return x


def _check_texts(source: str, what: str, values: list) -> None:
    """Every text at most a name long (:func:`cad.texts.bounded`)."""
    for k, value in enumerate(values):
        if isinstance(value, str):
            try:
                bounded(value, f"{source}: {what} {k + 1}")
            except ValueError as exc:
                raise FormatError(str(exc)) from None


class _DuplicateKey(ValueError):
    """A key written twice in one JSON object (the reader would keep the last silently)."""


def _unique_keys(pairs: list[tuple[str, object]]) -> dict:
    out: dict = {}
    for key, value in pairs:
        if key in out:
            raise _DuplicateKey(json.dumps(key)[:60])
        out[key] = value
    return out


def load_dag(path: str | os.PathLike[str]) -> GameDAG:
    """Load a game DAG from ``.json`` (``asmplan-dag/1``) or ``.graphml``.

    Raises ``FileNotFoundError`` or ``ValueError`` with a message naming the file.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file")
    suffix = path.suffix.lower()
    if suffix in JSON_SUFFIXES:
        try:
            data = json.loads(path.read_text(encoding="utf-8"), object_pairs_hook=_unique_keys)
        except _DuplicateKey as exc:
            raise FormatError(f"{path}: duplicate key {exc} in a JSON object") from None
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise FormatError(f"{path}: malformed JSON ({exc})") from None
        except RecursionError:
            raise FormatError(f"{path}: malformed JSON (nested too deeply)") from None
        return dag_from_dict(data, source=str(path))
    if suffix in GRAPHML_SUFFIXES:
        try:
            g = nx.read_graphml(path)
        except Exception as exc:  # networkx raises several XML error types
            raise FormatError(f"{path}: malformed GraphML ({' '.join(str(exc).split())})") from None
        if not g.is_directed():
            raise GraphError(f"{path}: expected a directed graph")
        try:
            dag = from_networkx(g)
            for what, texts in (
                ("node id", dag.node_ids),
                ("node label", dag.node_labels),
                ("edge operation", dag.operations),
                ("edge agent", dag.agents),
            ):
                _check_texts(str(path), what, list(texts or ()))
            return dag
        except FormatError:
            raise  # it names the file already
        except OverflowError:
            raise GraphError(f"{path}: a cost is too large (the limit is {MAX_COST:g})") from None
        except ValueError as exc:
            raise GraphError(f"{path}: {exc}") from None
    raise FormatError(f"{path}: unknown graph format {suffix!r}: expected .json or .graphml")


def save_dag(dag: GameDAG, path: str | os.PathLike[str]) -> Path:
    """Save ``dag`` atomically as ``.json`` (``asmplan-dag/1``) or ``.graphml``."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in JSON_SUFFIXES:
        # Indented for a person to read; compact above that size (8x faster, 30% smaller).
        if dag.n_edges <= READABLE_EDGES:
            text = json.dumps(dag_to_dict(dag), indent=1, allow_nan=False)
        else:
            text = json.dumps(dag_to_dict(dag), separators=(",", ":"), allow_nan=False)
        return write_text(path, text + "\n")
    if suffix in GRAPHML_SUFFIXES:
        g = dag.to_networkx()
        g.graph["start"] = str(g.graph["start"])
        g.graph["end"] = str(g.graph["end"])
        buffer = io.BytesIO()
        nx.write_graphml(g, buffer)
        return write_bytes(path, buffer.getvalue())
    raise FormatError(f"{path}: unknown graph format {suffix!r}: expected .json or .graphml")
