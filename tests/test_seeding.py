"""The batch-made random generators (experiments.seeding) are NumPy's default_rng(SeedSequence(seed, spawn_key)),
bit for bit: compared on random seeds and streams, large integers included."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from experiments import rows
from experiments.seeding import generators

_INTS = st.one_of(st.integers(0, 3), st.integers(0, 2 ** 32 - 1), st.integers(2 ** 32 - 2, 2 ** 32 + 2),
                  st.integers(0, 2 ** 130))


def _reference(seed, stream):
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=tuple(stream)))


@settings(max_examples=150, deadline=None)
@given(seed=_INTS, streams=st.lists(st.lists(_INTS, max_size=7), min_size=1, max_size=6))
def test_each_generator_draws_what_numpys_seed_sequence_gives(seed, streams):
    for stream, rng in zip(streams, generators(seed, streams)):
        ref = _reference(seed, stream)
        assert rng.bit_generator.state == ref.bit_generator.state
        assert np.array_equal(rng.normal(size=5), ref.normal(size=5))


def test_what_else_is_asked_of_the_seed_sequence_is_numpys():
    rng = generators(29, [(3, 0, 7)])[0]
    ref = _reference(29, (3, 0, 7))
    assert rng.bit_generator.seed_seq.entropy == 29 and rng.bit_generator.seed_seq.spawn_key == (3, 0, 7)
    assert np.array_equal(rng.bit_generator.seed_seq.generate_state(3), ref.bit_generator.seed_seq.generate_state(3))
    assert [c.integers(2 ** 62) for c in rng.spawn(3)] == [c.integers(2 ** 62) for c in ref.spawn(3)]


@pytest.mark.parametrize("seed, stream", [(-1, (0,)), (5, (0, -2)), (5, (0, 1.5)), (True, (0,))])
def test_what_is_not_a_nonnegative_int_is_left_to_numpy(seed, stream):
    assert generators(seed, [stream]) == [None]


def test_the_batched_data_are_the_data_of_one_task_at_a_time():
    spec = {"source": "circle", "label": "c", "params": {"radius": 2.0, "n": 40, "noise": 0.1}}
    tasks = [{"dataset": spec, "seed": 11, "stream": [0, 0, r]} for r in range(5)]
    made = rows._generators(tasks)
    assert len(made) == 5
    for task in tasks:
        batched, _ = rows.load_data(spec, 11, task["stream"], made[id(task)])
        alone, _ = rows.load_data(spec, 11, task["stream"])
        assert batched.tobytes() == alone.tobytes()
