"""Tests of tamias2d._containers: Munk2D's cpArray and cpHashSet.

The hash set's iteration order decides the order in which the broad phase
updates its leaves, so it is checked against a small Python model of the
rules Munk2D documents: prime table sizes, head insertion into a bucket,
growth when entries reach the size (rehash walking old buckets in order and
head-inserting again), traversal bucket by bucket from chain head to tail.
"""
import random

import pytest

_testing = pytest.importorskip("tamias2d._testing")
_TestArray = _testing._TestArray
_TestHashSet = _testing._TestHashSet

PRIMES = [5, 13, 23, 47, 97, 193, 389, 769, 1543, 3079, 6151, 12289, 24593, 49157,
          98317, 196613, 393241, 786433, 1572869, 3145739, 6291469, 12582917,
          25165843, 50331653, 100663319, 201326611, 402653189, 805306457, 1610612741]


@pytest.fixture(autouse=True)
def _no_leftover_failures():
    _testing._set_alloc_failure(-1)
    _testing._take_out_of_memory()
    yield
    _testing._set_alloc_failure(-1)
    assert not _testing._take_out_of_memory()


# -- cpArray --------------------------------------------------------------------------
def test_array_default_and_given_capacity():
    assert _TestArray().max == 4
    assert _TestArray(10).max == 10
    assert _TestArray().num == 0


def test_array_growth_rule():
    a = _TestArray()
    caps = []
    for i in range(1, 60):
        a.push(i)
        caps.append(a.max)
    # max becomes 3*(max+1)/2 (integer division) each time the array is full.
    expected, cap = [], 4
    for n in range(1, 60):
        if n > cap:
            cap = 3 * (cap + 1) // 2
        expected.append(cap)
    assert caps == expected
    assert sorted(set(caps))[:5] == [4, 7, 12, 19, 30]
    assert a.to_list() == list(range(1, 60))


def test_array_pop_returns_last_and_clears_slot():
    a = _TestArray()
    for i in (1, 2, 3):
        a.push(i)
    assert a.pop() == 3
    assert a.to_list() == [1, 2]
    assert a.slots() == [1, 2, 0, 0]
    with pytest.raises(IndexError):
        _TestArray().pop()


def test_array_delete_is_swap_with_last():
    a = _TestArray()
    for i in range(1, 7):
        a.push(i)
    a.delete(2)
    assert a.to_list() == [1, 6, 3, 4, 5]
    a.delete(5)                       # the last one: nothing moves
    assert a.to_list() == [1, 6, 3, 4]
    a.delete(1)
    assert a.to_list() == [4, 6, 3]
    # Vacated slots are cleared (slots past the last push were never written:
    # realloc leaves them undefined, as in Munk2D).
    assert a.slots()[3:6] == [0, 0, 0]
    a.delete(99)                      # absent: no-op
    assert a.to_list() == [4, 6, 3]


def test_array_delete_removes_first_match_only():
    a = _TestArray()
    for i in (7, 8, 7, 9):
        a.push(i)
    a.delete(7)
    assert a.to_list() == [9, 8, 7]


def test_array_matches_list_model():
    rng = random.Random(3)
    a = _TestArray()
    model = []
    for _ in range(2000):
        r = rng.random()
        if r < 0.5 or not model:
            v = rng.randint(1, 50)
            a.push(v)
            model.append(v)
        elif r < 0.8:
            v = rng.randint(1, 50)
            a.delete(v)
            if v in model:
                i = model.index(v)
                last = model.pop()
                if i < len(model):
                    model[i] = last
        else:
            assert a.pop() == model.pop()
        assert a.to_list() == model
    for v in range(1, 51):
        assert a.contains(v) == (v in model)


def test_array_free_each_and_contains():
    a = _TestArray()
    a.free_each_noop()
    for i in (3, 4):
        a.push(i)
    a.free_each_noop()
    assert a.contains(3) and not a.contains(5)


def test_array_push_out_of_memory_leaves_array_unchanged():
    a = _TestArray()
    for i in range(1, 5):
        a.push(i)
    _testing._set_alloc_failure(0)     # the growth realloc fails
    with pytest.raises(MemoryError):
        a.push(5)
    assert a.to_list() == [1, 2, 3, 4] and a.max == 4
    a.push(5)                             # works again
    assert a.to_list() == [1, 2, 3, 4, 5] and a.max == 7


def test_array_new_out_of_memory():
    _testing._set_alloc_failure(0)
    with pytest.raises(MemoryError):
        _TestArray()
    _testing._set_alloc_failure(1)     # the element storage fails
    with pytest.raises(MemoryError):
        _TestArray()


# -- prime.h ----------------------------------------------------------------------------
def test_next_prime_table():
    assert [_testing._next_prime(p) for p in PRIMES] == PRIMES
    assert _testing._next_prime(0) == 5
    assert _testing._next_prime(-3) == 5
    assert _testing._next_prime(6) == 13
    assert _testing._next_prime(1543) == 1543
    assert _testing._next_prime(1544) == 3079
    assert _testing._next_prime(1610612742) == 0    # past the table


# -- cpHashSet ----------------------------------------------------------------------------
class HashSetModel:
    """Munk2D's hash-set rules in plain Python."""

    def __init__(self, size=0):
        self.size = next(p for p in PRIMES if p >= size)
        self.table = [[] for _ in range(self.size)]
        self.entries = 0

    def insert(self, h, key):
        chain = self.table[h % self.size]
        if key in chain:
            return
        chain.insert(0, key)
        self.entries += 1
        if self.entries >= self.size:
            new_size = next(p for p in PRIMES if p >= self.size + 1)
            new = [[] for _ in range(new_size)]
            for chain in self.table:
                for k in chain:
                    new[self.hashes[k] % new_size].insert(0, k)
            self.table, self.size = new, new_size

    def remove(self, h, key):
        chain = self.table[h % self.size]
        if key in chain:
            chain.remove(key)
            self.entries -= 1
            return key
        return 0

    def items(self):
        return [k for chain in self.table for k in chain]


