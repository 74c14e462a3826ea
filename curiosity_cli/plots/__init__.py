"""Matplotlib figures. Modules here import matplotlib lazily, inside their functions."""

from __future__ import annotations

import contextlib
import re

#: Matplotlib's warning of a character its fonts cannot draw, e.g. an emoji in a class name.
_MISSING_GLYPH = re.compile(r"Glyph (\d+) .*missing from font")


@contextlib.contextmanager
def missing_glyphs_noted():
    """Matplotlib's warnings of characters its fonts lack, as one note on stderr when the block ends.

    Matplotlib warns once per character and drawing (a PNG and a PDF of one figure give
    two), each with a source path; the user needs one line saying which characters show
    as empty boxes. Every other warning passes on as it came.
    """
    import warnings

    from curiosity_cli.files import note

    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            yield
    finally:  # the filters are the caller's again: what passes on meets them
        missing = set()
        for warning in caught:
            found = _MISSING_GLYPH.match(str(warning.message))
            if found is not None and issubclass(warning.category, UserWarning):
                missing.add(chr(int(found[1])))
            else:
                warnings.warn_explicit(
                    warning.message, warning.category, warning.filename, warning.lineno, source=warning.source
                )
        if missing:
            shown = ", ".join(f"{char} (U+{ord(char):04X})" for char in sorted(missing))
            note(f"the figure's font has no {shown}: drawn as an empty box")
