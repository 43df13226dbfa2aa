"""The random streams of a study's rows, made for a batch of rows at once.

A row of random data draws from ``numpy.random.default_rng(numpy.random.SeedSequence(seed, spawn_key=stream))``
(``experiments.engine``: the study's seed, the stream of its data set and repetition). NumPy's ``SeedSequence``
(M. E. O'Neill's ``seed_seq`` hash; NEP 19 keeps its output fixed across NumPy versions) mixes its entropy and makes a
``PCG64`` state in loops of scalar operations: 9 us of the 16 us it took to make a 100-point circle. The same 32-bit
integer operations run here on arrays, one element per row of a batch (0.3 us a row), and each row's generator is a
``PCG64`` seeded with its state: the same generator, bit for bit (tests/test_seeding.py compares them with NumPy's
over random seeds and streams, large integers included).
"""
from __future__ import annotations

import numpy as np
from numpy.random.bit_generator import ISpawnableSeedSequence

# the constants of numpy.random.SeedSequence (numpy/random/bit_generator.pyx)
_INIT_A, _MULT_A = 0x43B0D7E5, 0x931E8875
_INIT_B, _MULT_B = 0x8B51F9DD, 0x58F38DED
_MIX_MULT_L, _MIX_MULT_R = 0xCA01F9DD, 0x4973F715
_XSHIFT = 16
_POOL = 4         # SeedSequence's default pool size (32-bit words)
_MASK = 0xFFFFFFFF
_U32 = np.uint32


def _words(value: int) -> list[int]:
    """A non-negative integer as SeedSequence reads it: its 32-bit words, least significant first ([0] for 0)."""
    if value == 0:
        return [0]
    out = []
    while value:
        out.append(value & _MASK)
        value >>= 32
    return out


def _hash_constants(start: int, mult: int, count: int) -> list[int]:
    """The successive values of SeedSequence's hash constant as ``hashmix`` (or ``generate_state``) uses them: the
    constant before each multiplication step, and the one after it."""
    out, h = [], start
    for _ in range(count):
        before = h
        h = (h * mult) & _MASK
        out.append((before, h))
    return out


def _hashmix(value: np.ndarray, consts: tuple[int, int]) -> np.ndarray:
    before, after = consts
    value = (value ^ _U32(before)) * _U32(after)
    return value ^ (value >> _U32(_XSHIFT))


def _mix(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    r = _U32(_MIX_MULT_L) * x - _U32(_MIX_MULT_R) * y
    return r ^ (r >> _U32(_XSHIFT))


def _pools(entropy: np.ndarray) -> np.ndarray:
    """SeedSequence's ``mix_entropy`` of each row of ``entropy`` ((m, L) uint32, the assembled entropy): (m, 4)."""
    m, length = entropy.shape
    steps = iter(_hash_constants(_INIT_A, _MULT_A, _POOL + _POOL * (_POOL - 1) + _POOL * max(0, length - _POOL)))
    zero = np.zeros(m, dtype=_U32)
    mixer = [_hashmix(entropy[:, i] if i < length else zero, next(steps)) for i in range(_POOL)]
    for src in range(_POOL):
        for dst in range(_POOL):
            if src != dst:
                mixer[dst] = _mix(mixer[dst], _hashmix(mixer[src], next(steps)))
    for src in range(_POOL, length):
        for dst in range(_POOL):
            mixer[dst] = _mix(mixer[dst], _hashmix(entropy[:, src], next(steps)))
    return np.stack(mixer, axis=1)


_STATE_STEPS = _hash_constants(_INIT_B, _MULT_B, 8)


def _pcg64_states(pools: np.ndarray) -> np.ndarray:
    """SeedSequence's ``generate_state(4, np.uint64)`` of each pool ((m, 4) uint32): (m, 4) uint64."""
    words = np.empty((pools.shape[0], 8), dtype=_U32)
    for i, (before, after) in enumerate(_STATE_STEPS):
        v = (pools[:, i % _POOL] ^ _U32(before)) * _U32(after)
        words[:, i] = v ^ (v >> _U32(_XSHIFT))
    return words.astype("<u4").view("<u8").astype(np.uint64)


def _assembled(seed: int, stream) -> list[int] | None:
    """The entropy words SeedSequence(seed, spawn_key=stream) hashes (its seed's words, padded with zeros to the
    pool's size, then each spawn key's words), or None for what it would not take as it is here (not a non-negative
    int): NumPy's own SeedSequence then makes that generator, and says what is wrong with it."""
    if type(seed) is not int or seed < 0:
        return None
    run = [seed] if seed <= _MASK else _words(seed)
    spawn = list(stream)
    for k in spawn:
        if type(k) is not int or not 0 <= k <= _MASK:  # a word each (the streams of studies), else word by word
            if any(type(k) is not int or k < 0 for k in stream):
                return None
            spawn = [w for k in stream for w in _words(k)]
            break
    if spawn and len(run) < _POOL:
        run += [0] * (_POOL - len(run))
    return run + spawn


class _Derived(ISpawnableSeedSequence):
    """The seed sequence of a generator made here: its PCG64 state, computed for a batch; anything else asked of it
    (``spawn``, ``entropy``, another ``generate_state``) is answered by NumPy's own ``SeedSequence(seed,
    spawn_key=stream)``, made on first use."""

    def __init__(self, state: np.ndarray, seed: int, stream: tuple):
        self._state, self._seed, self._stream, self._real = state, seed, stream, None

    def real(self) -> np.random.SeedSequence:
        if self._real is None:
            self._real = np.random.SeedSequence(self._seed, spawn_key=self._stream)
        return self._real

    def generate_state(self, n_words, dtype=np.uint32):
        if n_words == 4 and (dtype is np.uint64 or np.dtype(dtype) == np.uint64):
            return self._state.copy()
        return self.real().generate_state(n_words, dtype)

    def spawn(self, n_children):
        return self.real().spawn(n_children)

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        return getattr(self.real(), name)


def generators(seed: int, streams) -> list[np.random.Generator | None]:
    """``numpy.random.default_rng(numpy.random.SeedSequence(seed, spawn_key=tuple(s)))`` for each stream ``s``, the
    seed sequences' hashing done once for all of them; None for a stream (or seed) of other values than
    non-negative ints, whose generator NumPy's ``SeedSequence`` must make itself (and refuse, if it is wrong)."""
    streams = [tuple(s) for s in streams]
    out: list = [None] * len(streams)
    groups: dict[int, list] = {}
    for i, s in enumerate(streams):
        words = _assembled(seed, s)
        if words is not None:
            groups.setdefault(len(words), []).append((i, words))
    for members in groups.values():
        states = _pcg64_states(_pools(np.array([w for _, w in members], dtype=_U32)))
        for (i, _), state in zip(members, states):
            out[i] = np.random.Generator(np.random.PCG64(_Derived(state, seed, streams[i])))
    return out
