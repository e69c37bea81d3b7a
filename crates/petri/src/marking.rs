//! Compact storage of markings during state-space generation.
//!
//! Each place gets a bit field just wide enough for the largest token count
//! seen so far; fields are packed greedily into 64-bit words and never straddle
//! a word. Most nets fit a marking in one word (Kanban with N = 5: 16 places ×
//! 3 bits). When a count outgrows its field, the field is widened (doubling its
//! range, one bit of headroom) and every stored marking is re-encoded —
//! indices do not change. When the headroom would cost a word per marking,
//! every field is fitted to the largest count stored instead
//! (`MarkingStore::fitted_layout`).
//! Markings live in one flat `Vec<u64>` in insertion order. Duplicates are
//! found by an index over it:
//!
//! * one-word markings (the common case) go to a [`WordTable`]: open
//!   addressing with linear probing whose slots hold the key *and* its index
//!   (16 bytes), so that a lookup costs one cache miss, not two (a probe, then
//!   the comparison with the stored marking); load factor ≤ 3/4, hence 21–43
//!   bytes of table per marking;
//! * wider markings use a `hashbrown::HashTable<u32>` of indices (about 5
//!   bytes per marking; the comparison reads the stored marking).

use hashbrown::HashTable;

/// Bit layout of a packed marking.
#[derive(Debug, Clone)]
pub(crate) struct Layout {
    width: Vec<u8>,
    word: Vec<u32>,
    shift: Vec<u8>,
    words: usize,
    /// The places of word `w` are `first[w]..first[w + 1]` (fields are
    /// packed in place order), for [`Layout::decode`].
    first: Vec<u32>,
}

impl Layout {
    /// Greedy packing of the given field widths (1..=32 bits each).
    pub(crate) fn new(width: Vec<u8>) -> Layout {
        let mut word = Vec::with_capacity(width.len());
        let mut shift = Vec::with_capacity(width.len());
        let (mut w, mut used) = (0u32, 0u32);
        for &b in &width {
            let b = u32::from(b);
            if used + b > 64 {
                w += 1;
                used = 0;
            }
            word.push(w);
            shift.push(used as u8);
            used += b;
        }
        let words = if width.is_empty() { 1 } else { w as usize + 1 };
        let mut first = vec![0u32; words + 1];
        for &w in &word {
            first[w as usize + 1] += 1;
        }
        for i in 0..words {
            first[i + 1] += first[i];
        }
        Layout {
            width,
            word,
            shift,
            words,
            first,
        }
    }

    /// Smallest widths that hold `m`, at least `min_bits` each.
    pub(crate) fn for_marking(m: &[u32], min_bits: u8) -> Layout {
        Layout::new(m.iter().map(|&v| bits_for(v).max(min_bits)).collect())
    }

    /// Words per marking.
    #[inline]
    pub(crate) fn words(&self) -> usize {
        self.words
    }

    /// Largest count place `p` can hold.
    #[inline]
    pub(crate) fn max_value(&self, p: usize) -> u32 {
        mask(self.width[p]) as u32
    }

    /// Bits per place.
    pub(crate) fn widths(&self) -> &[u8] {
        &self.width
    }

    #[inline]
    pub(crate) fn get(&self, key: &[u64], p: usize) -> u32 {
        ((key[self.word[p] as usize] >> self.shift[p]) & mask(self.width[p])) as u32
    }

    /// Adds `d` to place `p`'s field; the caller guarantees the result fits.
    #[inline]
    pub(crate) fn add(&self, key: &mut [u64], p: usize, d: i64) {
        let w = &mut key[self.word[p] as usize];
        let delta = (d.unsigned_abs()) << self.shift[p];
        if d >= 0 {
            *w = w.wrapping_add(delta);
        } else {
            *w = w.wrapping_sub(delta);
        }
    }

    /// The bits of the fields of `places`, one mask word per key word.
    pub(crate) fn mask_of(&self, places: impl Iterator<Item = usize>) -> Vec<u64> {
        let mut bits = vec![0; self.words];
        for p in places {
            bits[self.word[p] as usize] |= mask(self.width[p]) << self.shift[p];
        }
        bits
    }

