"""Time writing a concurrent plan's ``policy`` object (issue 23) and check it byte for byte.

``capture``: plan a product with the CLI (``asmplan plan FILE ARGS...``) and pickle the
concurrent game and its policy table as :func:`asmplan.pipeline.plan_document` hands them
to :func:`asp.concurrent.describe.policy_names`. ``time``: load a pickle, build the policy
object (``policy_names`` then :func:`asmplan.planfile.concurrent_policy_object`), print its
CPU seconds and the SHA-256 of ``json.dumps(policy, sort_keys=True)``: the hash must not
change when the code that writes the policy does.

Usage::

    python benchmarks/plan_policy_write.py capture OUT.pkl FILE [plan args...]
    python benchmarks/plan_policy_write.py time OUT.pkl [OUT2.pkl ...]
"""

from __future__ import annotations

import hashlib
import json
import pickle
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this checkout first


def capture(out: str, argv: list[str]) -> None:
    """Plan ``argv`` with the CLI, pickling ``(game, table)`` of the concurrent policy."""
    import asp.concurrent.describe as describe
    from asmplan.cli import main

    original = describe.policy_names

    def keep(game, table):
        with open(out, "wb") as f:
            pickle.dump((game, table), f, protocol=pickle.HIGHEST_PROTOCOL)
        return original(game, table)

    describe.policy_names = keep
    with tempfile.TemporaryDirectory() as folder:
        sys.argv = ["asmplan", "plan", *argv, "-o", folder]
        try:
            main()
        except SystemExit as exc:
            if exc.code:
                raise


def policy_of(game, table) -> tuple[dict, float]:
    """The policy object of ``(game, table)`` and the CPU seconds it took."""
    from asmplan.planfile import concurrent_policy_object
    from asp.concurrent.describe import policy_names

    t0 = time.process_time()
    policy = concurrent_policy_object(policy_names(game, table), table)
    return policy, time.process_time() - t0


def main() -> None:
    if sys.argv[1] == "capture":
        capture(sys.argv[2], sys.argv[3:])
        return
    for path in sys.argv[2:]:
        with open(path, "rb") as f:
            game, table = pickle.load(f)
        policy, seconds = policy_of(game, table)
        digest = hashlib.sha256(json.dumps(policy, sort_keys=True).encode()).hexdigest()
        print(
            f"{path}: {table.node.size:,} states, {table.edge.size:,} moves, "
            f"{seconds:.2f} s CPU, sha256 {digest[:16]}"
        )


if __name__ == "__main__":
    main()
