"""A student's function that is given a hidden test's generator cannot learn the submission seed from it.

An adversarial review of issue 30 recovered the submission seed, and the hidden streams, from the state of the
generators that pf_step's hidden tests gave it, when they were seeded with the pair (seed, stream) itself."""

from __future__ import annotations

import numpy as np

from autograder.hidden_tests import cases
from autograder.kernel import wire
from random_draws import random_draws
from seed_inversion import M32, mix_entropy_fwd, recover_seed_stream


@random_draws(false_fail=0.0, why="an identity: the inversion undoes NumPy's seeding exactly, for any seed")
def test_the_inversion_recovers_a_seed_from_a_generators_state(seed):
    """The attack works (so the test below can fail): the state of default_rng([seed, *stream]) gives the seed back."""
    seed64 = seed | (1 << 62)  # two 32-bit words, as a submission seed has
    generator = np.random.default_rng([seed | (1 << 62), 4004, 99, 0])
    assert generator.bit_generator.seed_seq.pool.tolist() == mix_entropy_fwd([seed64 & M32, seed64 >> 32, 4004, 99, 0])
    words = recover_seed_stream(generator.bit_generator.state, [0])
    assert words[0] | (words[1] << 32) == seed64 and words[2:] == [4004, 99]


@random_draws(false_fail=1e-18, why="a 64-bit word of a SHA-256 digest equal to the seed by chance (2**-64 a word)")
def test_a_hidden_tests_generator_does_not_give_the_submission_seed_back(seed):
    seed64 = seed | (1 << 62)  # two 32-bit words, as a submission seed has
    with cases.seeded(seed64):
        generator = cases.rng(4004, 99, 0)
    for tail in ([], [0], [99, 0], [4004, 99, 0]):
        words = recover_seed_stream(generator.bit_generator.state, tail)
        assert seed64 not in (words[0] | (words[1] << 32), words[2] | (words[3] << 32)), tail
    sent = wire._seed_sequence_json(generator.bit_generator.seed_seq)
    assert seed64 not in np.atleast_1d(sent["entropy"]).tolist() and sent["spawn_key"] == []


@random_draws(false_fail=0.0, why="a count kept beside a seed sequence, whatever its entropy")
def test_a_forged_count_of_children_spawned_is_counted_not_spawned(seed):
    """An adversarial review: a kernel that said its copy of the generator had spawned 2**20 children made the grader
    spawn them all (13 s and 441 MB a call). The count is kept beside the seed sequence, and sent on the next call."""
    given = np.random.default_rng(seed)
    wire._spawn_as_many(given.bit_generator.seed_seq, np.random.SeedSequence(1, n_children_spawned=wire.MAX_SPAWNED + 7))
    assert given.bit_generator.seed_seq.n_children_spawned == 0
    assert wire._seed_sequence_json(given.bit_generator.seed_seq)["n_children_spawned"] == wire.MAX_SPAWNED