    pub(crate) fn encode(&self, m: &[u32], key: &mut [u64]) {
        key.iter_mut().for_each(|w| *w = 0);
        for (p, &v) in m.iter().enumerate() {
            debug_assert!(u64::from(v) <= mask(self.width[p]));
            key[self.word[p] as usize] |= u64::from(v) << self.shift[p];
        }
    }

    /// The counts of the packed `key` into `m` (one per place), word by
    /// word: a word's fields are consecutive places, read by
    /// shifting the word down field after field (a word of zeros is a run
    /// of empty places), instead of looking up each place's word and shift.
    pub(crate) fn decode(&self, key: &[u64], m: &mut [u32]) {
        debug_assert_eq!(m.len(), self.width.len());
        for (w, &v) in key.iter().enumerate().take(self.words) {
            let (lo, hi) = (self.first[w] as usize, self.first[w + 1] as usize);
            let (slots, widths) = (&mut m[lo..hi], &self.width[lo..hi]);
            if v == 0 {
                slots.fill(0);
                continue;
            }
            let mut v = v;
            for (slot, &b) in slots.iter_mut().zip(widths) {
                *slot = (v & mask(b)) as u32;
                v >>= b; // 1..=32 bits: never the whole word
            }
        }
    }
}

#[inline]
fn mask(width: u8) -> u64 {
    if width >= 64 {
        u64::MAX
    } else {
        (1u64 << width) - 1
    }
}

/// Bits needed to hold `v` (at least 1).
pub(crate) fn bits_for(v: u32) -> u8 {
    (32 - v.leading_zeros()).max(1) as u8
}

/// Hash of a packed key of several words (the index of wide markings, and
/// the forced hops of `reachability`).
#[inline]
pub(crate) fn hash_words(key: &[u64]) -> u64 {
    // Multiply-xorshift mixing per word, then the murmur3 finaliser.
    let mut h: u64 = 0x9E37_79B9_7F4A_7C15;
    for &w in key {
        h = (h ^ w).wrapping_mul(0xFF51_AFD7_ED55_8CCD);
        h ^= h >> 32;
    }
    h ^= h >> 33;
    h = h.wrapping_mul(0xC4CE_B9FE_1A85_EC53);
    h ^ (h >> 33)
}

/// Whether two packed keys are equal (word by word: keys are a few words
/// long, too short for a call to `memcmp` to pay).
#[inline]
pub(crate) fn same_key(a: &[u64], b: &[u64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x == y)
}

/// Mixes a one-word key (the murmur3 64-bit finaliser).
#[inline]
fn hash_word(k: u64) -> u64 {
    let mut h = k ^ (k >> 33);
    h = h.wrapping_mul(0xFF51_AFD7_ED55_8CCD);
    h ^= h >> 33;
    h = h.wrapping_mul(0xC4CE_B9FE_1A85_EC53);
    h ^ (h >> 33)
}

/// Table size from which [`MarkingStore::touch`] pays (below, the table
/// stays in the L2 cache).
const TOUCH_ABOVE: usize = 1 << 20;

/// A slot of a [`WordTable`]: a key and its index (`EMPTY` when free).
#[derive(Debug, Clone, Copy)]
struct Slot {
    key: u64,
    index: u32,
}

const EMPTY: u32 = u32::MAX;

/// Hash set of one-word keys mapping each to its index: linear probing,
/// power-of-two capacity, slot = the top bits of the hash, grown ×2 when 3/4
/// full. Keys sit in the slots, so a probe that finds its key needs no
/// other memory access.
#[derive(Debug, Clone, Default)]
pub(crate) struct WordTable {
    slots: Vec<Slot>,
    /// `64 − log2(capacity)`.
    shift: u32,
    len: usize,
}

impl WordTable {
    fn with_capacity(n: usize) -> WordTable {
        let cap = (n.max(8) * 4 / 3 + 1).next_power_of_two();
        let empty = Slot { key: 0, index: EMPTY };
        WordTable {
            slots: vec![empty; cap],
            shift: 64 - cap.trailing_zeros(),
            len: 0,
        }
    }

