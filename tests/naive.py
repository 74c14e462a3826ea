"""Slow, obviously-correct twins of every numba kernel, for the tests to compare against.

Each function says plainly what its fast counterpart computes, with plain loops, float64
or unpacked bits, and textbook library calls.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

# --------------------------------------------------------------------------- textons
# Twins of curiosity_cli/words/_texton_kernels.py and the MR8 filtering in filterbank.py.

def nearest_centres_naive(vectors: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """Twin of ``_texton_kernels.nearest_centres_kernel``: float64 brute force.

    For each row, the squared distance to every centre, summed over dimensions from the
    first upward in float64, and the first index of the smallest (``np.argmin``).
    """
    v64 = np.asarray(vectors, dtype=np.float32).astype(np.float64)
    c64 = np.asarray(centres, dtype=np.float32).astype(np.float64)
    out = np.empty(len(v64), np.int32)
    for n, v in enumerate(v64):
        dist = np.zeros(len(c64))
        for j in range(c64.shape[1]):
            dist += (v[j] - c64[:, j]) ** 2
        out[n] = np.argmin(dist)
    return out


def mr8_responses_naive(image: np.ndarray, filters, standardise: bool = True) -> np.ndarray:
    """Twin of ``filterbank.mr8_responses``: explicit sliding-window correlation in float64.

    The image is mirrored with ``np.pad(mode="symmetric")`` (``cba|abc``, OpenCV's
    ``BORDER_REFLECT``), then each output pixel is the sum of kernel times the window
    centred on it. (Not ``scipy.ndimage.correlate``: with ``mode="reflect"`` it returns
    garbage once the kernel overhangs the image several times, e.g. a 49 x 49 kernel on a
    5 x 7 image, in scipy 1.17.)
    """
    image = np.asarray(image, dtype=np.float64)
    if standardise:
        image = image - image.mean()
        if image.std() > 0:
            image = image / image.std()
    support = filters.support
    windows = sliding_window_view(np.pad(image, support // 2, mode="symmetric"), (support, support))

    def correlate(kernel):
        return np.einsum("rcij,ij->rc", windows, kernel.astype(np.float64))

    channels = []
    for bank, absolute in ((filters.edge, True), (filters.bar, False)):
        for scale in range(bank.shape[0]):
            per_orientation = [correlate(kernel) for kernel in bank[scale]]
            if absolute:
                per_orientation = [np.abs(r) for r in per_orientation]
            channels.append(np.max(per_orientation, axis=0))
    channels.append(correlate(filters.gaussian))
    channels.append(correlate(filters.log))
    return np.stack(channels, axis=-1)


def normalise_responses_naive(responses: np.ndarray, scale: float = 0.03) -> np.ndarray:
    """Twin of ``filterbank.normalise_responses``, one vector at a time."""
    responses = np.asarray(responses, dtype=np.float64)
    flat = responses.reshape(-1, responses.shape[-1])
    out = np.zeros_like(flat)
    for i, f in enumerate(flat):
        length = math.sqrt(sum(x * x for x in f))
        if length > 0:
            out[i] = f * math.log(1 + length / scale) / length
    return out.reshape(responses.shape)


# --------------------------------------------------------------------------- ORB words
# Twins of curiosity_cli/words/_hamming_kernels.py. Pure numpy on unpacked bits: a Hamming
# distance is the number of differing bits. Arguments take the public layout
# ((N, 32) uint8 descriptors) rather than the kernels' 64-bit views.

BLOCK = 1024  # the kernels' block size for k-means++ block sums


def hamming_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N, K) int64 Hamming distances between rows of (N, 32) and (K, 32) uint8."""
    bits_a = np.unpackbits(a, axis=1).astype(np.int64)
    bits_b = np.unpackbits(b, axis=1).astype(np.int64)
    return (bits_a[:, None, :] != bits_b[None, :, :]).sum(axis=2)


