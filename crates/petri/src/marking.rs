//! Compact storage of markings during state-space generation.
//!
//! Each place gets a bit field just wide enough for the largest token count
//! seen so far; fields are packed greedily into 64-bit words and never straddle
//! a word. Most nets fit a marking in one word (Kanban with N = 5: 16 places ×
//! 3 bits). When a count outgrows its field, the field is widened (doubling its
//! range) and every stored marking is re-encoded — indices do not change.
//! Markings live in one flat `Vec<u64>`; a `hashbrown::HashTable<u32>` of
//! indices into it finds duplicates, so a stored marking costs `8 × words`
//! bytes plus about 5 bytes of table.

use hashbrown::HashTable;

/// Bit layout of a packed marking.
#[derive(Debug, Clone)]
pub(crate) struct Layout {
    width: Vec<u8>,
    word: Vec<u32>,
    shift: Vec<u8>,
    words: usize,
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
        Layout {
            width,
            word,
            shift,
            words,
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

    pub(crate) fn encode(&self, m: &[u32], key: &mut [u64]) {
        key.iter_mut().for_each(|w| *w = 0);
        for (p, &v) in m.iter().enumerate() {
            debug_assert!(u64::from(v) <= mask(self.width[p]));
            key[self.word[p] as usize] |= u64::from(v) << self.shift[p];
        }
    }

    pub(crate) fn decode(&self, key: &[u64], m: &mut [u32]) {
        for (p, slot) in m.iter_mut().enumerate() {
            *slot = self.get(key, p);
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

#[inline]
fn hash_words(key: &[u64]) -> u64 {
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

/// A set of markings with stable dense indices, in insertion order.
#[derive(Debug, Clone)]
pub(crate) struct MarkingStore {
    layout: Layout,
    data: Vec<u64>,
    table: HashTable<u32>,
    len: usize,
}

impl MarkingStore {
    pub(crate) fn new(layout: Layout) -> MarkingStore {
        MarkingStore {
            layout,
            data: Vec::new(),
            table: HashTable::new(),
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
    #[inline]
    pub(crate) fn insert(&mut self, key: &[u64]) -> (u32, bool) {
        let w = self.layout.words;
        let n = self.len;
        let hash = hash_words(key);
        let data = &self.data;
        let found = self.table.find(hash, |&i| {
            let i = i as usize;
            &data[i * w..(i + 1) * w] == key
        });
        if let Some(&i) = found {
            return (i, false);
        }
        self.data.extend_from_slice(key);
        let data = &self.data;
        self.table.insert_unique(hash, n as u32, |&i| {
            let i = i as usize;
            hash_words(&data[i * w..(i + 1) * w])
        });
        self.len += 1;
        (n as u32, true)
    }

    /// Re-encodes every marking with a new layout (same places).
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
        let mut table = HashTable::with_capacity(self.len);
        let data = &self.data;
        let rehash = |&i: &u32| hash_words(&data[i as usize * w..(i as usize + 1) * w]);
        for i in 0..self.len as u32 {
            table.insert_unique(rehash(&i), i, rehash);
        }
        self.table = table;
    }

    /// Approximate heap bytes used.
    pub(crate) fn heap_bytes(&self) -> usize {
        self.data.capacity() * 8 + self.table.capacity() * 5
    }

    /// Frees the hash table (lookups are no longer possible).
    pub(crate) fn drop_index(&mut self) {
        self.table = HashTable::new();
        self.data.shrink_to_fit();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
