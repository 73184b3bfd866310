"""The build frame of a generated spec: a candidate frame that cannot be read is passed over."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from asp.fromcad import framing
from cad.errors import GeometryError
from cad.frame import Candidate


def test_a_frame_whose_relations_fail_is_passed_over(monkeypatch):
    relations = SimpleNamespace(tt=np.zeros((2, 2, 6), dtype=bool), parts=("a", "b"))
    spec = SimpleNamespace(generated=True, frame=None, base_part="a")
    decided = SimpleNamespace(spec=spec, relations=relations)
    turned = Candidate(rotation=np.eye(3), direction=(1.0, 0.0, 0.0), parts=("a",))
    monkeypatch.setattr(framing, "candidate_frames", lambda geometry, parts: [turned])

    def in_frame(rotation):
        raise GeometryError("parts 'a' and 'b' interpenetrate by about 1.4 mm")

    choice, chosen = framing.choose_frame(decided, None, in_frame)
    assert chosen is None and choice.rotation is None
    assert choice.failed == 1
    assert "parts overlap there that fit in the file's frame" in choice.text
