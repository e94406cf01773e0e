"""Fixtures of the generator tests."""

import pytest


@pytest.fixture(scope="module")
def torch_one_thread():
    """The tiny diffusion models are small; keep the shared 2-core machine free (restored after)."""
    import torch

    n = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(n)
