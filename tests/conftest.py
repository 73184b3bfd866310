"""Shared test fixtures and paths."""

from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO.parent / "shared" / "data"


@pytest.fixture
def shared_data() -> Path:
    """The public benchmark data beside the repository (never copied into it)."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"shared data not found at {SHARED_DATA}")
    return SHARED_DATA


@pytest.fixture
def deterministic_torch():
    """One torch thread and deterministic kernels, so the same seed trains the same."""
    import torch

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    torch.use_deterministic_algorithms(True)
    yield
    torch.use_deterministic_algorithms(False)
    torch.set_num_threads(threads)


@pytest.fixture
def step_deflections(monkeypatch) -> list:
    """The ``tol_linear`` (mm) of every STEP tessellation cascadio does from now on."""
    cascadio = pytest.importorskip("cascadio")
    seen = []
    convert = cascadio.step_to_glb

    def spy(*args, **kwargs):
        seen.append(kwargs.get("tol_linear"))
        return convert(*args, **kwargs)

    monkeypatch.setattr(cascadio, "step_to_glb", spy)
    return seen
