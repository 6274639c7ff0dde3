"""Text for the terminal: user-provided strings shown inert, and one-line messages.

A scene name, a description or a path comes from a file the user (or someone else)
wrote. Printed raw, an ANSI escape in it can recolour or rewrite the terminal, a
newline can forge a second message, and through Rich a ``[/]`` is markup (a
``MarkupError`` that ends the run). :func:`plain` shows control characters as
Python escapes; :func:`markup` also escapes Rich markup. Imports nothing heavy
(Rich only inside :func:`markup`), so the CLI may use it before any handler loads.
"""

from __future__ import annotations

import re
import sys

__all__ = ["error_line", "markup", "plain", "warn"]

# C0 controls (newline and tab too: a message stays one line), DEL, C1 controls, and
# the bidirectional overrides and isolates that reorder how text is displayed.
_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f\u061c\u200e\u200f\u202a-\u202e\u2066-\u2069]")


def _escape(match: re.Match[str]) -> str:
    code = ord(match.group())
    return f"\\x{code:02x}" if code <= 0xFF else f"\\u{code:04x}"


def plain(text: object) -> str:
    """``str(text)`` with every control character shown as an escape (``\\x1b``,
    ``\\n``, ``\\u202e``): safe to print, always one line."""
    return _CONTROL.sub(_escape, str(text))


def markup(text: object) -> str:
    """:func:`plain`, with Rich markup escaped: a literal in a Rich table or print."""
    from rich.markup import escape  # noqa: PLC0415 - Rich only where a table is drawn

    return escape(plain(text))


def error_line(error: BaseException) -> str:
    """``Type: message`` of an exception on one line (whitespace runs, newlines
    included, become one space), control characters shown inert."""
    message = " ".join(str(error).split()) or "(no message)"
    return plain(f"{type(error).__name__}: {message}")


def warn(message: object) -> None:
    """One ``warning: ...`` line on stderr (``message`` shown with :func:`plain`)."""
    print(f"warning: {plain(message)}", file=sys.stderr)