    #[inline]
    fn capacity(&self) -> usize {
        self.slots.len()
    }

    /// The index of `key`, or inserts it with index `next`; `(index, new)`.
    #[inline]
    fn find_or_insert(&mut self, key: u64, next: u32) -> (u32, bool) {
        if (self.len + 1) * 4 > self.capacity() * 3 {
            self.grow();
        }
        let h = hash_word(key);
        let mask = self.capacity() - 1;
        let mut s = (h >> self.shift) as usize;
        loop {
            let slot = &mut self.slots[s];
            if slot.index == EMPTY {
                *slot = Slot { key, index: next };
                self.len += 1;
                return (next, true);
            }
            if slot.key == key {
                return (slot.index, false);
            }
            s = (s + 1) & mask;
        }
    }

    /// The index of `key`, if present.
    #[inline]
    fn find(&self, key: u64) -> Option<u32> {
        let mask = self.capacity() - 1;
        let mut s = (hash_word(key) >> self.shift) as usize;
        loop {
            let slot = &self.slots[s];
            if slot.index == EMPTY {
                return None;
            }
            if slot.key == key {
                return Some(slot.index);
            }
            s = (s + 1) & mask;
        }
    }

    /// Loads the home slot of `key` and returns its key: a hint that brings
    /// the slot into the cache ahead of [`WordTable::find_or_insert`]. Such
    /// loads are independent, so the processor overlaps their misses.
    #[inline]
    fn touch(&self, key: u64) -> u64 {
        self.slots[(hash_word(key) >> self.shift) as usize].key
    }

    fn grow(&mut self) {
        let old = std::mem::take(&mut self.slots);
        *self = WordTable::with_capacity(old.len());
        for slot in old.into_iter().filter(|s| s.index != EMPTY) {
            self.find_or_insert(slot.key, slot.index);
        }
    }
}

/// The index of a [`MarkingStore`].
#[derive(Debug, Clone)]
enum Index {
    /// One word per marking.
    Word(WordTable),
    /// Several words per marking: indices into the store, compared there.
    Words(HashTable<u32>),
    /// Dropped ([`MarkingStore::drop_index`]).
    None,
}

impl Index {
    fn for_words(words: usize, n: usize) -> Index {
        if words == 1 {
            Index::Word(WordTable::with_capacity(n))
        } else {
            Index::Words(HashTable::with_capacity(n))
        }
    }
}

/// A set of markings with stable dense indices, in insertion order.
#[derive(Debug, Clone)]
pub(crate) struct MarkingStore {
    layout: Layout,
    data: Vec<u64>,
    table: Index,
    len: usize,
}

impl MarkingStore {
    pub(crate) fn new(layout: Layout) -> MarkingStore {
        MarkingStore {
            table: Index::for_words(layout.words, 0),
            layout,
            data: Vec::new(),
            len: 0,
        }
    }

    pub(crate) fn layout(&self) -> &Layout {
        &self.layout
    }

    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// The packed key of marking `i`.
    #[inline]
    pub(crate) fn key(&self, i: usize) -> &[u64] {
        let w = self.layout.words;
        &self.data[i * w..(i + 1) * w]
    }

    /// Decodes marking `i` into `m`.
    pub(crate) fn decode(&self, i: usize, m: &mut [u32]) {
        self.layout.decode(self.key(i), m);
    }

    /// Token count of place `p` in marking `i`.
    #[inline]
    pub(crate) fn tokens(&self, i: usize, p: usize) -> u32 {
        self.layout.get(self.key(i), p)
    }

