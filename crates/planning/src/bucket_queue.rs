//! The priority queue of the wavefront: buckets as wide as the shortest
//! edge.
//!
//! R. Dial, *Algorithm 360: shortest-path forest with topological
//! ordering*, CACM 12 (1969), generalised to real weights as in
//! U. Meyer, P. Sanders, *Δ-stepping*, J. Algorithms 49 (2003): with
//! buckets `[kΔ, (k + 1)Δ)` and `Δ` no larger than the lightest edge, a cell
//! in the lowest non-empty bucket has its final value — its predecessor on
//! a shortest path is at least `Δ` cheaper, so in an earlier bucket, already
//! processed — and cells of one bucket can be processed in any order. Only
//! the `⌈w_max / Δ⌉ + 2` buckets that can hold entries at once are kept, in
//! a ring. Push and pop are `O(1)`; moving past empty buckets costs
//! `O(N_max / Δ)` over a whole run.
//!
//! Rounding can in principle put an entry one bucket early; the navigation
//! function then corrects the values it settled too soon (it re-opens a
//! cell whose value drops), so its result never depends on this.

/// A ring of buckets of cell indices (module docs).
#[derive(Debug, Clone, Default)]
pub(crate) struct BucketQueue {
    buckets: Vec<Vec<u32>>,
    /// Number of the bucket being emptied (not taken modulo the ring).
    current: u64,
    inv_width: f64,
    len: usize,
}

impl BucketQueue {
    /// Empties the queue for keys from 0 up, buckets `width` wide, and room
    /// for keys up to `span_widths` widths above the current bucket.
    pub(crate) fn reset(&mut self, width: f64, span_widths: f64) {
        let n = (span_widths.ceil() as usize).saturating_add(2);
        self.buckets.truncate(n);
        for b in &mut self.buckets {
            b.clear();
        }
        self.buckets.resize_with(n, Vec::new);
        self.current = 0;
        self.inv_width = 1.0 / width;
        self.len = 0;
    }

    /// Adds an item with a finite key `≥ 0` (clamped into the buckets the
    /// ring can hold: the current one up to the last).
    #[inline]
    pub(crate) fn push(&mut self, key: f64, item: u32) {
        let n = self.buckets.len() as u64;
        let b = ((key * self.inv_width) as u64).clamp(self.current, self.current + n - 1);
        self.buckets[(b % n) as usize].push(item);
        self.len += 1;
    }

    /// Number of the bucket being emptied: every entry of a lower bucket
    /// has been popped, and no later push goes below it.
    #[inline]
    pub(crate) fn current(&self) -> u64 {
        self.current
    }

    /// Removes an item of the lowest non-empty bucket.
    #[inline]
    pub(crate) fn pop(&mut self) -> Option<u32> {
        if self.len == 0 {
            return None;
        }
        let n = self.buckets.len() as u64;
        loop {
            if let Some(item) = self.buckets[(self.current % n) as usize].pop() {
                self.len -= 1;
                return Some(item);
            }
            self.current += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn items_come_out_by_bucket() {
        let mut q = BucketQueue::default();
        q.reset(0.5, 4.0);
        q.push(1.2, 1); // bucket 2
        q.push(0.1, 0); // bucket 0
        q.push(2.9, 3); // bucket 5
        q.push(1.4, 2); // bucket 2
        assert_eq!(q.pop(), Some(0));
        let mut two = [q.pop().unwrap(), q.pop().unwrap()];
        two.sort();
        assert_eq!(two, [1, 2]);
        // Keys below the current bucket go into it; the ring wraps.
        q.push(0.0, 7);
        assert_eq!(q.pop(), Some(7));
        q.push(4.6, 4); // bucket 9, beyond the ring (2 to 7): clamped to 7
        assert_eq!(q.pop(), Some(3));
        assert_eq!(q.pop(), Some(4));
        assert_eq!(q.pop(), None);
        q.reset(1.0, 1.0);
        assert_eq!(q.pop(), None);
    }
}
