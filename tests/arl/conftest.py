"""Fixtures of the arl tests."""

import pytest
import torch


@pytest.fixture
def deterministic_torch():
    """One torch thread and deterministic kernels, so the same seed trains the same."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    torch.use_deterministic_algorithms(True)
    yield
    torch.use_deterministic_algorithms(False)
    torch.set_num_threads(threads)