    /// Inserts a packed key; returns its index and whether it is new.
    ///
    /// # Panics
    ///
    /// After [`MarkingStore::drop_index`] (a bug).
    #[inline]
    pub(crate) fn insert(&mut self, key: &[u64]) -> (u32, bool) {
        let w = self.layout.words;
        let n = self.len;
        let (i, new) = match &mut self.table {
            Index::Word(t) => t.find_or_insert(key[0], n as u32),
            Index::Words(table) => {
                let hash = hash_words(key);
                let data = &self.data;
                let found = table.find(hash, |&i| {
                    let i = i as usize;
                    same_key(&data[i * w..(i + 1) * w], key)
                });
                if let Some(&i) = found {
                    (i, false)
                } else {
                    table.insert_unique(hash, n as u32, |&i| {
                        let i = i as usize;
                        hash_words(&data[i * w..(i + 1) * w])
                    });
                    (n as u32, true)
                }
            }
            Index::None => unreachable!("insert into a store whose index was dropped"),
        };
        if new {
            self.data.extend_from_slice(key);
            self.len += 1;
        }
        (i, new)
    }

    /// Brings the table slots of `keys` (consecutive keys of `words` words)
    /// into the cache before they are inserted: a batch of independent loads
    /// whose misses overlap, where inserting one key after the other waits for
    /// each miss in turn (it branches on the loaded slot). Only the one-word
    /// table benefits; wider markings are left alone.
    pub(crate) fn touch(&self, keys: &[u64]) {
        if let Index::Word(t) = &self.table {
            if self.layout.words == 1 && t.capacity() * std::mem::size_of::<Slot>() > TOUCH_ABOVE {
                let acc = keys.iter().fold(0u64, |acc, &k| acc ^ t.touch(k));
                std::hint::black_box(acc);
            }
        }
    }

    /// The index of a packed key, if stored (read-only: safe to call from
    /// several threads at once).
    ///
    /// # Panics
    ///
    /// After [`MarkingStore::drop_index`] (a bug).
    #[inline]
    pub(crate) fn find(&self, key: &[u64]) -> Option<u32> {
        let w = self.layout.words;
        match &self.table {
            Index::Word(t) => t.find(key[0]),
            Index::Words(table) => table
                .find(hash_words(key), |&i| {
                    let i = i as usize;
                    same_key(&self.data[i * w..(i + 1) * w], key)
                })
                .copied(),
            Index::None => unreachable!("lookup in a store whose index was dropped"),
        }
    }

    /// Re-encodes every marking with a new layout (same places).
    /// The layout to widen to when a firing needs the widths `needed`:
    /// every field that must grow gets one bit of headroom beyond its need
    /// (twice the range, see the module docs), unless the headroom costs a
    /// word per marking that the counts do not need; then every field is
    /// just wide enough for the largest count stored and for the firing
    /// (Kanban 8: sixteen 4-bit fields, one word, where headroom would take
    /// two). Tight fields may need more relayouts later; a word per marking
    /// is worth it. No field is made narrower than `floor` (the widths that
    /// earlier firings asked for: markings that are followed but not stored
    /// — forced hops — are not among the counts, and fitting them out of
    /// their width would make the relayouts take turns forever).
    ///
    /// `pending` gives the largest counts of markings about to be stored
    /// (the successors of the round being expanded): fitting to the stored
    /// ones alone could take from a field the width a pending marking
    /// needs, and the next attempt would widen it again and shrink another
    /// (a livelock met on Kanban 8). It is called only when fitting.
    pub(crate) fn fitted_layout(
        &self,
        needed: &[u8],
        floor: &[u8],
        pending: impl FnOnce() -> Vec<u32>,
    ) -> Layout {
        let old = &self.layout;
        let roomy: Vec<u8> = needed
            .iter()
            .zip(&old.width)
            .map(|(&n, &w)| if n > w { (n + 1).min(32) } else { w })
            .collect();
        let roomy = Layout::new(roomy);
        if roomy.words() <= old.words() {
            return roomy;
        }
        let mut largest = pending();
        let mut m = vec![0u32; old.width.len()];
        for i in 0..self.len {
            self.decode(i, &mut m);
            for (l, &c) in largest.iter_mut().zip(&m) {
                *l = (*l).max(c);
            }
        }
        let tight: Vec<u8> = needed
            .iter()
            .zip(&old.width)
            .zip(&largest)
            .zip(floor)
            .map(|(((&n, &w), &l), &f)| bits_for(l).max(if n > w { n } else { 0 }).max(f))
            .collect();
        let tight = Layout::new(tight);
        if tight.words() < roomy.words() {
            tight
        } else {
            roomy
        }
    }

