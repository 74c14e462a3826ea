"""Numba kernel of the contingency tables of many word labelings' pixel maps.

Private: call :class:`curiosity_cli.label.pixel_tables.PixelTables`; twin in
``tests/naive.py`` (``pixel_tables_naive``).
"""

from __future__ import annotations

from curiosity_cli._numba import njit


@njit
def pixel_tables_kernel(words, classes, pixels, word_labels, out):
    """Add ``pixels[e]`` to ``out[r, word_labels[words[e], r], classes[e]]`` for every entry ``e`` and labelling ``r``.

    ``words``, ``classes``, ``pixels`` (E,): the (word, reference class) pairs of a map's
    pixels and how many pixels each pair holds; ``word_labels`` (N, R) int; ``out`` (R, n_labels, n_classes) int64.
    """
    for e in range(words.shape[0]):
        w = words[e]
        c = classes[e]
        n = pixels[e]
        for r in range(word_labels.shape[1]):
            out[r, word_labels[w, r], c] += n
