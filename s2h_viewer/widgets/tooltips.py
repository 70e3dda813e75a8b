"""Long tooltips wrapped: Qt draws a plain-text tooltip on one line, which ran off the screen's edge for a
target's frame warning; rich text it wraps to the screen."""

from __future__ import annotations

from html import escape


def wrapped(text: str) -> str:
    """``text`` as a tooltip Qt wraps (a rich-text paragraph, its characters escaped, a new line where it has one)."""
    return f"<p>{escape(text).replace(chr(10), '<br>')}</p>"
