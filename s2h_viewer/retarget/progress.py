"""Progress and cancellation from inside long computations (ASM-Opt's steps, a comparison's stages)
without threading a callback through every method's signature: a caller installs a hook for the
current thread (``reporting``); the work calls ``report(fraction)``, and the hook may raise
``Cancelled`` to stop it between chunks."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar

_hook: ContextVar[Callable[[float], None] | None] = ContextVar("s2h_progress_hook", default=None)


class Cancelled(Exception):
    """The user cancelled the running work."""


@contextmanager
def reporting(hook: Callable[[float], None]) -> Iterator[None]:
    """Route ``report`` calls made in this thread (context) to ``hook(fraction)`` while the block runs."""
    token = _hook.set(hook)
    try:
        yield
    finally:
        _hook.reset(token)


def report(fraction: float) -> None:
    """How far (0..1) the current piece of work is; raises ``Cancelled`` when the hook says so."""
    hook = _hook.get()
    if hook is not None:
        hook(min(max(fraction, 0.0), 1.0))


@contextmanager
def stage(start: float, end: float) -> Iterator[None]:
    """Inside the block, ``report(f)`` means ``start + f * (end - start)`` of the enclosing work."""
    outer = _hook.get()
    if outer is None:
        yield
        return
    with reporting(lambda f: outer(start + f * (end - start))):
        yield
