"""Progress and cancellation of long work: the one way a retarget (or a comparison, or the annotation
solver) says how far it is, and the one place it can be stopped. The CLI's progress bars and the app's
dialogs and retarget queue all listen the same way: a caller installs a hook for the current thread
(``with reporting(hook)``); the work calls ``report(fraction)`` between chunks and splits itself into
parts with ``stage``; the hook hears ``(fraction of the whole, what is running)`` and may raise
``Cancelled`` to stop the work at that report. Without a hook, reports cost nothing."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass

#: hook(fraction of the whole work 0..1, what is running: the innermost stage's name, "" if none)
Hook = Callable[[float, str], None]


class Cancelled(Exception):
    """The user cancelled the running work."""


@dataclass(frozen=True)
class _Span:
    """The share [start, end] of the hooked work that ``report(0..1)`` covers now, and its name."""

    hook: Hook
    start: float = 0.0
    end: float = 1.0
    what: str = ""


_span: ContextVar[_Span | None] = ContextVar("s2h_progress_span", default=None)


@contextmanager
def reporting(hook: Hook) -> Iterator[None]:
    """Route ``report`` calls made in this thread (context) to ``hook`` while the block runs."""
    token = _span.set(_Span(hook))
    try:
        yield
    finally:
        _span.reset(token)


def report(fraction: float, what: str | None = None) -> None:
    """How far (0..1) the current piece of work is (``what``: name it); raises ``Cancelled`` when the
    hook says so."""
    span = _span.get()
    if span is not None:
        fraction = min(max(fraction, 0.0), 1.0)
        span.hook(span.start + fraction * (span.end - span.start), span.what if what is None else what)


@contextmanager
def stage(start: float, end: float, what: str | None = None) -> Iterator[None]:
    """Inside the block, ``report(f)`` means ``start + f * (end - start)`` of the enclosing work, and the
    work is named ``what`` (else the enclosing name)."""
    outer = _span.get()
    if outer is None:
        yield
        return
    width = outer.end - outer.start
    token = _span.set(_Span(outer.hook, outer.start + start * width, outer.start + end * width,
                            outer.what if what is None else what))
    try:
        yield
    finally:
        _span.reset(token)
