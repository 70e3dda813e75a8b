"""How many threads torch uses for the small batched optimisations (ASM-Opt, the contact fit)."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import torch


@contextmanager
def torch_threads(n: int) -> Iterator[None]:
    """Run torch on ``n`` threads, then restore: small batches gain nothing from a second thread, and
    threads that spin waiting for each other are many times slower on a busy machine."""
    before = torch.get_num_threads()
    torch.set_num_threads(n)
    try:
        yield
    finally:
        torch.set_num_threads(before)
