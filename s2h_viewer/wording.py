"""Words for counts in what the app and the CLI say: "1 frame", "3 frames", "2 fixes"."""

from __future__ import annotations


def plural(word: str, n: int, plural_form: str | None = None) -> str:
    """``word`` for one, else its plural (``plural_form``, or ``word`` + "s")."""
    return word if n == 1 else (plural_form or word + "s")


def counted(n: int, word: str, plural_form: str | None = None) -> str:
    """'1 frame', '138 frames', '2 fixes' (``plural_form`` "fixes")."""
    return f"{n} {plural(word, n, plural_form)}"