def nearest_words(descriptors: np.ndarray, vocabulary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Twin of ``nearest_words``: (index, distance), ties to the lowest index."""
    distances = hamming_matrix(descriptors, vocabulary)
    index = np.argmin(distances, axis=1)  # argmin returns the first minimum
    return index.astype(np.int32), distances[np.arange(len(descriptors)), index].astype(np.int32)


def lower_min_distance(
    descriptors: np.ndarray, centre: np.ndarray, min_sq: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Twin of ``_lower_min_distance``: (new min_sq, block sums)."""
    sq = hamming_matrix(descriptors, centre[None, :])[:, 0] ** 2
    new = np.minimum(min_sq, sq)
    n_blocks = -(-len(new) // BLOCK)
    sums = np.array([new[b * BLOCK : (b + 1) * BLOCK].sum() for b in range(n_blocks)], np.int64)
    return new, sums


def sample_weighted(weights: np.ndarray, target: int) -> int:
    """Twin of ``_sample_weighted``: first i with weights[:i + 1].sum() > target."""
    for i in range(len(weights)):
        if weights[: i + 1].sum() > target:
            return i
    raise AssertionError("target not below the total")


def kmeanspp_seeds(descriptors: np.ndarray, first: int, uniforms: np.ndarray, k: int) -> list[int]:
    """Twin of ``kmeanspp_seeds``: the seed indices (fewer than k if the rows run out)."""
    distances = hamming_matrix(descriptors, descriptors)
    seeds = [first]
    while len(seeds) < k:
        weights = distances[:, seeds].min(axis=1) ** 2
        total = int(weights.sum())
        if total == 0:
            break
        target = min(int(uniforms[len(seeds) - 1] * total), total - 1)
        seeds.append(int(np.searchsorted(np.cumsum(weights), target, side="right")))
    return seeds


def bit_counts(descriptors: np.ndarray, labels: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Twin of ``bit_counts``: (k, 256) set-bit counts per centre, (k,) member counts."""
    bits = np.unpackbits(descriptors, axis=1)
    counts = np.zeros((k, bits.shape[1]), np.int64)
    sizes = np.zeros(k, np.int64)
    for c in range(k):
        members = bits[labels == c]
        counts[c] = members.sum(axis=0)
        sizes[c] = len(members)
    return counts, sizes


# --------------------------------------------------------------------------- topic model
# Twins of curiosity_cli/topics/_rng.py, _sampler.py, _gibbs_kernels.py and _perplexity_kernels.py.
# They keep only words and topics (per cell, in a dict) and recount whatever they need
# from the topics every time they need it: nothing is cached, so nothing can go stale.
# The float32 arithmetic of a draw is written out exactly as the kernels do it, because
# the tests compare topics bit for bit.

from dataclasses import dataclass  # noqa: E402  (kept with the section that uses it)

MASK64 = 2**64 - 1
GOLDEN = 0x9E3779B97F4A7C15


def mix(z: int) -> int:
    """splitmix64's output function on Python ints."""
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK64
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK64
    return z ^ (z >> 31)


class Stream:
    """splitmix64 started at ``mix(key ^ mix(counter ^ cell * GOLDEN))``."""

    def __init__(self, key: int, counter: int, cell: int):
        self.state = mix(key ^ mix((counter & MASK64) ^ ((cell * GOLDEN) & MASK64)))

    def bits(self) -> int:
        self.state = (self.state + GOLDEN) & MASK64
        return mix(self.state)


def unit32(bits: int) -> np.float32:
    return np.float32(bits >> 40) * np.float32(2.0**-24)


def unit64(bits: int) -> float:
    return (bits >> 11) * 2.0**-53


def below(bits: int, n: int) -> int:
    return ((bits >> 32) * n) >> 32


def lane_draw(p: np.ndarray, bits: int) -> int:
    """Inverse-CDF draw from float32 weights ``p`` (length a multiple of 8) in lane order.

    Topics are visited lane by lane (lane j: topics j, j + 8, ...). All sums are float32,
    each lane summed from 0 in topic order, the total as lane 0 + lane 1 + ... + lane 7.
    """
    p = np.asarray(p, np.float32)
    lanes = [np.float32(0.0)] * 8
    for k in range(len(p)):
        lanes[k % 8] = np.float32(lanes[k % 8] + p[k])
    total = np.float32(0.0)
    for s in lanes:
        total = np.float32(total + s)
    target = np.float32(unit32(bits) * total)
    positive = [j for j in range(8) if lanes[j] > 0]
    lane, before = positive[-1], np.float32(0.0)  # the last positive lane if rounding runs past
    for j in positive:
        if target < np.float32(before + lanes[j]):
            lane = j
            break
        before = np.float32(before + lanes[j])
    rest = np.float32(target - before)
    members = [k for k in range(lane, len(p), 8) if p[k] > 0]
    running = np.float32(0.0)
    for k in members:
        running = np.float32(running + p[k])
        if rest < running:
            return k
    return members[-1]


@dataclass
class NaiveModel:
    """The state a twin needs: words and topics of each observed cell, in a dict."""

    n_topics: int
    vocabulary_size: int
    table: np.ndarray
    alpha: float
    beta: float
    key: int
    counter: int
    words: dict
    topics: dict
    order: list
    times: list
    frozen: np.ndarray | None = None  # (V, K) frozen word-topic counts
    allowed: np.ndarray | None = None  # (V, K) bool: the topics each word may take (FrozenChains' allowed); None: all
    free_stream: int | None = None  # the first stream id of no cell: n_cells as the model was made

    def __post_init__(self):
        if self.free_stream is None:
            self.free_stream = self.n_cells

    @classmethod
    def of(cls, model) -> NaiveModel:
        """A twin state equal to a TopicModel's current state."""
        cells = [int(c) for c in model.observed_cells()]
        return cls(
            n_topics=model.n_topics,
            vocabulary_size=model.vocabulary_size,
            table=np.array(model.neighbours),
            alpha=model.alpha,
            beta=model.beta,
            key=mix(model.seed),
            counter=model.full_state()["counter"],
            words={c: model.cell_words(c).astype(np.int64) for c in cells},
            topics={c: model.topics([c]).astype(np.int64) for c in cells},
            order=cells,
            times=[int(t) for t in model.observation_times()],
            frozen=model.topic_word_counts() if model.frozen else None,
            free_stream=int(model._free_stream),
        )

    @property
    def n_cells(self) -> int:
        return self.table.shape[0]

    @property
    def padded(self) -> int:
        return -(-self.n_topics // 8) * 8

    def topics_in_cell_order(self) -> np.ndarray:
        cells = sorted(self.topics)
        return np.concatenate([self.topics[c] for c in cells]) if cells else np.zeros(0, np.int64)


def count_topics(state: NaiveModel, topics: dict | None = None):
    """(nwk (V, K), nk (K,), ncz (n_cells, K)) counted from topics; a topic of -1 counts nowhere."""
    topics = state.topics if topics is None else topics
    nwk = np.zeros((state.vocabulary_size, state.n_topics), np.int64)
    ncz = np.zeros((state.n_cells, state.n_topics), np.int64)
    for c, zs in topics.items():
        for w, z in zip(state.words[c], zs):
            if z >= 0:
                nwk[w, z] += 1
                ncz[c, z] += 1
    return nwk, nwk.sum(axis=0), ncz


def neighbourhood(state: NaiveModel, ncz: np.ndarray, cell: int) -> np.ndarray:
    """Topic counts of ``cell`` plus those of every neighbour in the table."""
    total = ncz[cell].copy()
    for d in state.table[cell]:
        if d >= 0:
            total += ncz[d]
    return total


def eq5_weights(state: NaiveModel, nwk, nk, around, w) -> np.ndarray:
    """float32 weights of eq. 5, padded to a multiple of 8 with zeros, as the kernel forms them."""
    if state.frozen is not None:
        nwk, nk = state.frozen, state.frozen.sum(axis=0)
    inv = (1.0 / (nk.astype(np.float64) + state.vocabulary_size * state.beta)).astype(np.float32)
    p = (nwk[w].astype(np.float32) + np.float32(state.beta)) * inv * (
        np.asarray(around).astype(np.float32) + np.float32(state.alpha)
    )
    if state.allowed is not None:
        p = np.where(state.allowed[w], p, np.float32(0))
    return np.concatenate([p, np.zeros(state.padded - state.n_topics, np.float32)])


def add_cell_naive(state: NaiveModel, cell: int, words, time: int | None = None) -> None:
    """Twin of ``add_cell_kernel``: uniform topics from stream (counter, cell)."""
    stream = Stream(state.key, state.counter, cell)
    state.words[cell] = np.asarray(words, np.int64)
    state.topics[cell] = np.array([below(stream.bits(), state.n_topics) for _ in words], np.int64)
    state.order.append(cell)
    state.times.append((state.times[-1] + 1 if state.times else 0) if time is None else time)
    state.counter += 1


def add_words_naive(state: NaiveModel, cell: int, words, time: int | None = None) -> None:
    """Twin of ``TopicModel.add_words``: more words for an observed cell, uniform topics from
    stream (counter, cell); the cell moves to the newest observation."""
    stream = Stream(state.key, state.counter, cell)
    new_topics = [below(stream.bits(), state.n_topics) for _ in words]
    state.words[cell] = np.concatenate([state.words[cell], np.asarray(words, np.int64)])
    state.topics[cell] = np.concatenate([state.topics[cell], np.array(new_topics, np.int64)])
    at = state.order.index(cell)
    del state.order[at], state.times[at]
    state.order.append(cell)
    state.times.append((max(state.times) + 1 if state.times else 0) if time is None else time)
    state.counter += 1


def remove_cells_naive(state: NaiveModel, cells) -> None:
    """Twin of ``TopicModel.remove_cells``: the cells' words and topics are gone, as if never added."""
    for c in cells:
        at = state.order.index(c)
        del state.order[at], state.times[at], state.words[c], state.topics[c]


def restart_naive(state: NaiveModel, seed: int) -> None:
    """Twin of ``TopicModel.restart``: a new key, and every observed cell's topics drawn
    again as if added in cell order (the j-th from stream (j, cell))."""
    state.key = mix(seed)
    cells = sorted(state.topics)
    for j, c in enumerate(cells):
        stream = Stream(state.key, j, c)
        state.topics[c] = np.array([below(stream.bits(), state.n_topics) for _ in state.words[c]], np.int64)
    state.order = cells
    state.times = list(range(len(cells)))
    state.counter = len(cells)


def gibbs_cell_naive(state: NaiveModel, cell: int, stream: Stream, stale_topics: dict | None = None) -> None:
    """One Gibbs pass over a cell's words, every count recounted without the word.

    With ``stale_topics``, the word-topic counts come from those topics for every other
    cell (and this cell's current topics): the view of a cell inside a batch phase.
    """
    zs = state.topics[cell]
    for i, w in enumerate(state.words[cell]):
        zs[i] = -1
        _, _, ncz = count_topics(state)
        source = state.topics if stale_topics is None else {**stale_topics, cell: zs}
        nwk, nk, _ = count_topics(state, source)
        zs[i] = lane_draw(eq5_weights(state, nwk, nk, neighbourhood(state, ncz, cell), w), stream.bits())


def refine_cells_naive(state: NaiveModel, cells) -> None:
    """Twin of ``refine_cells_kernel``: cell j of the list uses stream (counter + j, cell)."""
    for j, c in enumerate(cells):
        gibbs_cell_naive(state, int(c), Stream(state.key, state.counter + j, int(c)))
    state.counter += len(cells)


def distance2_colouring_naive(table: np.ndarray) -> np.ndarray:
    """Twin of ``distance2_colouring``: greedy, in cell order, smallest colour free within distance 2."""
    colour = {}
    for c in range(table.shape[0]):
        near = {d for d in table[c] if d >= 0}
        near |= {e for d in list(near) for e in table[d] if e >= 0}
        near.discard(c)
        used = {colour[d] for d in near if d in colour}
        colour[c] = min(set(range(len(used) + 1)) - used)
    return np.array([colour[c] for c in range(table.shape[0])], np.int32)


def refine_batch_naive(state: NaiveModel, sweeps: int) -> None:
    """Twin of ``TopicModel.refine_batch``: phases by colour, stale word-topic counts per phase.

    Phases: for each colour in increasing order, the observed cells of that colour in
    cell order, cut into ceil(n / m) runs of consecutive cells with m = ceil(observed
    cells / 16), the first n mod runs of them one cell longer than the rest. In sweep s,
    each cell of a phase is refined with stream (counter + s, cell), seeing every other
    cell's word-topic contribution as it was when the phase began.
    """
    colour = distance2_colouring_naive(state.table)
    cells = sorted(state.topics)
    most = math.ceil(len(cells) / 16)
    phases = []
    for h in sorted({colour[c] for c in cells}):
        group = [c for c in cells if colour[c] == h]
        runs = math.ceil(len(group) / most)
        at = 0
        for j in range(runs):
            size = len(group) // runs + (1 if j < len(group) % runs else 0)
            phases.append(group[at : at + size])
            at += size
    for s in range(sweeps):
        for phase in phases:
            start = {c: zs.copy() for c, zs in state.topics.items()}
            for c in phase:
                gibbs_cell_naive(state, c, Stream(state.key, state.counter + s, c), stale_topics=start)
    state.counter += sweeps


def refine_realtime_naive(
    state: NaiveModel, budget: int, eta: float, picks: str = "uniform", tau: float = 2.0,
) -> tuple[int, int, int]:
    """Twin of ``refine_realtime_kernel``: (words sampled, picks, words sampled at the newest time).

    ``recent`` picks the newest time with probability ``eta``, ``recent-64-ours`` one of
    the newest 64."""
    times = sorted(set(state.times))
    groups = [[c for c, t in zip(state.order, state.times) if t == time] for time in times]
    picker = Stream(state.key, state.counter, state.free_stream)
    recent = picks in ("recent", "recent-64-ours")
    window = 64 if picks == "recent-64-ours" else 1
    done = picks = idle = newest = 0
    while done + idle < budget:  # a pick without words spends one unit
        bits = picker.bits()
        if recent:
            take_newest = unit64(bits) < eta
            bits = picker.bits()
            if take_newest:
                last = min(window, len(groups))
                group = groups[len(groups) - last + below(bits, last)]
            else:
                group = groups[min(math.floor(unit64(bits) ** (1.0 / tau) * len(groups)), len(groups) - 1)]
        elif len(groups) == 1 or unit64(bits) < eta:
            group = groups[-1]
        else:
            group = groups[below(picker.bits(), len(groups) - 1)]
        for c in group:
            gibbs_cell_naive(state, c, Stream(state.key, state.counter + 1 + picks, c))
        sampled = sum(len(state.words[c]) for c in group)
        done += sampled
        newest += sampled if group is groups[-1] else 0
        idle += sampled == 0
        picks += 1
    state.counter += 1 + picks
    return done, picks, newest


def lda_gibbs_naive(docs, topics, n_topics, n_words, alpha, beta, streams):
    """Collapsed Gibbs sampler of LDA (Griffiths & Steyvers 2004), one pass over each document.

    ``docs`` and ``topics`` are lists of arrays (topics changed in place); document d
    draws from ``streams[d]``. p(z = k) ∝ (n_wk + β)/(n_k + Vβ) · (n_dk + α), every count
    without the word, in the kernels' float32 arithmetic and lane-order draw.
    """
    padding = np.zeros(-(-n_topics // 8) * 8 - n_topics, np.float32)
    for d, (doc, zs) in enumerate(zip(docs, topics)):
        for i, w in enumerate(doc):
            zs[i] = -1
            nwk = np.zeros((n_words, n_topics), np.int64)
            for other_doc, other_zs in zip(docs, topics):
                for v, z in zip(other_doc, other_zs):
                    if z >= 0:
                        nwk[v, z] += 1
            ndk = np.bincount(zs[zs >= 0], minlength=n_topics)
            inv = (1.0 / (nwk.sum(axis=0) + n_words * beta)).astype(np.float32)
            p = (nwk[w].astype(np.float32) + np.float32(beta)) * inv * (ndk.astype(np.float32) + np.float32(alpha))
            zs[i] = lane_draw(np.concatenate([p, padding]), streams[d].bits())


def ml_topics_naive(state: NaiveModel, cells) -> np.ndarray:
    """Twin of ``ml_topics_kernel``: np.argmax of eq. 5 with the word included, float64."""
    nwk, nk, ncz = count_topics(state)
    if state.frozen is not None:
        nwk, nk = state.frozen, state.frozen.sum(axis=0)
    norm = 1.0 / (nk + state.vocabulary_size * state.beta)
    out = []
    for c in cells:
        around = neighbourhood(state, ncz, c)
        for w in state.words[c]:
            weights = (nwk[w] + state.beta) * norm * (around + state.alpha)
            out.append(np.argmax(weights if state.allowed is None else np.where(state.allowed[w], weights, 0.0)))
    return np.array(out, np.int64)


def log_likelihood_naive(state: NaiveModel) -> float:
    """Twin of ``log_likelihood_sum_kernel`` over every cell, divided by the words: mean log Σ_k φ_k(w) θ_c(k), float64."""
    nwk, nk, ncz = count_topics(state)
    if state.frozen is not None:
        nwk, nk = state.frozen, state.frozen.sum(axis=0)
    phi = (nwk + state.beta) / (nk + state.vocabulary_size * state.beta)
    logs = []
    for c in sorted(state.words):
        around = neighbourhood(state, ncz, c)
        theta = (around + state.alpha) / (around.sum() + state.n_topics * state.alpha)
        logs += [math.log(float(phi[w] @ theta)) for w in state.words[c]]
    return float(np.mean(logs)) if logs else 0.0


def word_perplexity_naive(state: NaiveModel, words) -> float:
    """Twin of ``word_perplexity_kernel``: eq. 11 straight from its definition."""
    nwk, nk, _ = count_topics(state)
    if state.frozen is not None:
        nwk, nk = state.frozen, state.frozen.sum(axis=0)
    phi = (nwk + state.beta) / (nk + state.vocabulary_size * state.beta)
    path = (nk + state.alpha) / (nk.sum() + state.n_topics * state.alpha)
    return math.exp(-np.mean([math.log(float(phi[w] @ path)) for w in words]))


def topic_perplexity_naive(
    state: NaiveModel, words, cell: int, context: str = "neighbourhood", sweeps: int = 1, path_topics: str = "smoothed",
    labels: str = "sample", words_in_model: str = "held-out",
) -> tuple[float, np.ndarray]:
    """Twin of ``topic_perplexity_kernel``: (eq. 12, the temporary topics).

    With ``added``, a word's temporary topic counts in Φ as in the neighbourhood: the
    counts of every other word at its current topic, the word itself left out."""
    nwk, nk, ncz = count_topics(state)
    around = neighbourhood(state, ncz, cell) if context == "neighbourhood" else np.zeros(state.n_topics, np.int64)
    stream = Stream(state.key, state.counter, state.free_stream + 1 + cell)
    counted = words_in_model == "added" and state.frozen is None
    topics = [-1] * len(words)
    for sweep in range(sweeps):
        for i, w in enumerate(words):
            if sweep:
                around[topics[i]] -= 1
            placed = [(v, z) for j, (v, z) in enumerate(zip(words, topics)) if counted and j != i and z >= 0]
            nwk_now, nk_now = nwk.copy(), nk.copy()
            for v, z in placed:
                nwk_now[v, z] += 1
                nk_now[z] += 1
            p = eq5_weights(state, nwk_now, nk_now, around, w)
            topics[i] = int(np.argmax(p)) if labels == "argmax" else lane_draw(p, stream.bits())
            around[topics[i]] += 1
    if state.frozen is not None:
        nk = state.frozen.sum(axis=0)
    elif counted:
        nk = nk + np.bincount(topics, minlength=state.n_topics)
    if path_topics == "smoothed":
        path = (nk + state.alpha) / (nk.sum() + state.n_topics * state.alpha)
    elif any(nk[z] == 0 for z in topics):
        return math.inf, np.array(topics)
    else:
        path = nk / nk.sum()
    return math.exp(-np.mean([math.log(path[z]) for z in topics])), np.array(topics)


def recount(model) -> dict:
    """The counts of a TopicModel recounted from its words and topics alone.

    Returns ``nwk`` (V, K), ``nk`` (K,), ``ncz`` (n_cells, K) and ``ng`` (n_cells, K);
    for a frozen model ``nwk`` and ``nk`` are the frozen counts.
    """
    state = NaiveModel.of(model)
    nwk, nk, ncz = count_topics(state)
    if state.frozen is not None:
        nwk, nk = state.frozen, state.frozen.sum(axis=0)
    ng = np.array([neighbourhood(state, ncz, c) for c in range(state.n_cells)]).reshape(ncz.shape)
    return {"nwk": nwk, "nk": nk, "ncz": ncz, "ng": ng}


def neighbour_table_problem_naive(table: np.ndarray) -> str | None:
    """Twin of ``check_neighbours``' graph checks on a table of valid entries: its message, or None.

    Through the table's directed edges, sorted: a cell listing itself, an edge listed
    twice, and the smallest edge whose reverse is not listed."""
    n_cells = table.shape[0]
    cell, column = np.nonzero(table >= 0)
    other = table[cell, column]
    if np.any(other == cell):
        return f"neighbours: cell {cell[other == cell][0]} lists itself"
    edges = cell.astype(np.int64) * n_cells + other
    unique = np.unique(edges)
    if unique.size != edges.size:
        return "neighbours: a cell lists the same neighbour twice"
    missing = np.setdiff1d(unique, other.astype(np.int64) * n_cells + cell)
    if missing.size:
        return (
            f"neighbours: not symmetric: cell {missing[0] // n_cells} lists {missing[0] % n_cells}, "
            "but not the other way round"
        )
    return None


# --------------------------------------------------------------------------- chains in lock-step
# Twins of curiosity_cli/topics/_chain_kernels.py, one chain at a time, on a frozen NaiveModel
# (state.frozen set): the kernels advance many chains together, and each must be this.


def running_sum_draw(p: np.ndarray, bits: int) -> int:
    """Inverse-CDF draw over the float32 running sum of ``p`` in topic order.

    The first topic whose running sum exceeds ``unit32(bits) * total``; if rounding
    leaves none, the last topic with a positive weight.
    """
    running, total = [], np.float32(0.0)
    for x in np.asarray(p, np.float32):
        total = np.float32(total + x)
        running.append(total)
    target = np.float32(unit32(bits) * total)
    for k, s in enumerate(running):
        if s > target:
            return k
    return max(k for k, x in enumerate(p) if x > 0)


def start_chain_naive(state: NaiveModel, seed: int, placed: bool) -> None:
    """Twin of ``start_chain_kernel``: uniform topics as ``restart_naive``, or placed ones
    (each word drawn from eq. 5 over the words placed before it, cell c from stream (0, c))."""
    if not placed:
        restart_naive(state, seed)
        return
    state.key = mix(seed)
    cells = sorted(state.topics)
    for c in cells:
        state.topics[c] = np.full(state.words[c].size, -1, np.int64)
    for c in cells:
        stream = Stream(state.key, 0, c)
        for i, w in enumerate(state.words[c]):
            _, _, ncz = count_topics(state)
            state.topics[c][i] = running_sum_draw(eq5_weights(state, None, None, neighbourhood(state, ncz, c), w), stream.bits())


def neighbour_colouring_naive(table: np.ndarray) -> np.ndarray:
    """Twin of ``neighbour_colouring``: greedy, in cell order, the smallest colour no neighbour has yet."""
    colour = np.full(table.shape[0], -1, np.int32)
    for c in range(table.shape[0]):
        taken = {int(colour[d]) for d in table[c] if d >= 0 and colour[d] >= 0}
        colour[c] = min(set(range(len(taken) + 1)) - taken)
    return colour


def sweep_chain_naive(state: NaiveModel, counter: int) -> None:
    """Twin of a ``FrozenChains`` sweep for one chain: cells colour by colour, each colour's
    in index order (``neighbour_colouring_naive``), cell c from stream (counter, c), each
    word drawn from eq. 5 with every count recounted without it."""
    colour = neighbour_colouring_naive(state.table)
    for c in sorted(state.topics, key=lambda c: (colour[c], c)):
        stream = Stream(state.key, counter, c)
        zs = state.topics[c]
        for i, w in enumerate(state.words[c]):
            zs[i] = -1
            _, _, ncz = count_topics(state)
            zs[i] = running_sum_draw(eq5_weights(state, None, None, neighbourhood(state, ncz, c), w), stream.bits())


# --------------------------------------------------------------------------- mutual information


def mutual_information_naive(a, b) -> float:
    """Σ_ij p(i, j) log2(p(i, j) / (p(i) p(j))) over the label values that occur, in bits."""
    a = list(np.asarray(a).ravel())
    b = list(np.asarray(b).ravel())
    n = len(a)
    total = 0.0
    for i in set(a):
        p_i = a.count(i) / n
        for j in set(b):
            p_j = b.count(j) / n
            p_ij = sum(1 for x, y in zip(a, b) if x == i and y == j) / n
            if p_ij > 0:
                total += p_ij * math.log2(p_ij / (p_i * p_j))
    return total


def expected_mutual_information_naive(table) -> float:
    """Twin of ``evaluate/_chance_kernels.py``: E[MI] in bits over every count of every cell, each
    weighted by its hypergeometric probability (scipy), with no tail left out."""
    from scipy.stats import hypergeom

    table = np.asarray(table)
    total = int(table.sum())
    expected = 0.0
    for a in table.sum(axis=1).tolist():
        for b in table.sum(axis=0).tolist():
            for n in range(max(1, a + b - total), min(a, b) + 1):
                expected += hypergeom.pmf(n, total, a, b) * n / total * math.log2(total * n / (a * b))
    return expected


# --------------------------------------------------------------------------- label tables


def pixel_tables_naive(pixel_words, reference, n_classes, word_labels, n_labels, kept=None) -> np.ndarray:
    """Twin of ``PixelTables(pixel_words, reference, n_classes).tables(word_labels, n_labels, kept)``: each
    column's pixel map drawn, then its kept pixels counted."""
    out = np.zeros((word_labels.shape[1], n_labels, n_classes), np.int64)
    for r in range(word_labels.shape[1]):
        pixels = word_labels[:, r][pixel_words]
        mask = np.ones(pixel_words.shape, bool) if kept is None else kept[:, r][pixel_words]
        np.add.at(out[r], (pixels[mask], np.asarray(reference)[mask]), 1)
    return out


# --------------------------------------------------------------------------- held-out log-likelihood
# Twin of curiosity_cli/label/_heldout_kernels.py with the factors heldout.word_log2 gives it, from a
# chain's topics rather than its counts.


def heldout_log2_naive(state: NaiveModel, held: dict) -> list[float]:
    """Twin of ``heldout.word_log2`` (``word_log2_kernel``) over ``held`` (cell -> held-out word ids), cells in order: for each word,
    log2 Σ_k θ_ck φ_k(w), θ_c from the topics of the observed words (``state``) of c and its neighbours plus α,
    φ from the frozen counts plus β, each a plain loop in float64."""
    _, _, ncz = count_topics(state)
    phi, k_topics, v = state.frozen, state.n_topics, state.vocabulary_size
    totals = [sum(int(phi[w, k]) for w in range(v)) for k in range(k_topics)]
    out = []
    for c in sorted(held):
        around = neighbourhood(state, ncz, c)
        norm = sum(int(n) for n in around) + k_topics * state.alpha
        for w in held[c]:
            p = 0.0
            for k in range(k_topics):
                p += (int(around[k]) + state.alpha) / norm * (int(phi[w, k]) + state.beta) / (totals[k] + v * state.beta)
            out.append(math.log2(p))
    return out


def heldout_sums_naive(scores, unvisited) -> tuple[float, float]:
    """Twin of ``heldout_sums_kernel``: the scores added one by one in their order, all and the unvisited ones."""
    total = part = 0.0
    for score, outside in zip(np.asarray(scores).tolist(), np.asarray(unvisited).tolist()):
        total += score
        if outside:
            part += score
    return total, part


# --------------------------------------------------------------------------- confirmation
# Twin of curiosity_cli/evaluate/confirmation.py's sign_flip_test, which draws the flips.


def sign_flip_p_naive(differences, strata) -> float:
    """The exact one-sided p of a stratified mean above 0: every one of the 2^n sign flips of the differences,
    the share whose mean over maps of each map's mean reaches the observed one."""
    import itertools

    differences = np.asarray(differences, np.float64)
    strata = list(strata)
    maps = sorted(set(strata))

    def statistic(values) -> float:
        return float(np.mean([np.mean([v for v, s in zip(values, strata) if s == m]) for m in maps]))

    observed = statistic(differences)
    flips = list(itertools.product((-1.0, 1.0), repeat=differences.size))
    return sum(statistic(differences * np.array(signs)) >= observed - 1e-12 for signs in flips) / len(flips)