    pub(crate) fn relayout(&mut self, layout: Layout) {
        let old = std::mem::replace(&mut self.layout, layout);
        let np = old.width.len();
        let mut m = vec![0u32; np];
        let w = self.layout.words;
        let mut data = Vec::with_capacity(self.len * w);
        let mut key = vec![0u64; w];
        for i in 0..self.len {
            old.decode(&self.data[i * old.words..(i + 1) * old.words], &mut m);
            self.layout.encode(&m, &mut key);
            data.extend_from_slice(&key);
        }
        self.data = data;
        self.rebuild_index();
    }

    fn rebuild_index(&mut self) {
        let w = self.layout.words;
        self.table = Index::for_words(w, self.len);
        match &mut self.table {
            Index::Word(t) => {
                for (i, &k) in self.data.iter().enumerate() {
                    t.find_or_insert(k, i as u32);
                }
            }
            Index::Words(table) => {
                let data = &self.data;
                let rehash = |&i: &u32| hash_words(&data[i as usize * w..(i as usize + 1) * w]);
                for i in 0..self.len as u32 {
                    table.insert_unique(rehash(&i), i, rehash);
                }
            }
            Index::None => {}
        }
    }

    /// Approximate heap bytes used.
    pub(crate) fn heap_bytes(&self) -> usize {
        self.data.capacity() * 8
            + match &self.table {
                Index::Word(t) => t.capacity() * std::mem::size_of::<Slot>(),
                Index::Words(t) => t.capacity() * 5,
                Index::None => 0,
            }
    }

    /// Heap bytes of the index alone (freed by [`MarkingStore::drop_index`]).
    pub(crate) fn index_bytes(&self) -> usize {
        self.heap_bytes() - self.data.capacity() * 8
    }

