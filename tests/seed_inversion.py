"""The words a NumPy PCG64 generator was seeded with, recovered from its state alone (no seed sequence needed).

Written by an adversarial reviewer of issue 30, who recovered the submission seed this way from a generator that a
hidden test gave a student's function. Every step from SeedSequence entropy to PCG64 state can be undone: the two
LCG steps of PCG64's seeding, generate_state (xor, multiplication by an odd constant, xorshift) and mix_entropy,
when the entropy beyond the 4-word pool is known or guessed. tests/test_case_seeds.py runs it against the hidden
tests' generators (autograder/hidden_tests/cases.py), whose words are now a digest.
"""

M32 = 0xFFFFFFFF
INIT_A, MULT_A, INIT_B, MULT_B = 0x43b0d7e5, 0x931e8875, 0x8b51f9dd, 0x58f38ded
MIX_L, MIX_R = 0xca01f9dd, 0x4973f715
PCG_MULT = (2549297995355413924 << 64) + 4865540595714422341
M128 = (1 << 128) - 1

def xs(v):  # v ^= v >> 16 is an involution on 32 bits
    return v ^ (v >> 16)

def inv(a, m=1 << 32):
    return pow(a, -1, m)

def hash_consts(n, init, mult):
    """the sequence of hash_const values after each multiply"""
    h, out = init, []
    for _ in range(n):
        out.append(h)  # value xored in
        h = (h * mult) & M32
        out.append(h)  # value multiplied by
    return out

def pool_from_generated(words):
    """invert generate_state: words are the uint32 outputs; pool has 4 words (first 4 outputs)."""
    h = INIT_B
    pool = []
    for w in words[:4]:
        x_const = h
        h = (h * MULT_B) & M32
        v = xs(w)
        v = (v * inv(h)) & M32
        v ^= x_const
        pool.append(v)
    return pool

def mix_entropy_fwd(entropy, pool_size=4):
    h = [INIT_A]
    def hashmix(v):
        v ^= h[0]; h[0] = (h[0] * MULT_A) & M32; v = (v * h[0]) & M32; return xs(v)
    def mix(x, y):
        return xs((MIX_L * x - MIX_R * y) & M32)
    m = [hashmix(entropy[i] if i < len(entropy) else 0) for i in range(pool_size)]
    for s in range(pool_size):
        for d in range(pool_size):
            if s != d:
                m[d] = mix(m[d], hashmix(m[s]))
    for s in range(pool_size, len(entropy)):
        for d in range(pool_size):
            m[d] = mix(m[d], hashmix(entropy[s]))
    return m

def unmix_entropy(pool, extra_words, pool_size=4):
    """invert mix_entropy for entropy = first pool_size words + known extra_words."""
    # hash_const sequence: replay
    n_hash = pool_size + pool_size * (pool_size - 1) + pool_size * len(extra_words)
    consts = []  # (xor_const, mult_const) per hashmix
    h = INIT_A
    for _ in range(n_hash):
        x = h; h = (h * MULT_A) & M32; consts.append((x, h))
    def hashmix_k(v, k):
        x, mlt = consts[k]; v ^= x; v = (v * mlt) & M32; return xs(v)
    def unhashmix_k(v, k):
        x, mlt = consts[k]; v = xs(v); v = (v * inv(mlt)) & M32; return v ^ x
    def unmix(r, y):  # r = mix(x, y) -> x
        t = xs(r)
        return ((t + MIX_R * y) * inv(MIX_L)) & M32
    m = list(pool)
    k_first = pool_size
    k_cross = k_first + pool_size * (pool_size - 1)
    # undo extra words (in reverse order)
    ks = []
    k = k_cross
    for s in range(len(extra_words)):
        for d in range(pool_size):
            ks.append((s, d, k)); k += 1
    for s, d, k in reversed(ks):
        m[d] = unmix(m[d], hashmix_k(extra_words[s], k))
    # undo cross mixing: note hashmix(m[s]) uses current m[s], which (s != d) is unchanged by this step
    ks = []
    k = k_first
    for s in range(pool_size):
        for d in range(pool_size):
            if s != d:
                ks.append((s, d, k)); k += 1
    for s, d, k in reversed(ks):
        m[d] = unmix(m[d], hashmix_k(m[s], k))
    return [unhashmix_k(m[i], i) for i in range(pool_size)]

def generated_from_pcg64_state(state):
    st, inc = state["state"]["state"], state["state"]["inc"]
    initseq_low = inc >> 1  # top bit of initseq lost
    prev = ((st - inc) * inv(PCG_MULT, 1 << 128)) & M128
    initstate = (prev - inc) & M128
    seed0, seed1 = initstate >> 64, initstate & ((1 << 64) - 1)
    words = []
    for v in (seed0, seed1):
        words += [v & M32, v >> 32]
    return words  # first 4 uint32 words of generate_state(8)

def recover_seed_stream(state, stream_tail):
    """Given the state of default_rng([seed, *stream]) (fresh), and the guessed tail of the entropy
    beyond the first 4 words, return the first 4 entropy words."""
    pool = pool_from_generated(generated_from_pcg64_state(state))
    return unmix_entropy(pool, list(stream_tail))
