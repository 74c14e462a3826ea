"""Contingency tables of many labelings of a map's pixels against one reference, without drawing the pixel maps.

Every pixel takes the label of one word (:func:`~curiosity_cli.label.sampling.pixel_words`),
so the table of a word labelling's pixel map against a reference labelling of the pixels
(the human labels, or Z_b) only needs, once per map, how many pixels each (word, reference
class) pair holds. Labelling a map compares hundreds of chains at each checkpoint with two
references: this gives the same integers as
:func:`~curiosity_cli.evaluate.information.contingency` of each drawn pixel map, without
drawing any.
"""

from __future__ import annotations

import numpy as np

from curiosity_cli.errors import ParameterError


class PixelTables:
    """The contingency tables of word labelings' pixel maps against ``reference``.

    Parameters
    ----------
    pixel_words : (H, W) int ndarray
        The word whose label each pixel takes, ``0 .. N - 1``.
    reference : (H, W) int ndarray
        A labelling of the same pixels, ``0 .. n_classes - 1``.
    n_classes : int
        Its number of labels.

    Raises
    ------
    ParameterError
        The shapes differ, or a reference label is out of range.
    """

    def __init__(self, pixel_words: np.ndarray, reference: np.ndarray, n_classes: int):
        pixel_words, reference = np.asarray(pixel_words), np.asarray(reference)
        if reference.shape != pixel_words.shape:
            raise ParameterError(f"reference: got shape {reference.shape}, expected the pixels' {pixel_words.shape}")
        if reference.size and (reference.min() < 0 or reference.max() >= n_classes):
            raise ParameterError(f"reference: labels {reference.min()} .. {reference.max()}, expected 0 .. {n_classes - 1}")
        pairs, pixels = np.unique(pixel_words.astype(np.int64).ravel() * n_classes + reference.ravel(), return_counts=True)
        self.n_classes = n_classes
        self._words = pairs // n_classes
        self._classes = pairs % n_classes
        self._pixels = pixels.astype(np.int64)
        self._n_words = int(self._words.max()) + 1 if pairs.size else 0

    def tables(self, word_labels: np.ndarray, n_labels: int, kept: np.ndarray | None = None) -> np.ndarray:
        """(R, n_labels, n_classes) int64: for each column ``r`` of ``word_labels``, the table of its pixel map against the reference.

        ``tables(word_labels, n)[r]`` is ``contingency(word_labels[:, r][pixel_words],
        reference, n, n_classes)``; with ``kept``, of only the pixels whose word is kept
        in column ``r`` (``kept[pixel_words, r]``).

        Parameters
        ----------
        word_labels : (N, R) int ndarray
            R labelings of the map's words, ``0 .. n_labels - 1``.
        n_labels : int
        kept : (N, R) bool ndarray, optional
            Which words' pixels each column's table counts; default all.

        Raises
        ------
        ParameterError
            Fewer words than the pixels take labels from, a label out of range, or
            ``kept`` not of ``word_labels``' shape.
        """
        from curiosity_cli.label._table_kernels import pixel_tables_kernel

        word_labels = np.asarray(word_labels)
        if word_labels.ndim != 2 or word_labels.shape[0] < self._n_words:
            raise ParameterError(f"word_labels: got shape {word_labels.shape}, expected (N >= {self._n_words}, R)")
        if word_labels.size and (word_labels.min() < 0 or word_labels.max() >= n_labels):
            raise ParameterError(f"word_labels: labels {word_labels.min()} .. {word_labels.max()}, expected 0 .. {n_labels - 1}")
        if kept is None:
            out = np.zeros((word_labels.shape[1], n_labels, self.n_classes), np.int64)
            pixel_tables_kernel(self._words, self._classes, self._pixels, word_labels, out)
            return out
        kept = np.asarray(kept, bool)
        if kept.shape != word_labels.shape:
            raise ParameterError(f"kept: got shape {kept.shape}, expected word_labels' {word_labels.shape}")
        # a word left out takes an extra label, n_labels, whose row of each table is then dropped
        dropped = np.where(kept, word_labels, n_labels)
        out = np.zeros((word_labels.shape[1], n_labels + 1, self.n_classes), np.int64)
        pixel_tables_kernel(self._words, self._classes, self._pixels, dropped, out)
        return out[:, :n_labels]