def test_hash_set_initial_size():
    assert _TestHashSet().size == 5
    assert _TestHashSet(6).size == 13
    assert _TestHashSet(100).size == 193


def test_hash_set_head_insertion_and_order():
    s = _TestHashSet()
    for k in (1, 6, 11, 2):
        s.insert(k, k)
    # bucket 1 holds 11, 6, 1 (newest first); bucket 2 holds 2.
    assert s.buckets() == [[], [11, 6, 1], [2], [], []]
    assert s.items() == [11, 6, 1, 2]
    assert s.count == 4


def test_hash_set_resize_reverses_chains():
    s = _TestHashSet()
    for k in (1, 6, 11, 16):
        s.insert(k, k)
    # All in bucket 1 of 5: [16, 11, 6, 1]. The 5th entry triggers the resize.
    s.insert(3, 3)
    assert s.size == 13
    # Rehash walks bucket 0 ([]), bucket 1 (16, 11, 6, 1), then bucket 3 (3),
    # head-inserting each into the 13-bucket table.
    expected = [[] for _ in range(13)]
    for k in (16, 11, 6, 1, 3):
        expected[k % 13].insert(0, k)
    assert s.buckets() == expected


def test_hash_set_growth_through_primes():
    s = _TestHashSet()
    sizes = []
    for k in range(1, 3200):
        s.insert(k * 7919, k)
        sizes.append(s.size)
        assert s.size == next(p for p in PRIMES if p > k)
    assert sorted(set(sizes)) == PRIMES[:11]


@pytest.mark.parametrize("seed", range(6))
def test_hash_set_matches_model(seed):
    rng = random.Random(seed)
    s = _TestHashSet()
    model = HashSetModel()
    model.hashes = {}
    for _ in range(3000):
        key = rng.randint(1, 400)
        h = model.hashes.setdefault(key, rng.choice([key, rng.getrandbits(64), key * 5]))
        if rng.random() < 0.65:
            assert s.insert(h, key) == key
            model.insert(h, key)
        else:
            assert s.remove(h, key) == model.remove(h, key)
        assert s.count == model.entries
        assert s.size == model.size
    assert s.items() == model.items()


def test_hash_set_hash_wraps_as_unsigned_64_bit():
    s = _TestHashSet()
    h = 2**64 - 1
    s.insert(h, 9)
    assert s.buckets()[h % 5] == [9]
    assert s.find(h, 9) == 9


def test_hash_set_insert_existing_returns_stored_element():
    s = _TestHashSet()
    assert s.insert(4, 4, use_trans=True) == 4
    assert s.insert(4, 4, use_trans=True) == 4
    assert s.trans_calls == 1
    assert s.count == 1


def test_hash_set_find_and_default_value():
    s = _TestHashSet()
    s.insert(3, 3)
    assert s.find(3, 3) == 3
    assert s.find(3, 8) == 0
    assert s.find(9, 3) == 0          # another bucket
    s.set_default(77)
    assert s.find(1, 1) == 77
    assert s.find(3, 3) == 3


def test_hash_set_remove():
    s = _TestHashSet()
    for k in (1, 6, 11):
        s.insert(k, k)
    assert s.remove(6, 6) == 6
    assert s.items() == [11, 1]
    assert s.remove(6, 6) == 0
    assert s.count == 2


def test_hash_set_each_may_remove_current_element():
    s = _TestHashSet()
    keys = [1, 6, 2, 7, 3]
    for k in keys[:4]:
        s.insert(k, k)
    expected = s.items()
    assert s.items_removing() == expected
    assert s.count == 0 and s.items() == []


def test_hash_set_filter():
    s = _TestHashSet()
    for k in range(1, 30):
        s.insert(k, k)
    before = s.items()
    visited = s.filter(3, 0)
    assert visited == before
    assert s.items() == [k for k in before if k % 3 != 0]
    assert s.count == len(s.items())


def test_hash_set_bins_pooled_in_32k_blocks():
    s = _TestHashSet()
    per_block = 32768 // 24
    s.insert(1, 1)
    assert s.blocks == 1 and s.pooled_bins() == per_block - 1
    for k in range(2, per_block + 1):
        s.insert(k, k)
    assert s.blocks == 1 and s.pooled_bins() == 0
    s.insert(per_block + 1, per_block + 1)
    assert s.blocks == 2
    s.remove(5, 5)                    # recycled bin is reused first
    pooled = s.pooled_bins()
    s.insert(10**6, 10**6)
    assert s.pooled_bins() == pooled - 1 and s.blocks == 2


def test_hash_set_out_of_memory():
    _testing._set_alloc_failure(0)
    with pytest.raises(MemoryError):
        _TestHashSet()
    s = _TestHashSet()
    _testing._set_alloc_failure(0)     # the first bin block
    with pytest.raises(MemoryError):
        s.insert(1, 1)
    assert s.count == 0 and s.items() == []
    s.insert(1, 1)
    assert s.items() == [1]


def test_hash_set_failed_resize_keeps_working():
    s = _TestHashSet()
    for k in range(1, 5):
        s.insert(k, k)
    _testing._set_alloc_failure(0)     # the new table of the resize fails
    s.insert(5, 5)
    assert _testing._take_out_of_memory()
    assert s.size == 5 and s.count == 5
    assert sorted(s.items()) == [1, 2, 3, 4, 5]
    s.insert(6, 6)                        # next insert resizes normally
    assert s.size == 13 and sorted(s.items()) == [1, 2, 3, 4, 5, 6]