    /// Frees the hash table (lookups are no longer possible).
    pub(crate) fn drop_index(&mut self) {
        self.table = Index::None;
        self.data.shrink_to_fit();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widening_keeps_headroom_unless_it_costs_a_word() {
        // Fifteen 4-bit fields and one 3-bit one: 63 bits, one word.
        let first = [8u32, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 7];
        let mut store = MarkingStore::new(Layout::for_marking(&first, 1));
        assert_eq!(store.layout().words(), 1);
        let mut key = vec![0; 1];
        store.layout().encode(&first, &mut key);
        store.insert(&key);
        // A count of 8 in the last field needs 4 bits, and 5 with headroom
        // would make 65: the fields are fitted instead.
        let mut needed = store.layout().widths().to_vec();
        needed[15] = 4;
        let fitted = store.fitted_layout(&needed, &[0; 16], || vec![0; 16]);
        assert_eq!(fitted.words(), 1);
        assert_eq!(fitted.widths(), &[4; 16]);
        store.relayout(fitted);
        let mut m = [0; 16];
        store.decode(0, &mut m);
        assert_eq!(m, first);
        // Room to spare: one bit of headroom, as before.
        let small = MarkingStore::new(Layout::for_marking(&[1, 1], 1));
        assert_eq!(
            small.fitted_layout(&[2, 1], &[0, 0], || unreachable!()).widths(),
            &[3, 1]
        );
        // A pending count keeps its width: 15 in field 0 needs 4 bits even
        // though no stored marking has more than 8 there.
        let mut pending = vec![0; 16];
        pending[0] = 15;
        assert_eq!(store.fitted_layout(&needed, &[0; 16], || pending).widths()[0], 4);
        // A floor keeps a field that a firing asked for before: fields of 30,
        // 30 and 4 bits holding 1s, the last to grow to 5 bits, are fitted
        // to 1, 1 and 5 bits — or to 1, 20 and 5 when a firing once asked
        // for 20 bits in the second.
        let mut wide = MarkingStore::new(Layout::new(vec![30, 30, 4]));
        let mut key = vec![0; 1];
        wide.layout().encode(&[1, 1, 1], &mut key);
        wide.insert(&key);
        let grow = [30, 30, 5];
        assert_eq!(
            wide.fitted_layout(&grow, &[0; 3], || vec![0; 3]).widths(),
            &[1, 1, 5]
        );
        assert_eq!(
            wide.fitted_layout(&grow, &[0, 20, 0], || vec![0; 3]).widths(),
            &[1, 20, 5]
        );
    }

    #[test]
    fn pack_unpack_and_widen() {
        let layout = Layout::for_marking(&[3, 0, 70_000, 1], 1);
        assert_eq!(layout.widths(), &[2, 1, 17, 1]);
        let mut store = MarkingStore::new(layout);
        let mut key = vec![0; store.layout().words()];
        store.layout().encode(&[3, 0, 70_000, 1], &mut key);
        assert_eq!(store.insert(&key), (0, true));
        assert_eq!(store.insert(&key), (0, false));
        store.layout().encode(&[1, 1, 5, 0], &mut key);
        assert_eq!(store.insert(&key), (1, true));
        let mut wide = store.layout().widths().to_vec();
        wide[1] = 32;
        store.relayout(Layout::new(wide));
        let mut m = [0; 4];
        store.decode(0, &mut m);
        assert_eq!(m, [3, 0, 70_000, 1]);
        let mut key = vec![0; store.layout().words()];
        store.layout().encode(&[1, 1, 5, 0], &mut key);
        assert_eq!(store.insert(&key), (1, false));
        store.layout().add(&mut key, 1, 1_000_000);
        store.layout().add(&mut key, 0, -1);
        store.layout().decode(&key, &mut m);
        assert_eq!(m, [0, 1_000_001, 5, 0]);
    }

    #[test]
    fn word_table_grows_and_keeps_indices() {
        let mut t = WordTable::with_capacity(0);
        // Keys 0 and u64::MAX included: no key value is reserved.
        let key_of = |k: u64| {
            if k == 7 {
                u64::MAX
            } else {
                k.wrapping_mul(0x9E37_79B9_7F4A_7C15)
            }
        };
        for k in 0..100_000u64 {
            let key = key_of(k);
            assert_eq!(t.find_or_insert(key, k as u32), (k as u32, true));
        }
        assert!(t.len * 4 <= t.capacity() * 3);
        for k in (0..100_000u64).rev() {
            let key = key_of(k);
            assert_eq!(t.find_or_insert(key, 0), (k as u32, false));
            assert_eq!(t.find(key), Some(k as u32));
        }
    }

    #[test]
    fn many_places_span_words() {
        let m: Vec<u32> = (0..100).map(|i| i * 7).collect();
        let layout = Layout::for_marking(&m, 1);
        assert!(layout.words() > 1);
        let mut key = vec![0; layout.words()];
        layout.encode(&m, &mut key);
        let mut back = vec![0; 100];
        layout.decode(&key, &mut back);
        assert_eq!(back, m);
    }

    proptest::proptest! {
        /// The word-by-word decoding reads what the place-by-place one
        /// reads, for any widths (1 to 32 bits, fields packed over several
        /// words, words left partly or wholly empty) and counts.
        #[test]
        fn decoding_word_by_word_reads_every_field(
            fields in proptest::collection::vec((1u8..=32, proptest::prelude::any::<u32>(), 0u8..3), 0..80),
        ) {
            let width: Vec<u8> = fields.iter().map(|f| f.0).collect();
            // A third of the counts zero, so that whole words are.
            let m: Vec<u32> = fields
                .iter()
                .map(|&(b, v, z)| if z == 0 { 0 } else { (u64::from(v) & mask(b)) as u32 })
                .collect();
            let layout = Layout::new(width);
            let mut key = vec![0; layout.words()];
            layout.encode(&m, &mut key);
            let mut back = vec![u32::MAX; m.len()];
            layout.decode(&key, &mut back);
            proptest::prop_assert_eq!(&back, &m);
            let each: Vec<u32> = (0..m.len()).map(|p| layout.get(&key, p)).collect();
            proptest::prop_assert_eq!(&back, &each);
        }
    }
}
